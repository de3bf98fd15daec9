//! The error type of the sensor model.

use thiserror::Error;

/// Everything that can go wrong when evaluating the sensor model.
///
/// Every variant carries the numbers a user needs to locate the problem; none
/// of them is ever replaced by a NaN or a silently wrong point.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ModelError {
    /// The four electrode amplitudes sum to zero or less: no light reached the
    /// PSD, or a channel is broken (docs/model.md §1).
    #[error("electrode amplitudes sum to {total} (must be positive): no usable light spot")]
    NonPositiveTotal {
        /// `Vx1 + Vx2 + Vy1 + Vy2` after dividing out the gains.
        total: f64,
    },
    /// An input number is NaN or infinite.
    #[error("non-finite input: {what}")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A model parameter is outside its valid domain (e.g. `f <= 0`).
    #[error("invalid model parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name as in CONVENTIONS.md.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// Newton's method for the inverse distortion (ideal → measured) did not
    /// reach 1e-12 mm: the point lies outside the model's valid region.
    #[error(
        "inverse distortion did not converge for ideal point ({x:.6}, {y:.6}) mm after \
         {iterations} iterations (last step {last_step:.3e} mm): outside the model's valid region"
    )]
    DistortionNotConverged {
        /// Ideal point x, mm.
        x: f64,
        /// Ideal point y, mm.
        y: f64,
        /// Iterations spent.
        iterations: usize,
        /// Size of the last Newton step, mm.
        last_step: f64,
    },
    /// The distortion Jacobian is singular at a point: the correction folds
    /// over there, so the point is outside the model's valid region.
    #[error("distortion Jacobian is singular at ({x:.6}, {y:.6}) mm (determinant {det:.3e})")]
    SingularDistortion {
        /// Point x, mm.
        x: f64,
        /// Point y, mm.
        y: f64,
        /// Determinant of the 2×2 Jacobian.
        det: f64,
    },
    /// A template point lies on or behind the sensor plane (`Zc <= 0`).
    #[error("point is not in front of the sensor (Zc = {zc:.6} mm)")]
    BehindSensor {
        /// Depth in the sensor frame, mm.
        zc: f64,
    },
    /// The back-projected ray does not meet the template plane in front of the
    /// sensor (parallel to it, or pointing away).
    #[error("ray does not meet the template plane in front of the sensor (ray parameter {s:.3e})")]
    RayMissesPlane {
        /// Ray parameter of the intersection (≤ 0 or non-finite when missed).
        s: f64,
    },
    /// A stage parameter is outside its valid domain.
    #[error("invalid model parameter {name} = {value}: {reason}")]
    InvalidStageParameter {
        /// Parameter name.
        name: String,
        /// Its value.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// The stages do not form a valid model (a parameter named twice with
    /// different units, an unknown name, a wrong block length).
    #[error("invalid model: {reason}")]
    InvalidModel {
        /// What is wrong.
        reason: String,
    },
}
