//! Measured points (or electrode amplitudes) → ideal points with a
//! calibration: the table `psdcal correct` writes, streamed row by row
//! (docs/model.md §2). Amplitude rows are first turned into measured points
//! (docs/model.md §1) with the calibration's sensor size and gains. Like
//! `aoa`, every row gets a `status`: `ok`, `off_active_area` (corrected
//! anyway: the model was not fitted there), or a code with empty values
//! (`non_finite_input`, `no_light`, `outside_valid_region` past a fold of the
//! correction, …).

use std::path::Path;

use nalgebra::Vector2;
use psdcal_locate::{angle_of_arrival, CalibratedSensor, Caution, LocateError, Measurement};
use psdcal_model::psd::is_on_active_area;

use crate::answer::loaded_sensor::LoadedSensor;
use crate::answer::point_rows::{answer_points, PointsAnswer};
use crate::base::error::Result;
use crate::base::table::num;

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

/// One corrected point.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CorrectedPoint {
    /// The measured point (from the amplitudes when given), mm.
    pub measured: Vector2<f64>,
    /// The ideal point, mm.
    pub ideal: Vector2<f64>,
    /// Off the active area (corrected anyway).
    pub cautions: Vec<Caution>,
}

/// Corrects one measurement with `sensor`: measured point, the valid
/// region's check, the PSD map, the distortion correction.
pub(crate) fn correct_point(
    sensor: &CalibratedSensor,
    m: &Measurement,
) -> Result<CorrectedPoint, LocateError> {
    let measured = sensor.measured_point(m)?.point;
    // Past a fold of the correction there is no unique ideal point.
    sensor.check_valid_region(&measured)?;
    // A PSD map (docs/model.md §8.3) corrects the point first.
    let corrected = sensor.map_corrected(&measured)?.point;
    let aoa = angle_of_arrival(&psdcal_model::Model::standard(&sensor.model), &corrected)?;
    let cautions = if is_on_active_area(&sensor.geometry, &measured) {
        Vec::new()
    } else {
        vec![Caution::OffActiveArea {
            x_mm: measured.x,
            y_mm: measured.y,
        }]
    };
    Ok(CorrectedPoint {
        measured,
        ideal: aoa.ideal,
        cautions,
    })
}

/// Corrects the points of `points` with the calibration at `calibration`,
/// streaming the answer to `out` (standard output when `None`); the
/// calibration is read within `limits`.
pub fn correct(
    calibration: &Path,
    points: &Path,
    out: Option<&Path>,
    limits: psdcal_io::ReadLimits,
) -> Result<Corrected> {
    let loaded = LoadedSensor::read_with(calibration, limits)?;
    let sensor = &loaded.sensor;
    let answer = answer_points(points, out, added_columns, |m| {
        let c = correct_point(sensor, m)?;
        let mut values = Vec::with_capacity(4);
        if matches!(m, Measurement::Amplitudes(_)) {
            values.extend([num(c.measured.x), num(c.measured.y)]);
        }
        values.extend([num(c.ideal.x), num(c.ideal.y)]);
        Ok((values, c.cautions))
    })?;
    Ok(Corrected {
        sensor: loaded,
        answer,
    })
}
