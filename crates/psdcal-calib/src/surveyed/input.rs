//! The input of a calibration from surveyed points: the points' surveyed
//! positions `P_j = (X, Y, Z)` (mm, one frame), the images that see them
//! ([`SurveyedData`]), and what is freed, the survey's σ per coordinate and
//! the iteration budget ([`SurveyedOptions`]).

use nalgebra::Vector3;
use psdcal_model::{Param, PsdGeometry, SensorModel};

use crate::data::ImageObservations;

/// The input: surveyed points and the images that see them.
#[derive(Debug, Clone, PartialEq)]
pub struct SurveyedData {
    /// Surveyed positions `(X, Y, Z)`, mm (one frame: the room's).
    pub points: Vec<Vector3<f64>>,
    /// Names of the points (for messages), as in the files.
    pub names: Vec<String>,
    /// Per image (sensor orientation), the measured points (`led` indexes
    /// `points`).
    pub images: Vec<ImageObservations>,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
}

/// Options of [`calibrate_surveyed`](crate::calibrate_surveyed).
#[derive(Debug, Clone, PartialEq)]
pub struct SurveyedOptions {
    /// The freed standard parameters (`f, cx, cy, k1, k2` by default, as
    /// [`crate::RefineOptions`]).
    pub free: Vec<Param>,
    /// The survey's standard deviation per coordinate, mm (0: exact points).
    pub survey_sigma_mm: f64,
    /// The model's values of the parameters that are not freed.
    pub base: SensorModel,
    /// Iteration budget of the refinement.
    pub max_iterations: usize,
}

impl Default for SurveyedOptions {
    fn default() -> Self {
        Self {
            free: vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2],
            survey_sigma_mm: 0.0,
            base: SensorModel::pinhole(8.0, 0.0, 0.0),
            max_iterations: 500,
        }
    }
}
