//! Measured points (or electrode amplitudes) → ideal points with a
//! calibration: the table `psdcal correct` writes, streamed row by row
//! (docs/model.md §2). Amplitude rows are first turned into measured points
//! (docs/model.md §1) with the calibration's sensor size and gains. Like
//! `aoa`, every row gets a `status`: `ok`, `off_active_area` (corrected
//! anyway: the model was not fitted there), or a code with empty values
//! (`non_finite_input`, `no_light`, `outside_valid_region` past a fold of the
//! correction, …).

use std::path::Path;

use psdcal_locate::{angle_of_arrival, Caution, Measurement};
use psdcal_model::sensor::is_on_active_area;

use crate::error::Result;
use crate::point_rows::{answer_points, PointsAnswer};
use crate::sensor::LoadedSensor;
use crate::table::num;

/// A corrected points file.
#[derive(Debug, Clone)]
pub struct Corrected {
    /// The calibration used.
    pub sensor: LoadedSensor,
    /// What was written: rows, added columns, status counts.
    pub answer: PointsAnswer,
}

/// The columns added: the measured point for amplitude input, the ideal
/// point, the status.
fn added_columns(amplitudes: bool) -> Vec<String> {
    let mut names: Vec<&str> = Vec::new();
    if amplitudes {
        names.extend(["x_mm", "y_mm"]);
    }
    names.extend(["x_ideal_mm", "y_ideal_mm", "status"]);
    names.into_iter().map(String::from).collect()
}

/// Corrects the points of `points` with the calibration at `calibration`,
/// streaming the answer to `out` (standard output when `None`).
pub fn correct(calibration: &Path, points: &Path, out: Option<&Path>) -> Result<Corrected> {
    let loaded = LoadedSensor::read(calibration)?;
    let sensor = &loaded.sensor;
    let answer = answer_points(points, out, added_columns, |m| {
        let measured = sensor.measured_point(m)?.point;
        // Past a fold of the correction there is no unique ideal point.
        sensor.check_valid_region(&measured)?;
        // A PSD map (docs/model.md §8.3) corrects the point first.
        let corrected = sensor.map_corrected(&measured)?.point;
        let aoa = angle_of_arrival(&sensor.model, &corrected)?;
        let mut values = Vec::with_capacity(4);
        if matches!(m, Measurement::Amplitudes(_)) {
            values.extend([num(measured.x), num(measured.y)]);
        }
        values.extend([num(aoa.ideal.x), num(aoa.ideal.y)]);
        let cautions = if is_on_active_area(&sensor.geometry, &measured) {
            Vec::new()
        } else {
            vec![Caution::OffActiveArea {
                x_mm: measured.x,
                y_mm: measured.y,
            }]
        };
        Ok((values, cautions))
    })?;
    Ok(Corrected {
        sensor: loaded,
        answer,
    })
}
