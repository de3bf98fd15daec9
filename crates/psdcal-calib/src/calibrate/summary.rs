//! The serialisable summary of a calibration ([`CalibrationSummary`]): every
//! parameter with its σ and unit, the gains apart, how the start was found,
//! the solver's report, the fit statistics, the named covariance and
//! correlations, σ² and the degrees of freedom, the global search, warnings
//! and diagnostics — what `--json` prints and the report reads.

use psdcal_model::stages::gains::GAIN_NAMES;
use psdcal_model::Diagnostic;
use serde::Serialize;

use crate::calibrate::result::CalibrationResult;
use crate::diagnose::fit_statistics::FitStatistics;
use crate::problem::weighting::NoiseModel;
use crate::refine::global::GlobalReport;
use crate::select::choose::ModelChoiceReport;
use crate::start::initialize::InitRoute;
use psdcal_model::CostKind;
use psdcal_solver::solver::{RobustLoss, Termination};

/// One parameter of a summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterSummary {
    /// Its name (`f`, `cx`, …).
    pub name: String,
    /// Its value.
    pub value: f64,
    /// Its standard deviation (`None` when fixed).
    pub std: Option<f64>,
    /// Its unit.
    pub unit: String,
    /// Whether it was estimated.
    pub estimated: bool,
}

/// A serialisable summary of a calibration, for `--json` output and reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrationSummary {
    /// Every sensor parameter.
    pub parameters: Vec<ParameterSummary>,
    /// The relative channel gains `g_x2, g_y1, g_y2`, when estimated.
    pub gains: Vec<ParameterSummary>,
    /// Which start won the gain estimation.
    pub gain_start: Option<String>,
    /// The cost minimised.
    pub cost: CostKind,
    /// The noise model that weighted it.
    pub noise: NoiseModel,
    /// The robust loss, if any.
    pub robust: Option<RobustLoss>,
    /// How the start was found (`closed_form`, `focal_search`, `focal_guess`).
    pub start: String,
    /// The closed form's focal length, when it had one (mm).
    pub closed_form_f: Option<f64>,
    /// Why the closed form was not used as the start, when it was not
    /// (information about the start, not a problem with the result).
    pub closed_form_rejection: Option<String>,
    /// Why the refinement stopped.
    pub termination: Termination,
    /// Iterations of the final refinement.
    pub iterations: usize,
    /// Cost after each accepted step.
    pub cost_history: Vec<f64>,
    /// Fit statistics.
    pub statistics: FitStatistics,
    /// Names of the estimated parameters, in the order of `covariance` and `correlation`.
    pub covariance_parameters: Vec<String>,
    /// Their covariance.
    pub covariance: Vec<Vec<f64>>,
    /// Their correlations.
    pub correlation: Vec<Vec<f64>>,
    /// Residual variance σ² per coordinate (cost units).
    pub sigma2: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// The global search over `l1`, when run.
    pub global: Option<GlobalReport>,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Diagnostics with stable codes (calibration.json's `diagnostics`).
    pub diagnostics: Vec<Diagnostic>,
    /// How σ was computed: `linear`, `jackknife`, `sandwich` or
    /// `bootstrap` ([`crate::CovarianceMethod`]).
    pub uncertainty: &'static str,
    /// The candidates, their held-out angle errors and the choice, when
    /// `calibrate` chose the freed parameters (docs/model.md §4.8).
    pub model_choice: Option<ModelChoiceReport>,
}

impl CalibrationResult {
    /// The serialisable summary.
    pub fn summary(&self) -> CalibrationSummary {
        let rows = |m: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> {
            (0..m.nrows())
                .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
                .collect()
        };
        CalibrationSummary {
            parameters: self.parameter_summaries(false),
            gains: self.parameter_summaries(true),
            gain_start: self.gain_start.clone(),
            cost: self.cost_kind,
            noise: self.noise,
            robust: self.robust,
            start: match self.init.route {
                InitRoute::ClosedForm => "closed_form",
                InitRoute::FocalSearch => "focal_search",
                InitRoute::FocalGuess => "focal_guess",
            }
            .into(),
            closed_form_f: self
                .init
                .closed_form
                .as_ref()
                .and_then(|c| c.focal_length().ok()),
            closed_form_rejection: self.init.closed_form_rejection.clone(),
            termination: self.refine.termination,
            iterations: self.refine.iterations,
            cost_history: self.refine.cost_history.clone(),
            statistics: self.statistics.clone(),
            covariance_parameters: self.covariance.names().to_vec(),
            covariance: self.covariance.rows(),
            correlation: rows(&self.covariance.correlation()),
            sigma2: self.covariance.sigma2,
            dof: self.covariance.dof,
            global: self.global.clone(),
            warnings: crate::warning::warning_texts(&self.warnings),
            diagnostics: self.diagnostics.clone(),
            uncertainty: self.covariance.method.name(),
            model_choice: self.model_choice.clone(),
        }
    }

    /// Every parameter of the model but the gains (`gains == false`), or the
    /// gains alone, with σ when estimated.
    fn parameter_summaries(&self, gains: bool) -> Vec<ParameterSummary> {
        self.model
            .parameters()
            .iter()
            .zip(self.model.values())
            .filter(|(p, _)| GAIN_NAMES.contains(&p.name.as_str()) == gains)
            .map(|(p, value)| ParameterSummary {
                name: p.name.clone(),
                value: *value,
                std: self.covariance.std(&p.name),
                unit: p.unit.clone(),
                estimated: self.free.contains(&p.name),
            })
            .collect()
    }
}
