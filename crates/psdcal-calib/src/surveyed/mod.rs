//! Calibration from surveyed, non-coplanar points (docs/model.md §8.4): IR
//! emitters fixed in a room (or LEDs of a 3-D template) whose positions
//! `P_j = (X, Y, Z)` were surveyed in one frame, seen in one or several
//! images (sensor orientations).
//!
//! *Start*: per image, the normalised DLT of the 3 × 4 projection matrix
//! `λ (x, y, 1)ᵀ = P (X, Y, Z, 1)ᵀ` (points and image points translated to
//! their centroid and scaled to mean distances √3 and √2; the null vector of
//! the 2n × 12 system by SVD, which needs n ≥ 6 points off any one plane),
//! split by RQ decomposition `P = K [R | t]`, `K` upper triangular with a
//! positive diagonal, `det R = +1`; one focal length `f = (K₁₁ + K₂₂)/2`,
//! `(cx, cy) = (K₁₃, K₂₃)/K₃₃` ([`crate::projection_dlt`]). The intrinsics
//! start at the median over the images, the distortion at zero.
//!
//! *Refinement*: the image-plane error of the model's chain (the same
//! [`Model`](psdcal_model::Model) and the same solver as [`mod@crate::refine`]),
//! `r_ij = project(θ, pose_i, P_j) − m_ij` (mm on the sensor), over the
//! freed model parameters and one `sensor_from_template` pose per image
//! ([`crate::surveyed_problem`]).
//!
//! *Uncertainty with survey noise*: the points are known to σ_s per
//! coordinate (independent), the measured points to σ_m. With `J` the
//! Jacobian of the residuals with respect to `x = (θ, poses)`, `J_P` that
//! with respect to the surveyed points and `S = JᵀJ`, the linearised
//! estimate moves by `δx = −S⁻¹ Jᵀ (J_P δP − ε)`, so
//!
//! ```text
//! Cov(x) = σ_m² S⁻¹ + σ_s² S⁻¹ G Gᵀ S⁻¹,   G = Jᵀ J_P
//! ```
//!
//! (an emitter seen in several images moves all its residuals together:
//! `G`'s columns sum over them). σ_m² is estimated from the cost without
//! the survey's share: `E[cost] = σ_m² (2n − p) + σ_s² T`,
//! `T = tr(J_Pᵀ J_P) − tr(Gᵀ S⁻¹ G)`, so
//! `σ_m² = max(0, cost − σ_s² T) / (2n − p)`.
//!
//! *Diagnostics*: the planar fit's, on this problem
//! ([`crate::surveyed_checks`]).
//!
//! The folder: [`projection_dlt`] (the start's DLT), [`problem`] (the
//! image-plane cost), [`checks`] (the diagnostics and linearity check); the
//! steps themselves are in a private `fit` module, re-exported here.

pub mod checks;
mod fit;
mod input;
pub mod problem;
pub mod projection_dlt;

pub use fit::{
    calibrate_surveyed, finish_refined, preliminary_k1, refine_surveyed, survey_covariance,
    RefinedSurveyed, SurveyedCalibration, MIN_DEPTH_RATIO,
};
pub use input::{SurveyedData, SurveyedOptions};
pub use problem::{dense_jacobians, DenseJacobians, SurveyedProblem, SurveyedState};
pub use projection_dlt::{decompose_projection, dlt_projection, flatness, MIN_SURVEYED_POINTS};
