//! The error type of psdcal-locate.
//!
//! Every variant names the numbers a user needs to see what went wrong, and
//! has a short machine-readable [`LocateError::status`] code: batch commands
//! write it in a `status` column for a row they cannot answer, instead of a
//! NaN or a silently wrong number.

use psdcal_model::{ModelError, RegionEnd};
use thiserror::Error;

/// Everything that can go wrong computing angles of arrival, positions and
/// error maps.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum LocateError {
    /// An input number is NaN or infinite.
    #[error("non-finite input: {what}")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// An answer came out NaN or infinite (a calibration whose numbers
    /// overflow there): the row gets no answer rather than a blank or
    /// infinite cell under the status `ok`.
    #[error("the answer is not finite: {what}")]
    NonFiniteAnswer {
        /// Which answer.
        what: &'static str,
    },
    /// An argument is outside its domain (a non-positive distance, a grid of
    /// fewer than two points, a negative σ, …).
    #[error("invalid {what}: {reason}")]
    InvalidInput {
        /// Which argument.
        what: &'static str,
        /// Why it is rejected, and what is expected.
        reason: String,
    },
    /// The sensor model or the electrode amplitudes are unusable.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The measured point lies where the distortion correction folds over or
    /// overflows: outside the model's valid region.
    #[error("measured point ({x:?}, {y:?}) mm is outside the model's valid region: {reason}")]
    OutsideValidRegion {
        /// Measured x, mm.
        x: f64,
        /// Measured y, mm.
        y: f64,
        /// What fails there.
        reason: &'static str,
    },
    /// The measured point lies outside the calibration's valid region
    /// (docs/model.md §8.2): past the first fold of the correction along its
    /// direction from the optical centre, outside a PSD map's scan, or
    /// beyond the checked zone far off the active area. Its status is
    /// `outside_valid_region`, as for [`LocateError::OutsideValidRegion`].
    #[error(
        "measured point ({x:?}, {y:?}) mm is outside the calibration's valid region: {}",
        match end {
            RegionEnd::DomainEdge => format!(
                "it is outside the PSD map's scan (its hull), where the map is not known; \
                 {distance_mm:.4} mm from the optical centre, the scan ending {limit_mm:.4} mm \
                 from it in this direction"
            ),
            RegionEnd::Fold => format!(
                "it is {distance_mm:.4} mm from the optical centre, and the distortion \
                 correction folds over {limit_mm:.4} mm from it in this direction: past there \
                 it has no unique answer"
            ),
            _ => format!(
                "it is {distance_mm:.4} mm from the optical centre, past the edge of the \
                 checked zone ({limit_mm:.4} mm in this direction), far off the active area"
            ),
        }
    )]
    BeyondValidRegion {
        /// Measured x, mm.
        x: f64,
        /// Measured y, mm.
        y: f64,
        /// Distance from the optical centre, mm.
        distance_mm: f64,
        /// How far the region reaches in that direction, mm.
        limit_mm: f64,
        /// Where the region ends there.
        end: RegionEnd,
    },
    /// The ray is parallel to the plane (it never meets it).
    #[error("the ray is parallel to the plane (|cos| between ray and normal = {cos:.3e})")]
    ParallelToPlane {
        /// |cosine| of the angle between the ray and the plane's normal.
        cos: f64,
    },
    /// The ray meets the plane behind the sensor.
    #[error(
        "the ray points away from the plane (its line meets it {behind:.6} mm behind the sensor)",
        behind = .distance_mm.abs()
    )]
    PointsAwayFromPlane {
        /// Signed distance along the unit ray to the plane, mm (≤ 0).
        distance_mm: f64,
    },
    /// Fewer than two rays to intersect.
    #[error("{found} ray(s) given; a position from rays needs at least 2 sensors")]
    TooFewRays {
        /// Rays given.
        found: usize,
    },
    /// The rays are (numerically) parallel: they do not fix a point.
    #[error(
        "the rays are parallel (largest angle between them {angle_deg:.3e}°): they do not fix a \
         position"
    )]
    ParallelRays {
        /// Largest angle between two of the rays, degrees.
        angle_deg: f64,
    },
    /// The least-squares intersection lies behind a sensor (the rays meet
    /// behind it, or diverge).
    #[error("the rays meet behind sensor '{sensor}' (depth {depth_mm:.6e} mm)")]
    BehindSensor {
        /// Sensor identifier.
        sensor: String,
        /// Depth of the point in that sensor's frame, mm.
        depth_mm: f64,
    },
    /// None of the sensors observing an emitter shares a field of view with
    /// another one.
    #[error(
        "sensors {sensors} share no field of view: their rays cannot meet in front of two of them"
    )]
    NoSharedView {
        /// The sensors, comma-separated.
        sensors: String,
    },
    /// A sensor identifier is not in the rig.
    #[error("sensor '{sensor}' is not in the rig")]
    UnknownSensor {
        /// The identifier.
        sensor: String,
    },
    /// The least-squares intersection did not converge.
    #[error("the ray intersection did not converge after {iterations} iterations")]
    NotConverged {
        /// Iterations spent.
        iterations: usize,
    },
    /// A covariance matrix is unusable (not square, not symmetric, negative
    /// variance, unknown parameter name).
    #[error("invalid covariance: {reason}")]
    InvalidCovariance {
        /// What is wrong.
        reason: String,
    },
}

impl LocateError {
    /// Short code for the `status` column of a row that cannot be answered.
    pub fn status(&self) -> &'static str {
        match self {
            LocateError::NonFinite { .. } => "non_finite_input",
            LocateError::NonFiniteAnswer { .. } => "non_finite_answer",
            LocateError::InvalidInput { .. } => "invalid_input",
            LocateError::Model(ModelError::NonPositiveTotal { .. }) => "no_light",
            LocateError::Model(_) => "model_error",
            LocateError::OutsideValidRegion { .. } | LocateError::BeyondValidRegion { .. } => {
                "outside_valid_region"
            }
            LocateError::ParallelToPlane { .. } => "parallel_to_plane",
            LocateError::PointsAwayFromPlane { .. } => "points_away_from_plane",
            LocateError::TooFewRays { .. } => "too_few_sensors",
            LocateError::ParallelRays { .. } => "parallel_rays",
            LocateError::BehindSensor { .. } => "behind_sensor",
            LocateError::NoSharedView { .. } => "no_shared_view",
            LocateError::UnknownSensor { .. } => "unknown_sensor",
            LocateError::NotConverged { .. } => "not_converged",
            LocateError::InvalidCovariance { .. } => "invalid_covariance",
        }
    }
}

/// Checks that `value` is finite.
pub(crate) fn finite(value: f64, what: &'static str) -> Result<f64, LocateError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(LocateError::NonFinite { what })
    }
}

/// `value > min`, false for NaN (reads better than `!(value > min)` in
/// rejections).
pub(crate) fn exceeds(value: f64, min: f64) -> bool {
    value > min
}
