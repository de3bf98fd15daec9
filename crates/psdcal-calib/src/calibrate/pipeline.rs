//! [`calibrate`](fn@super::calibrate) as a list of named steps: the start,
//! the refinement (global search, gain starts, prior), the post-fit jobs
//! shared with the helper thread, the checks on the uncertainty, and the
//! warnings and diagnostics of the result (conventions in [`super`]).

use psdcal_model::{Diagnostic, DiagnosticCode, ParameterCovariance, ValidRegion};
use std::sync::Arc;

use crate::calibrate::finish::{check_data_in_domain, check_data_in_region, settle_block};
use crate::calibrate::gain_starts::refine_from_gain_starts;
use crate::calibrate::helper::Helper;
use crate::calibrate::model_choice::{choose_model, model_dependence, with_choice_spread};
use crate::calibrate::options::{seeded_base, CalibrateOptions, Uncertainty};
use crate::calibrate::result::CalibrationResult;
use crate::data::CalibrationData;
use crate::diagnose::diagnostics::{diagnose_structure, diagnose_uncertainty};
use crate::diagnose::fit_statistics::{fit_statistics, FitStatistics};
use crate::diagnose::residual_structure::DiagnosticReport;
use crate::problem::calibration_problem::FitState;
use crate::problem::prior::Prior;
use crate::refine::global::{refine_global, GlobalOptions, GlobalReport};
use crate::refine::linearization::AtSolution;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::robust_scale::{absolute, residual_noise, RESCALE_TOLERANCE};
use crate::refine::solve::refine;
use crate::select::influence::jackknife_raised;
use crate::start::initialize::{initialize, Initialization};
use crate::start::misplaced::misplaced_led;
use crate::uncertainty::bootstrap::{bootstrap_covariance, BootstrapReport};
use crate::uncertainty::covariance::{
    analytic_method, covariance_at, Covariance, CovarianceMethod,
};
use crate::uncertainty::linearity::{check_linearity_at, LinearityCheck, UncertaintyVerdict};
use crate::uncertainty::profile::profile_at_three_sigma;
use crate::warning::FitWarning;
use crate::CalibError;

/// Largest relative standard deviation of a freed `f` accepted as a
/// calibration: beyond it the images do not determine the focal length.
pub const MAX_RELATIVE_STD_F: f64 = 0.2;

/// Calibrates a sensor from `data`.
pub fn calibrate(
    data: &CalibrationData,
    options: &CalibrateOptions,
) -> Result<CalibrationResult, CalibError> {
    check_data_in_domain(data, options)?;
    let (mut result, chosen) =
        calibrate_as_given(data, options).map_err(|e| blame_misplaced_led(data, e))?;
    check_data_in_region(&result, data)?;
    // The block is carried into the covariance of the parameters chosen.
    settle_block(&mut result, data, &chosen)?;
    Ok(result)
}

/// A failure that a misplaced LED explains is reported as such
/// ([`crate::misplaced`]): the fit's own message would blame the poses.
fn blame_misplaced_led(data: &CalibrationData, error: CalibError) -> CalibError {
    let fit_failed = matches!(
        error,
        CalibError::Degenerate { .. }
            | CalibError::NotConverged { .. }
            | CalibError::Numerical { .. }
            | CalibError::NonPositiveFocalSquared { .. }
    );
    match fit_failed.then(|| misplaced_led(data)).flatten() {
        Some(m) => CalibError::MisplacedLed {
            led: m.led,
            score: m.score,
            next_score: m.next_score,
            images: m.images,
            cause: error.to_string(),
        },
        None => error,
    }
}

/// The calibration and the options it ended with (the freed parameters
/// the data chose).
fn calibrate_as_given(
    data: &CalibrationData,
    options: &CalibrateOptions,
) -> Result<(CalibrationResult, CalibrateOptions), CalibError> {
    // The post-fit work's second thread starts now ([`crate::calibrate::helper`]).
    let mut helper = Helper::spawn();
    let init = initialize(data, &options.init)?;
    let start = FitState {
        model: init.model.clone(),
        poses: init.poses.clone(),
    };
    let at_start = robust_at(data, options, &options.refine, &start)?;
    let (refined, global, gain_start) = refine_from_start(data, &at_start, &init)?;
    let (refined, at_solution) = rescale_robust(data, options, at_start, refined)?;
    let options = &at_solution;
    check_converged(&refined)?;
    let (refined, global, chosen_options, model_choice, neighbours) =
        choose_model(data, options, &init, refined, global)?;
    let options = &chosen_options;
    let (refined, refine_options) = match &options.prior {
        None => (refined, options.refine.clone()),
        Some(prior) => refine_with_prior(data, refined, options, prior)?,
    };
    let refine_options = &refine_options;
    let free = refine_options.free_names();
    let fitted_gains = refined.model.gains();
    let after_fit = post_fit(&mut helper, data, &refined, options, refine_options)?;
    check_focal_length(&after_fit.covariance, &refined)?;
    let (covariance, bootstrap) = final_covariance(
        data,
        &refined,
        refine_options,
        options,
        after_fit.covariance,
    )?;
    let covariance = with_choice_spread(covariance, &neighbours)?;
    let linearity = profiled_linearity(
        data,
        &refined,
        refine_options,
        &free,
        &covariance,
        after_fit.linearity,
    );
    let statistics = after_fit.statistics;
    let warnings = result_warnings(&covariance, &init, &statistics, global.as_ref());
    let mut diagnosed = after_fit.diagnosed;
    diagnose_uncertainty(&mut diagnosed, &covariance, global.as_ref());
    let mut diagnostics = result_diagnostics(diagnosed.diagnostics, &linearity, &statistics);
    diagnostics.extend(model_dependence(&neighbours, &covariance));
    let result = CalibrationResult {
        gains: fitted_gains,
        gain_start,
        model: refined.model,
        valid_region: after_fit.valid_region,
        poses: refined.poses,
        free,
        cost_kind: options.refine.cost,
        noise: options.refine.noise,
        robust: options.refine.robust,
        cost: refined.cost,
        init: init.report,
        refine: refined.report,
        global,
        covariance,
        linearity,
        bootstrap,
        statistics,
        warnings,
        diagnostics,
        block: None,
        model_choice,
    };
    Ok((result, options.clone()))
}

/// `options` with the robust loss (given in units of the residuals' noise)
/// made absolute at the noise of `state` ([`crate::refine::robust_scale`]).
fn robust_at(
    data: &CalibrationData,
    options: &CalibrateOptions,
    refine_options: &RefineOptions,
    state: &FitState,
) -> Result<CalibrateOptions, CalibError> {
    let Some(relative) = options.refine.robust else {
        return Ok(options.clone());
    };
    let sigma = residual_noise(data, state, refine_options)?;
    Ok(CalibrateOptions {
        refine: absolute(&options.refine, relative, sigma),
        ..options.clone()
    })
}

/// The fit refined again when the noise at the solution differs from the
/// start's by more than [`RESCALE_TOLERANCE`] (the loss's scale follows it).
fn rescale_robust(
    data: &CalibrationData,
    options: &CalibrateOptions,
    at_start: CalibrateOptions,
    refined: Refined,
) -> Result<(Refined, CalibrateOptions), CalibError> {
    let (Some(_), Some(used)) = (options.refine.robust, at_start.refine.robust) else {
        return Ok((refined, at_start));
    };
    let state = FitState {
        model: refined.model.clone(),
        poses: refined.poses.clone(),
    };
    let at_solution = robust_at(data, options, &at_start.refine, &state)?;
    let sigma_ratio = at_solution
        .refine
        .robust
        .map_or(0.0, |l| l.scale() / used.scale());
    if (sigma_ratio - 1.0).abs() <= RESCALE_TOLERANCE {
        return Ok((refined, at_start));
    }
    let again = refine(
        data,
        refined.model.clone(),
        &refined.poses,
        &at_solution.refine,
    )?;
    Ok((again, at_solution))
}

/// The refinement from the initialisation: with the gains freed, from the
/// competing gain starts ([`crate::calibrate::gain_starts`]); otherwise with
/// the global search over `l1` when it is freed. Returns the fit, the global
/// search's report and the winning gain start's name.
fn refine_from_start(
    data: &CalibrationData,
    options: &CalibrateOptions,
    init: &Initialization,
) -> Result<(Refined, Option<GlobalReport>, Option<String>), CalibError> {
    // The global search's cold starts use the same start options.
    let global_options = GlobalOptions {
        init: options.init,
        ..options.global.clone()
    };
    let global_options = &global_options;
    let start = seeded_base(options, &init.model)?;
    if options.refine.fit_gains {
        let (r, g, name) = refine_from_gain_starts(data, init, &start, options, global_options)?;
        Ok((r, g, Some(name)))
    } else {
        let (r, g) = refine_global(data, &start, &init.poses, &options.refine, global_options)?;
        Ok((r, g, None))
    }
}

/// What the post-fit jobs return.
struct AfterFit {
    /// The analytic covariance.
    covariance: Covariance,
    /// The linearity check at ±3σ of that covariance.
    linearity: LinearityCheck,
    /// Where the fitted model's correction is one-to-one.
    valid_region: ValidRegion,
    /// The fit statistics.
    statistics: FitStatistics,
    /// The residual-structure diagnostics.
    diagnosed: DiagnosticReport,
}

/// What the finished fit is asked: four independent jobs
/// ([`crate::calibrate::helper`]). The covariance and the linearity check
/// (from the refinement's last linearisation), the valid region and the fit
/// statistics are posted for the second thread, on a copy of the data and
/// the solution; this thread runs the residual-structure tests, the
/// largest, then takes back what the other has not started, last first.
fn post_fit(
    helper: &mut Helper,
    data: &CalibrationData,
    refined: &Refined,
    options: &CalibrateOptions,
    refine_options: &RefineOptions,
) -> Result<AfterFit, CalibError> {
    let shared = Arc::new((data.clone(), refined.clone(), refine_options.clone()));
    let after_fit = helper.run({
        let shared = shared.clone();
        move || -> Result<_, CalibError> {
            let (data, refined, refine_options) = &*shared;
            let at = AtSolution::new(data, refined, refine_options)?;
            let method = analytic_method(refined, refine_options);
            Ok((
                covariance_at(&at, data, refined, refine_options, method)?,
                check_linearity_at(&at, data, refine_options)?,
            ))
        }
    });
    let valid_region = helper.run({
        let shared = shared.clone();
        move || ValidRegion::of_model(&shared.1.model, &shared.0.geometry)
    });
    let (cost, robust) = (options.refine.cost, options.refine.robust);
    let statistics = helper.run(move || {
        let (data, refined, _) = &*shared;
        fit_statistics(data, &refined.model, &refined.poses, cost, robust)
    });
    let diagnosed = diagnose_structure(data, refined, &options.refine, &options.diagnostics);
    let statistics = statistics.wait();
    let valid_region = valid_region.wait();
    let after_fit = after_fit.wait();
    let (covariance, linearity) = after_fit?;
    Ok(AfterFit {
        covariance,
        linearity,
        valid_region,
        statistics,
        diagnosed,
    })
}

/// A fit whose focal length has a standard deviation above
/// [`MAX_RELATIVE_STD_F`] of its value is an error.
fn check_focal_length(covariance: &Covariance, refined: &Refined) -> Result<(), CalibError> {
    if let Some(sd) = covariance.std("f") {
        let f = refined.model.get("f").unwrap_or(f64::NAN);
        if sd > MAX_RELATIVE_STD_F * f {
            return Err(CalibError::Degenerate {
                reason: format!(
                    "the focal length is not determined by these images (f = {f:.4} ± {sd:.4} mm): \
                     the template poses are (nearly) parallel to the sensor or too few; tilt the \
                     template 10°–40° in several directions"
                ),
            });
        }
    }
    Ok(())
}

/// The reported covariance: the analytic one, or the bootstrap's when asked
/// (with its report).
fn final_covariance(
    data: &CalibrationData,
    refined: &Refined,
    refine_options: &RefineOptions,
    options: &CalibrateOptions,
    analytic: Covariance,
) -> Result<(Covariance, Option<BootstrapReport>), CalibError> {
    match options.uncertainty {
        Uncertainty::Linear => Ok((analytic, None)),
        Uncertainty::Jackknife if refined.weights.is_none() && refine_options.robust.is_none() => {
            let at = AtSolution::new(data, refined, refine_options)?;
            // Without every image's leave-one-out fit determined, the
            // linear covariance, named as such.
            let Ok(raised) = jackknife_raised(&at, analytic.parameters.matrix()) else {
                return Ok((analytic, None));
            };
            let parameters =
                ParameterCovariance::new(analytic.names().to_vec(), raised).map_err(|e| {
                    CalibError::Numerical {
                        stage: "covariance",
                        reason: e.to_string(),
                    }
                })?;
            Ok((
                Covariance {
                    parameters,
                    method: CovarianceMethod::Jackknife,
                    ..analytic
                },
                None,
            ))
        }
        Uncertainty::Jackknife => Ok((analytic, None)),
        Uncertainty::Bootstrap(boot) => {
            let (c, report) =
                bootstrap_covariance(data, refined, refine_options, &analytic, &boot)?;
            Ok((c, Some(report)))
        }
    }
}

/// The linearity check, with the profile at ±3σ where the walk finds the
/// cost not quadratic: it decides whether the reported σ understates the
/// uncertainty.
fn profiled_linearity(
    data: &CalibrationData,
    refined: &Refined,
    refine_options: &RefineOptions,
    free: &[String],
    covariance: &Covariance,
    linearity: LinearityCheck,
) -> LinearityCheck {
    if linearity.verdict.is_reliable() {
        linearity
    } else {
        let std: Vec<f64> = free
            .iter()
            .map(|n| covariance.std(n).unwrap_or(f64::NAN))
            .collect();
        linearity.with_profile(profile_at_three_sigma(data, refined, refine_options, &std))
    }
}

/// The result's warnings: the covariance's, the skipped preliminary
/// correction, the robust loss's outliers, competing minima over `l1`.
fn result_warnings(
    covariance: &Covariance,
    init: &Initialization,
    statistics: &FitStatistics,
    global: Option<&GlobalReport>,
) -> Vec<FitWarning> {
    let mut warnings = covariance.warnings.clone();
    if let Some(note) = &init.report.preliminary_note {
        warnings.push(note.clone());
    }
    if !statistics.outliers.is_empty() {
        warnings.push(FitWarning::Outliers {
            count: statistics.outliers.len(),
        });
    }
    if let Some(g) = global {
        // Only when the data hardly tell the next minimum from the kept one
        // (the diagnostic's rule, `local_minimum_suspected`).
        if g.competing(covariance.sigma2) {
            warnings.push(FitWarning::LocalMinima {
                count: g.minima.len(),
                lowest: g.minima[0].cost,
                next: g.minima[1].cost,
            });
        }
    }
    warnings
}

/// The result's diagnostics: `diagnostics` (residual structure, local
/// minima, conditioning), then an unreliable linearity verdict and points
/// outside the valid region.
fn result_diagnostics(
    mut diagnostics: Vec<Diagnostic>,
    linearity: &LinearityCheck,
    statistics: &FitStatistics,
) -> Vec<Diagnostic> {
    if let UncertaintyVerdict::Unreliable { reason } = &linearity.verdict {
        if !diagnostics
            .iter()
            .any(|d| d.code == DiagnosticCode::UncertaintyUnreliable)
        {
            diagnostics.push(Diagnostic::warning(
                DiagnosticCode::UncertaintyUnreliable,
                reason.clone(),
            ));
        }
    }
    if statistics.unprojectable > 0 {
        diagnostics.push(Diagnostic::warning(
            DiagnosticCode::OutsideValidRegion,
            format!(
                "{} point(s) fall outside the fitted model's valid region (they cannot be reprojected)",
                statistics.unprojectable
            ),
        ));
    }
    diagnostics
}

/// A refinement that ran out of iterations is an error.
fn check_converged(refined: &Refined) -> Result<(), CalibError> {
    if refined.report.termination.converged() {
        return Ok(());
    }
    Err(CalibError::NotConverged {
        reason: format!(
            "{} iterations without meeting a stopping criterion (cost {:.6e}); \
             try --focal-guess, fewer freed parameters, or more images",
            refined.report.iterations, refined.cost
        ),
    })
}

/// The last refinement with `prior`'s parameters freed (module
/// documentation), from `held` (the fit with them held at `options.base`'s
/// values); returns it and its options.
fn refine_with_prior(
    data: &CalibrationData,
    held: Refined,
    options: &CalibrateOptions,
    prior: &ParameterCovariance,
) -> Result<(Refined, RefineOptions), CalibError> {
    let held_names = options.refine.free_names();
    if let Some(name) = prior.names().iter().find(|n| held_names.contains(n)) {
        return Err(CalibError::InvalidInput {
            reason: format!("'{name}' is both freed and given a prior; expected one of the two"),
        });
    }
    let unknowns = held_names.len() + 6 * held.poses.len();
    let observations = 2 * data.point_count();
    if observations <= unknowns || held.cost.is_nan() || held.cost <= 0.0 {
        return Err(CalibError::Degenerate {
            reason: "refining with a prior needs the data's noise: more coordinates than \
                     parameters and a non-zero residual"
                .into(),
        });
    }
    let scale = (held.cost / (observations - unknowns) as f64).sqrt();
    let mean = prior
        .names()
        .iter()
        .map(|n| {
            options.base.get(n).ok_or_else(|| CalibError::InvalidInput {
                reason: format!("the prior's parameter '{n}' is not in the model"),
            })
        })
        .collect::<Result<Vec<f64>, _>>()?;
    let mut joint = options.refine.clone();
    joint
        .free_stage_parameters
        .extend(prior.names().iter().cloned());
    joint.prior = Some(Prior::new(prior, &mean, scale)?);
    let mut refined = refine(data, held.model, &held.poses, &joint)?;
    check_converged(&refined)?;
    // The report counts both refinements.
    refined.report.iterations += held.report.iterations;
    refined.report.accepted += held.report.accepted;
    Ok((refined, joint))
}
