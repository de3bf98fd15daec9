//! Angles of arrival of a points file with their uncertainty (docs/model.md §5):
//! the table `psdcal aoa` writes.

use std::path::Path;

use psdcal_io::{PointInput, Points};
use psdcal_locate::{sigmas_and_correlation, LocateOptions, Measurement};

use crate::error::Result;
use crate::sensor::LoadedSensor;
use crate::table::{deg, empty, num, refuse_existing_columns, StatusCount, Table};

/// The angles of arrival of a points file.
#[derive(Debug, Clone)]
pub struct AoaTable {
    /// The calibration used.
    pub sensor: LoadedSensor,
    /// The points read.
    pub points: Points,
    /// The columns added, in order.
    pub added: Vec<String>,
    /// Input columns then the added ones.
    pub table: Table,
    /// Status counts and per-row warnings.
    pub count: StatusCount,
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

/// The measurement of a points row.
pub fn measurement(input: &PointInput) -> Measurement {
    match input {
        PointInput::Position(p) => Measurement::Point(*p),
        PointInput::Amplitudes(a) => Measurement::Amplitudes(*a),
    }
}

/// Angles of arrival of every row of `points` with the calibration at
/// `calibration`; `point_sigma_mm` adds the point noise's part.
pub fn aoa_table(
    calibration: &Path,
    points: &Path,
    point_sigma_mm: Option<f64>,
) -> Result<AoaTable> {
    let loaded = LoadedSensor::read(calibration)?;
    let points = Points::read(points)?;
    let with_point = point_sigma_mm.is_some();
    let added = added_columns(points.amplitudes, with_point);
    refuse_existing_columns(&points, &added)?;
    let options = LocateOptions {
        point_sigma_mm: point_sigma_mm.unwrap_or(0.0),
        ..LocateOptions::default()
    };
    let mut count = StatusCount::default();
    let mut values = Vec::with_capacity(points.rows.len());
    for row in &points.rows {
        let at = format!("{}:{}", points.source, row.line_no);
        let mut out = Vec::with_capacity(added.len());
        match loaded.sensor.aoa(&measurement(&row.input), &options) {
            Ok(est) => {
                let a = &est.aoa;
                if points.amplitudes {
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
                let cautions = est.cautions();
                out.push(count.answered_with(&at, &cautions));
            }
            Err(e) => {
                out.extend(empty(added.len() - 1));
                out.push(e.status().to_string());
                count.failed(&e, &at);
            }
        }
        values.push(out);
    }
    let table = Table::extending(&points, &added, values);
    Ok(AoaTable {
        sensor: loaded,
        points,
        added,
        table,
        count,
    })
}
