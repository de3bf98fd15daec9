//! `psdcal map`: AoA and position error maps over the sensor area (the
//! paper's Figure 9, (P40)–(P42); psdcal-locate's maps).

use psdcal_io::read_calibration;
use psdcal_locate::{error_map, ErrorSource, MapOptions, ParameterErrors};
use psdcal_model::{PsdGeometry, SensorModel};

use crate::cli::Output;
use crate::cli_locate::{MapConfig, MapModel, MapSource};
use crate::locate_output::{calibrated_sensor, deg, empty, num, write_output, StatusCount};

/// Runs `map`.
pub fn run(config: &MapConfig, output: Output) -> anyhow::Result<()> {
    let (model, geometry, covariance, model_name) = match &config.model {
        MapModel::Calibration(path) => {
            let calibration = read_calibration(path)?;
            let sensor = calibrated_sensor(&calibration, path)?;
            (
                sensor.model,
                sensor.geometry,
                Some(sensor.covariance),
                path.display().to_string(),
            )
        }
        MapModel::PaperLens(n) => (
            if *n == 1 {
                SensorModel::paper_lens1()
            } else {
                SensorModel::paper_lens2()
            },
            PsdGeometry::default(),
            None,
            format!("the paper's lens {n}"),
        ),
    };
    let source = match (&config.source, covariance) {
        (MapSource::Errors(errors), _) => {
            ErrorSource::Parameters(ParameterErrors::new(errors.clone())?)
        }
        (MapSource::KSigma(k), Some(covariance)) => {
            if covariance.is_empty() {
                anyhow::bail!(
                    "{model_name} has no covariance (nothing was estimated), so a k-sigma map would \
                     be zero everywhere; give parameter errors with --error NAME=VALUE"
                );
            }
            ErrorSource::Covariance { covariance, k: *k }
        }
        (MapSource::KSigma(_), None) => anyhow::bail!("--k-sigma needs --calibration"),
    };
    let options = MapOptions {
        grid: config.grid,
        distance_mm: config.distance_mm,
        paper_form: config.paper,
    };
    let map = error_map(&model, &geometry, &source, &options)?;
    let mut header: Vec<String> = [
        "x_mm",
        "y_mm",
        "alpha_x_deg",
        "alpha_y_deg",
        "aoa_error_x_deg",
        "aoa_error_y_deg",
        "aoa_error_deg",
        "position_error_x_mm",
        "position_error_y_mm",
        "position_error_mm",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    if config.paper {
        header.extend([
            "paper_aoa_error_x_deg".into(),
            "paper_aoa_error_y_deg".into(),
        ]);
    }
    header.push("status".into());
    let mut count = StatusCount::default();
    let mut rows = Vec::with_capacity(map.cells.len());
    for cell in &map.cells {
        let mut out = vec![num(cell.measured.x), num(cell.measured.y)];
        match &cell.values {
            Ok(v) => {
                out.extend([
                    deg(v.alpha.x),
                    deg(v.alpha.y),
                    deg(v.aoa_error.x),
                    deg(v.aoa_error.y),
                    deg(v.aoa_error_total),
                    num(v.position_error.x),
                    num(v.position_error.y),
                    num(v.position_error_total),
                ]);
                if let Some(p) = v.paper_aoa_error {
                    out.extend([deg(p.x), deg(p.y)]);
                }
                out.push("ok".into());
                count.answered("ok", None);
            }
            Err(e) => {
                out.extend(empty(header.len() - 3));
                out.push(e.status().to_string());
                count.failed(
                    e,
                    &format!("grid point ({}, {}) mm", cell.measured.x, cell.measured.y),
                );
            }
        }
        rows.push(out);
    }
    write_output(config.out.as_ref(), &header, &rows)?;
    count.print_warnings();
    let max_aoa = map.max_aoa_error().map(f64::to_degrees);
    let max_pos = map.max_position_error();
    let source_text = match &config.source {
        MapSource::Errors(e) => e
            .iter()
            .map(|(p, v)| format!("Δ{p} = {v}"))
            .collect::<Vec<_>>()
            .join(", "),
        MapSource::KSigma(k) => format!("{k} σ of the calibration's covariance"),
    };
    match (output, &config.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let json = serde_json::json!({
                "command": "map",
                "model": model_name,
                "errors": source_text,
                "grid": config.grid,
                "distance_mm": config.distance_mm,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "max_aoa_error_deg": max_aoa,
                "max_position_error_mm": max_pos,
                "rows": count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, out) => {
            let text = format!(
                "map: {model_name}, {source_text}, {n} x {n} grid over {lx} x {ly} mm, plane at \
                 {s} mm: largest AoA error {aoa}°, largest position error {pos} mm; {counts}",
                n = config.grid,
                lx = geometry.lx,
                ly = geometry.ly,
                s = config.distance_mm,
                aoa = max_aoa.map_or("-".into(), |v| format!("{v:.4}")),
                pos = max_pos.map_or("-".into(), |v| format!("{v:.2}")),
                counts = count.summary(),
            );
            match out {
                Some(path) => println!("{text}; wrote {}", path.display()),
                None => eprintln!("{text}"),
            }
        }
    }
    Ok(())
}
