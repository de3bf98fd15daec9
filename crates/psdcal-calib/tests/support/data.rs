//! Plain points (psdcal-testkit's) as psdcal-calib's `CalibrationData`;
//! shared by `tests/support` and `tests/common`.

use nalgebra::Vector2;
use psdcal_calib::CalibrationData;
use psdcal_model::PsdGeometry;

/// `CalibrationData` of `points[image][led]` (images named 1, 2, …).
pub fn calibration_data(
    template: &[Vector2<f64>],
    lines: &[Vec<usize>],
    points: Vec<Vec<Vector2<f64>>>,
) -> CalibrationData {
    CalibrationData::from_points(template, lines, points, PsdGeometry::default())
}
