//! The model choice's step of the pipeline (docs/model.md §4.8): the
//! forward selection by held-out error when `calibrate` is to choose
//! ([`crate::select::choose`]), and the default covariance widened by the
//! choice's own spread ([`crate::select::choice_spread`]).

use psdcal_model::{Diagnostic, DiagnosticCode, ParameterCovariance};

use crate::calibrate::options::CalibrateOptions;
use crate::data::CalibrationData;
use crate::refine::global::{GlobalOptions, GlobalReport};
use crate::refine::refined::Refined;
use crate::select::choice_spread::{choice_covariance, Neighbour, PLAUSIBLE};
use crate::select::choose::{choose, ModelChoice, ModelChoiceReport};
use crate::start::initialize::{InitRoute, Initialization};
use crate::uncertainty::covariance::{Covariance, CovarianceMethod};
use crate::CalibError;

/// With [`ModelChoice::HeldOut`] (and an unweighted, non-robust fit
/// without gains or prior), the freed parameters grown by held-out error
/// from the base fit ([`crate::select::choose`]); otherwise the base fit.
/// Returns the fit, its global search's report, the options with the
/// chosen freed parameters and the choice's report.
pub(crate) type ChosenFit = (
    Refined,
    Option<GlobalReport>,
    CalibrateOptions,
    Option<ModelChoiceReport>,
    Vec<Neighbour>,
);

pub(crate) fn choose_model(
    data: &CalibrationData,
    options: &CalibrateOptions,
    init: &Initialization,
    refined: Refined,
    global: Option<GlobalReport>,
) -> Result<ChosenFit, CalibError> {
    let r = &options.refine;
    let eligible = options.choice == ModelChoice::HeldOut
        && !r.fit_gains
        && r.robust.is_none()
        && options.prior.is_none()
        && refined.weights.is_none()
        && data.images.len() >= 3;
    if !eligible {
        return Ok((refined, global, options.clone(), None, Vec::new()));
    }
    let global_options = GlobalOptions {
        init: options.init,
        ..options.global.clone()
    };
    let cold_aspect = init.report.route != InitRoute::ClosedForm;
    let base = (refined.clone(), global.clone());
    let chosen = match choose(data, refined, global, r, cold_aspect, &global_options) {
        Ok(chosen) => chosen,
        // Held-out errors need every image's leave-one-out fit determined:
        // without it the given parameters are fitted, and the report says why.
        Err(CalibError::Degenerate { reason }) => {
            let report = ModelChoiceReport::skipped(r.free_names(), reason);
            return Ok((base.0, base.1, options.clone(), Some(report), Vec::new()));
        }
        Err(e) => return Err(e),
    };
    let mut chosen_options = options.clone();
    chosen_options.refine = chosen.options;
    Ok((
        chosen.refined,
        chosen.global,
        chosen_options,
        Some(chosen.report),
        chosen.neighbours,
    ))
}

/// The default covariance widened by the models the data could as well have
/// chosen ([`crate::select::choice_spread`]); any other method as it is.
pub(crate) fn with_choice_spread(
    covariance: Covariance,
    neighbours: &[Neighbour],
) -> Result<Covariance, CalibError> {
    if covariance.method != CovarianceMethod::Jackknife || neighbours.is_empty() {
        return Ok(covariance);
    }
    let names = covariance.names().to_vec();
    let widened = covariance.parameters.matrix() + choice_covariance(neighbours, &names);
    let parameters =
        ParameterCovariance::new(names, widened).map_err(|e| CalibError::Numerical {
            stage: "covariance",
            reason: e.to_string(),
        })?;
    Ok(Covariance {
        parameters,
        ..covariance
    })
}

/// An information diagnostic when `f`, `cx` or `cy` moves by more than 3σ
/// with a group the choice took narrowly (a plausible neighbour,
/// `model_dependent`): a model without the group (another program's
/// default, a fit with `--fit`) disagrees beyond σ, by design.
pub(crate) fn model_dependence(
    neighbours: &[Neighbour],
    covariance: &Covariance,
) -> Option<Diagnostic> {
    let moves: Vec<String> = neighbours
        .iter()
        .filter(|n| n.probability >= PLAUSIBLE)
        .flat_map(|n| {
            n.delta.iter().filter_map(move |(name, d)| {
                let sigma = covariance.parameters.std(name)?;
                let key = ["f", "cx", "cy"].contains(&name.as_str());
                (key && d.abs() > 3.0 * sigma).then(|| {
                    format!(
                        "{name} by {:+.4} mm ({:.1}σ) with {}",
                        d,
                        d / sigma,
                        n.free.join(",")
                    )
                })
            })
        })
        .collect();
    (!moves.is_empty()).then(|| {
        Diagnostic::info(
            DiagnosticCode::ModelDependent,
            format!(
                "the estimate depends on the model chosen beyond its σ: {}; a model without \
                 these terms (another program's default, --fit without them) will disagree by \
                 as much",
                moves.join("; ")
            ),
        )
    })
}
