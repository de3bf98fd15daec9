//! # psdcal-calib
//!
//! Calibration of a PSD sensor from images of a planar LED template: the
//! paper's adapted Zhang method (docs/model.md §4) — preliminary distortion
//! correction, data normalisation, homographies by DLT, the constrained closed
//! form, and Levenberg–Marquardt refinement on the template-plane error (P29),
//! with the parameters' covariance.
#![warn(missing_docs)]

pub mod data;
mod error;
mod focal_profile;
pub mod homography;
pub mod initialize;
pub mod preliminary;
pub mod straightness;
pub mod zhang;

pub use data::{CalibrationData, ImageObservations, Observation};
pub use error::CalibError;
pub use homography::{fit_homography, Homography, HomographyFit, HomographyOptions};
pub use initialize::{initialize, InitOptions, InitReport, InitRoute, Initialization};
pub use preliminary::{estimate_preliminary, Preliminary, PreliminaryOptions, PreliminaryReport};
pub use zhang::{closed_form, pose_from_homography, ClosedFormSolution};
pub mod bootstrap;
pub mod calibration_problem;
pub mod carried;
pub mod covariance;
pub mod diagnostics;
pub mod electrical;
mod gain_starts;
pub mod global;
mod helper;
pub mod linearity;
mod linearization;
pub mod misplaced;
pub mod plan;
pub mod prior;
pub mod profile;
pub mod projection_dlt;
pub mod refine;
pub mod report;
pub mod residual_structure;
pub mod surveyed;
pub mod surveyed_checks;
pub mod surveyed_problem;
pub mod weighting;

pub use bootstrap::{bootstrap_covariance, BootstrapOptions, BootstrapReport};
pub use carried::{carry_fixed_covariance, CarriedCovariance};
pub use covariance::{covariance, Covariance, CovarianceMethod};
pub use diagnostics::{diagnose, DiagnosticOptions, DiagnosticReport};
pub use electrical::{equal_current_gains, GainEstimate};
pub use global::{refine_global, GlobalOptions, GlobalReport, LocalMinimum};
pub use linearity::{check_linearity, LinearityCheck, ParameterLinearity, UncertaintyVerdict};
pub use prior::Prior;
pub use psdcal_solver::{self as solver, normal_equations};
pub use psdcal_solver::{Problem, Solution, SolverOptions, SolverReport};
pub use refine::{
    refine, CalibrationProblem, CostKind, FitState, RefineOptions, RefineReport, Refined,
    RobustLoss, Termination,
};
pub use report::{fit_statistics, FitStatistics, ImageStats, PointError};
pub use weighting::{point_covariance, NoiseModel, PointWeights};
pub mod calibrate;
mod calibration_summary;
pub use calibrate::{
    calibrate, CalibrateOptions, CalibrationResult, CalibrationSummary, ParameterSummary,
    Uncertainty,
};
pub use surveyed::{calibrate_surveyed, SurveyedCalibration, SurveyedData, SurveyedOptions};
