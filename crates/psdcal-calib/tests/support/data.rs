//! Plain points (psdcal-testkit's) as psdcal-calib's `CalibrationData`;
//! shared by `tests/support` and `tests/common`.

use nalgebra::Vector2;
use psdcal_calib::{CalibrationData, ImageObservations, Observation};
use psdcal_model::PsdGeometry;

/// `CalibrationData` of `points[image][led]` (images named 1, 2, …).
pub fn calibration_data(
    template: &[Vector2<f64>],
    lines: &[Vec<usize>],
    points: Vec<Vec<Vector2<f64>>>,
) -> CalibrationData {
    let images = points
        .into_iter()
        .enumerate()
        .map(|(i, image)| ImageObservations {
            id: format!("{}", i + 1),
            points: image
                .into_iter()
                .enumerate()
                .map(|(led, measured)| Observation { led, measured })
                .collect(),
        })
        .collect();
    CalibrationData {
        amplitudes: None,
        template: template.to_vec(),
        lines: lines.to_vec(),
        images,
        geometry: PsdGeometry::default(),
    }
}
