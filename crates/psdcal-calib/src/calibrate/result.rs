//! What a calibration returns ([`CalibrationResult`]): the model and its valid
//! region, the poses, the freed parameters in covariance order, the cost and
//! how it was weighted, the reports of the start, the refinement and the
//! global search, the covariance with its linearity check (and bootstrap),
//! the fit statistics, warnings and diagnostics.

use nalgebra::DMatrix;
use psdcal_model::{ChannelGains, CostKind, Diagnostic, Model, Pose, SensorModel, ValidRegion};
use psdcal_solver::solver::{RobustLoss, SolverReport as RefineReport};

use crate::diagnose::fit_statistics::FitStatistics;
use crate::problem::weighting::NoiseModel;
use crate::refine::global::GlobalReport;
use crate::refine::refined::Refined;
use crate::select::choose::ModelChoiceReport;
use crate::start::initialize::InitReport;
use crate::uncertainty::bootstrap::BootstrapReport;
use crate::uncertainty::covariance::Covariance;
use crate::uncertainty::linearity::LinearityCheck;
use crate::warning::FitWarning;

/// A finished calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationResult {
    /// The estimated model (every stage; the gains when they were freed).
    pub model: Model,
    /// Where the estimated model's correction is one-to-one (docs/model.md §8.2).
    pub valid_region: ValidRegion,
    /// The estimated relative channel gains, when they were freed.
    pub gains: Option<ChannelGains>,
    /// Which start won the gain estimation, when the gains were freed.
    pub gain_start: Option<String>,
    /// One `sensor_from_template` pose per image.
    pub poses: Vec<Pose>,
    /// Names of the freed parameters, in covariance order.
    pub free: Vec<String>,
    /// The cost minimised.
    pub cost_kind: CostKind,
    /// The noise model that weighted it.
    pub noise: NoiseModel,
    /// The robust loss, if any.
    pub robust: Option<RobustLoss>,
    /// Final cost (weighted under a noise model other than uniform).
    pub cost: f64,
    /// How the start was found.
    pub init: InitReport,
    /// The refinement's report.
    pub refine: RefineReport,
    /// The global search's report (when `l1` was freed).
    pub global: Option<GlobalReport>,
    /// Uncertainty of the estimate.
    pub covariance: Covariance,
    /// Whether the linear covariance holds at ±3σ ([`crate::linearity`]):
    /// the verdict behind the diagnostic `uncertainty_unreliable`.
    pub linearity: LinearityCheck,
    /// The bootstrap's report, when the covariance is a bootstrap's.
    pub bootstrap: Option<BootstrapReport>,
    /// Fit statistics.
    pub statistics: FitStatistics,
    /// Everything the user should know (identifiability, start, outliers).
    pub warnings: Vec<FitWarning>,
    /// A block of the model with a known covariance (a PSD map's
    /// coefficients), held fixed with its covariance carried or refined
    /// with it as the prior ([`CalibrateOptions::fixed_covariance`],
    /// [`CalibrateOptions::prior`]); `None` without one.
    ///
    /// [`CalibrateOptions::fixed_covariance`]: crate::CalibrateOptions::fixed_covariance
    /// [`CalibrateOptions::prior`]: crate::CalibrateOptions::prior
    pub block: Option<BlockCovariance>,
    /// What the fit noticed about itself, with stable codes
    /// ([`crate::diagnostics`]; calibration.json's `diagnostics`).
    pub diagnostics: Vec<Diagnostic>,
    /// How the freed parameters were chosen by held-out error, when they
    /// were ([`crate::select::choose`]); `None` for a fit of given
    /// parameters.
    pub model_choice: Option<ModelChoiceReport>,
}

impl CalibrationResult {
    /// The fit's solution as a [`Refined`] (model, poses, cost and the
    /// solver's report; the point weights are not kept), for the
    /// post-fit functions that take one (covariance, diagnostics, profile).
    pub fn refined(&self) -> Refined {
        Refined {
            model: self.model.clone(),
            poses: self.poses.clone(),
            cost: self.cost,
            weights: None,
            report: self.refine.clone(),
            linearization: None,
        }
    }
}

impl CalibrationResult {
    /// The standard parameters of the estimated model.
    pub fn sensor_model(&self) -> SensorModel {
        self.model.sensor_model()
    }
}

/// A block of the model with a known covariance after the calibration
/// (docs/model.md §8.3).
#[derive(Debug, Clone, PartialEq)]
pub struct BlockCovariance {
    /// The block's parameters and their values in the fitted model.
    pub parameters: Vec<(String, f64)>,
    /// Its own covariance when refined (`None` when held fixed: the known
    /// covariance stands).
    pub matrix: Option<DMatrix<f64>>,
    /// Its covariance with the estimated parameters: rows the block's
    /// parameters, columns the result's covariance names.
    pub cross: DMatrix<f64>,
}
