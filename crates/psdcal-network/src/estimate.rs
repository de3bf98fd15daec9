//! What the calibration says of each sensor ([`SensorEstimate`]) and what
//! fixes the world ([`Gauge`]).

use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use psdcal_model::{Model, Pose};

/// What fixes the world frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gauge {
    /// The static frame's LEDs: origin, axes and scale.
    StaticFrame,
    /// The first sensor's frame, scaled by the wand.
    FirstSensor,
}

impl Gauge {
    /// One line for the output.
    pub fn describe(self, first: &str) -> String {
        match self {
            Gauge::StaticFrame => {
                "world frame: the static frame's LEDs (origin, axes and scale)".to_string()
            }
            Gauge::FirstSensor => format!(
                "world frame: sensor '{first}''s own frame (no static frame given), scaled by \
                 the wand's length"
            ),
        }
    }
}

/// One sensor's estimate.
#[derive(Debug, Clone)]
pub struct SensorEstimate {
    /// `sensor_from_world`.
    pub sensor_from_world: Pose,
    /// Its 6 × 6 covariance (`rx ry rz tx ty tz`; zero for the gauge
    /// sensor).
    pub pose_covariance: SMatrix<f64, 6, 6>,
    /// The optical centre in the world, mm.
    pub position_mm: Vector3<f64>,
    /// Its covariance, mm².
    pub position_covariance: Matrix3<f64>,
    /// The refined model.
    pub model: Model,
    /// The refined lens parameters' names (the prior's) and covariance.
    pub lens_names: Vec<String>,
    /// Their covariance.
    pub lens_covariance: DMatrix<f64>,
    /// Sightings used.
    pub points: usize,
    /// Σ‖r‖² of its sightings' image-plane errors, mm².
    pub residual_mm2: f64,
}

impl SensorEstimate {
    /// RMS image-plane error of its sightings, mm (per point, both axes).
    pub fn rms_image_mm(&self) -> f64 {
        (self.residual_mm2 / self.points.max(1) as f64).sqrt()
    }

    /// The position's σ per world axis, mm.
    pub fn position_sigma_mm(&self) -> Vector3<f64> {
        self.position_covariance
            .diagonal()
            .map(|v| v.max(0.0).sqrt())
    }

    /// The orientation's σ, degrees: the root of the rotation vector's
    /// variances summed.
    pub fn orientation_sigma_deg(&self) -> f64 {
        self.pose_covariance
            .fixed_view::<3, 3>(0, 0)
            .trace()
            .max(0.0)
            .sqrt()
            .to_degrees()
    }
}
