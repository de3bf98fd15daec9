//! `psdcal aoa`: angles of arrival of measured points (or electrode
//! amplitudes) with their uncertainty (MODEL.md §5, psdcal-locate).

use psdcal_io::{read_calibration, PointInput, Points};
use psdcal_locate::{sigmas_and_correlation, LocateOptions, Measurement};

use crate::cli::Output;
use crate::cli_locate::AoaConfig;
use crate::locate_output::{
    calibrated_sensor, deg, empty, num, points_table, refuse_existing_columns,
    warn_without_covariance, write_output, StatusCount,
};

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

/// Runs `aoa`.
pub fn run(config: &AoaConfig, output: Output) -> anyhow::Result<()> {
    let calibration = read_calibration(&config.calibration)?;
    let sensor = calibrated_sensor(&calibration, &config.calibration)?;
    let points = Points::read(&config.points)?;
    let with_point = config.point_sigma_mm.is_some();
    let added = added_columns(points.amplitudes, with_point);
    refuse_existing_columns(&points, &added)?;
    warn_without_covariance(&sensor, &config.calibration);
    let options = LocateOptions {
        point_sigma_mm: config.point_sigma_mm.unwrap_or(0.0),
        ..LocateOptions::default()
    };
    let mut count = StatusCount::default();
    let mut values = Vec::with_capacity(points.rows.len());
    for row in &points.rows {
        let at = format!("{}:{}", points.source, row.line_no);
        let m = measurement(&row.input);
        let mut out = Vec::with_capacity(added.len());
        match sensor.aoa(&m, &options) {
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
                let status = psdcal_locate::status_of(&cautions);
                let warning = cautions
                    .first()
                    .map(|c| format!("{at}: {c}; answered anyway"));
                count.answered(&status, warning);
                out.push(status);
            }
            Err(e) => {
                out.extend(empty(added.len() - 1));
                out.push(e.status().to_string());
                count.failed(&e, &at);
            }
        }
        values.push(out);
    }
    let (header, rows) = points_table(&points, &added, values);
    write_output(config.out.as_ref(), &header, &rows)?;
    count.print_warnings();
    let summary = format!(
        "aoa: {} point{} of {} with {}: {}",
        points.rows.len(),
        if points.rows.len() == 1 { "" } else { "s" },
        points.source,
        config.calibration.display(),
        count.summary()
    );
    match (output, &config.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let json = serde_json::json!({
                "command": "aoa",
                "calibration": config.calibration.display().to_string(),
                "points": points.source,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "from_amplitudes": points.amplitudes,
                "point_sigma_mm": config.point_sigma_mm,
                "added_columns": added,
                "rows": count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, Some(out)) => println!("{summary}; wrote {}", out.display()),
        // The table is on standard output: the summary goes to standard error.
        (Output::Text, None) => eprintln!("{summary}"),
    }
    Ok(())
}
