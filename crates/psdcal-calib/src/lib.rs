//! # psdcal-calib
//!
//! Calibration of a PSD sensor from images of a planar LED template: the
//! paper's adapted Zhang method (docs/model.md §4) — preliminary distortion
//! correction, data normalisation, homographies by DLT, the constrained closed
//! form, and Levenberg–Marquardt refinement on the template-plane error (P29),
//! with the parameters' covariance.
//!
//! The modules, one concept each, lower ones first (a module uses only those
//! above it in this list, and its own folder's lower files):
//!
//! - [`data`], [`CalibError`], [`electrical`]: the input, the errors, the
//!   electrical gain calibration;
//! - [`problem`]: the cost (P29), its noise weighting and prior;
//! - [`start`]: preliminary correction, homographies, closed form, focal search;
//! - [`mod@refine`]: Levenberg–Marquardt and the global search over `l1`;
//! - [`uncertainty`]: covariance, linearity check, profile, bootstrap;
//! - [`select`]: each image's influence, the parameter set the data choose;
//! - [`mod@diagnose`]: fit statistics, residual structure, diagnostics;
//! - [`surveyed`]: the calibration from surveyed 3-D points;
//! - [`mod@calibrate`]: the whole calibration, end to end;
//! - [`plan`]: pose planning, predicted before any data exist.
//!
//! The former flat module paths (`psdcal_calib::homography`,
//! `psdcal_calib::covariance`, …) are kept as re-exports of the moved modules.
#![warn(missing_docs)]

pub mod calibrate;
pub mod data;
pub mod diagnose;
pub mod electrical;
mod error;
pub mod plan;
pub mod problem;
pub mod refine;
pub mod select;
pub mod start;
pub mod surveyed;
pub mod uncertainty;
mod warning;

// The former flat module paths.
pub use diagnose::{diagnostics, fit_statistics, residual_structure};
pub use problem::{calibration_problem, prior, weighting};
pub use refine::global;
pub use start::{homography, initialize, misplaced, preliminary, straightness, zhang};
pub use surveyed::{checks as surveyed_checks, problem as surveyed_problem, projection_dlt};
pub use uncertainty::{bootstrap, carried, covariance, linearity, profile};

pub use calibrate::{
    calibrate, BlockCovariance, CalibrateOptions, CalibrationResult, CalibrationSummary,
    ParameterSummary, Uncertainty,
};
pub use data::{CalibrationData, DataPoint, ImageObservations, Observation};
pub use diagnose::diagnostics::{diagnose, DiagnosticOptions, DiagnosticReport};
pub use diagnose::fit_statistics::{fit_statistics, FitStatistics, ImageStats, PointError};
pub use electrical::{equal_current_gains, GainEstimate};
pub use error::CalibError;
pub use problem::prior::Prior;
pub use problem::weighting::{point_covariance, NoiseModel, PointWeights};
pub use psdcal_solver::{self as solver, normal_equations};
pub use psdcal_solver::{Problem, Solution, SolverOptions, SolverReport};
pub use refine::global::{refine_global, GlobalOptions, GlobalReport, LocalMinimum};
pub use refine::{
    refine, CalibrationProblem, CostKind, FitState, RefineOptions, RefineReport, Refined,
    RobustLoss, Termination,
};
pub use select::choose::{CandidateScore, ModelChoice, ModelChoiceReport, NeighbourScore};
pub use select::influence::{influence, ImageInfluence};
pub use start::homography::{fit_homography, Homography, HomographyFit, HomographyOptions};
pub use start::initialize::{initialize, InitOptions, InitReport, InitRoute, Initialization};
pub use start::preliminary::{
    estimate_preliminary, Preliminary, PreliminaryOptions, PreliminaryReport,
};
pub use start::zhang::{closed_form, pose_from_homography, ClosedFormSolution};
pub use surveyed::{calibrate_surveyed, SurveyedCalibration, SurveyedData, SurveyedOptions};
pub use uncertainty::bootstrap::{bootstrap_covariance, BootstrapOptions, BootstrapReport};
pub use uncertainty::carried::{carry_fixed_covariance, CarriedCovariance};
pub use uncertainty::covariance::{covariance, Covariance, CovarianceMethod};
pub use uncertainty::linearity::{
    check_linearity, LinearityCheck, ParameterLinearity, UncertaintyVerdict,
};
pub use warning::{warning_texts, FitWarning};
