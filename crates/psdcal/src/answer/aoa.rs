//! Angles of arrival of a points file with their uncertainty (docs/model.md §5):
//! the table `psdcal aoa` writes, streamed row by row.

use std::path::Path;

use psdcal_io::PointInput;
use psdcal_locate::{sigmas_and_correlation, LocateOptions, Measurement};

use crate::answer::loaded_sensor::LoadedSensor;
use crate::answer::point_rows::{answer_points, PointsAnswer};
use crate::base::error::Result;
use crate::base::table::{deg, num};

/// The angles of arrival of a points file, written as they are computed.
#[derive(Debug, Clone)]
pub struct AoaTable {
    /// The calibration used.
    pub sensor: LoadedSensor,
    /// What was written: rows, added columns, status counts.
    pub answer: PointsAnswer,
}

/// The columns added, in order.
fn added_columns(amplitudes: bool, point_sigma: bool) -> Vec<String> {
    let mut names: Vec<&str> = Vec::new();
    if amplitudes {
        names.extend(["x_mm", "y_mm"]);
    }
    names.extend([
        "x_ideal_mm",
        "y_ideal_mm",
        "alpha_x_deg",
        "alpha_y_deg",
        "ray_x",
        "ray_y",
        "ray_z",
        "sigma_alpha_x_deg",
        "sigma_alpha_y_deg",
        "rho_alpha_xy",
        "sigma_alpha_x_cal_deg",
        "sigma_alpha_y_cal_deg",
    ]);
    if point_sigma {
        names.extend(["sigma_alpha_x_point_deg", "sigma_alpha_y_point_deg"]);
    }
    names.push("status");
    names.into_iter().map(String::from).collect()
}

/// The measurement of a points row (`None` for a row without finite
/// numbers).
pub fn measurement(input: &PointInput) -> Option<Measurement> {
    match input {
        PointInput::Position(p) => Some(Measurement::Point(*p)),
        PointInput::Amplitudes(a) => Some(Measurement::Amplitudes(*a)),
        _ => None,
    }
}

/// Angles of arrival of every row of `points` with the calibration at
/// `calibration`, streamed to `out` (standard output when `None`);
/// `point_sigma_mm` adds the point noise's part; the calibration is read
/// within `limits`.
pub fn aoa_table(
    calibration: &Path,
    points: &Path,
    point_sigma_mm: Option<f64>,
    out: Option<&Path>,
    limits: psdcal_io::ReadLimits,
) -> Result<AoaTable> {
    let loaded = LoadedSensor::read_with(calibration, limits)?;
    let with_point = point_sigma_mm.is_some();
    let options = LocateOptions {
        point_sigma_mm: point_sigma_mm.unwrap_or(0.0),
        ..LocateOptions::default()
    };
    let sensor = &loaded.sensor;
    let answer = answer_points(
        points,
        out,
        |amps| added_columns(amps, with_point),
        |m| {
            let est = sensor.aoa(m, &options)?;
            let a = &est.aoa;
            let mut out = Vec::with_capacity(16);
            if matches!(m, Measurement::Amplitudes(_)) {
                out.extend([num(a.measured.x), num(a.measured.y)]);
            }
            let (sx, sy, rho) = sigmas_and_correlation(&est.alpha_covariance());
            let (cx, cy, _) = sigmas_and_correlation(&est.alpha_covariance_calibration());
            let d = a.direction.into_inner();
            out.extend([
                num(a.ideal.x),
                num(a.ideal.y),
                deg(a.alpha.x),
                deg(a.alpha.y),
                num(d.x),
                num(d.y),
                num(d.z),
                deg(sx),
                deg(sy),
                num(rho),
                deg(cx),
                deg(cy),
            ]);
            if with_point {
                let (px, py, _) = sigmas_and_correlation(&est.alpha_covariance_measurement());
                out.extend([deg(px), deg(py)]);
            }
            Ok((out, est.cautions()))
        },
    )?;
    Ok(AoaTable {
        sensor: loaded,
        answer,
    })
}
