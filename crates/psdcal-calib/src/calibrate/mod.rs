//! The whole calibration, end to end (docs/model.md §4): the robust start
//! ([`mod@crate::initialize`]: preliminary correction, normalised DLT, closed
//! form or focal search), Levenberg–Marquardt on the template-plane cost
//! (P29) with the global search over `l1` when it is freed
//! ([`crate::global`]), the covariance ([`mod@crate::covariance`]) and the fit
//! statistics ([`mod@crate::fit_statistics`]), then the diagnostics
//! ([`crate::diagnostics`]: misfit, gain imbalance, local minima,
//! unreliable uncertainty).
//!
//! With [`CalibrateOptions::prior`] (a PSD map refined with its scan's
//! information, docs/model.md §8.3), the fit above runs with the prior's
//! parameters held at their values in `base` (`μ`); then one more
//! refinement frees them, starting from that solution, with the prior
//! residuals `s L (m − μ)` ([`crate::prior`]), `s² = cost / dof` of the
//! fit with them held (the data's variance per coordinate in cost units).
//! The covariance, the linearity check and the bootstrap are then those of
//! the joint fit (data and prior); the residual-structure diagnostics keep
//! the prior's parameters held (at their refined values).
//!
//! Fixed parameters keep the values of [`CalibrateOptions::base`] (zero
//! distortion by default, or e.g. an `l1` known from a PSD scan). Freed
//! parameters start from the initialisation where it estimates them
//! (`f, cx, cy, k1, k2`) and from `base` otherwise.
//!
//! A refinement that runs out of iterations is an error, never a result;
//! so is a fit whose focal length has a standard deviation above
//! [`MAX_RELATIVE_STD_F`] of its value (nearly parallel template poses).
//!
//! The folder: the steps of [`calibrate`](fn@calibrate) (a private `pipeline`
//! module), the competing starts of a fit that frees the channel gains
//! (`gain_starts`), the second thread of the post-fit work (`helper`), and the
//! serialisable summary ([`CalibrationSummary`]).

mod finish;
mod gain_starts;
mod helper;
mod model_choice;
mod options;
mod pipeline;
mod result;
mod summary;

pub use options::{CalibrateOptions, Uncertainty};
pub use pipeline::{calibrate, MAX_RELATIVE_STD_F};
pub use result::{BlockCovariance, CalibrationResult};
pub use summary::{CalibrationSummary, ParameterSummary};
