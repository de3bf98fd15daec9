//! `psdcal locate`: emitter positions with their 3-D covariance, on a plane
//! in the sensor frame (one calibrated sensor) or from the rays of a rig
//! of sensors with known poses in a world frame (psdcal-locate).

use std::path::Path;

use nalgebra::Matrix3;
use psdcal_io::{read_calibration, Points, RigFile, RigObservations};
use psdcal_locate::{status_of, LocateOptions, Measurement, Plane, Rig, RigSensor};

use crate::cli::Output;
use crate::cli_locate::{LocateConfig, LocateTarget};
use crate::cmd_aoa::measurement;
use crate::locate_output::{
    calibrated_sensor, deg, empty, num, points_table, refuse_existing_columns,
    warn_without_covariance, write_output, StatusCount,
};

/// The position and covariance columns in `frame` (`sensor` or `world`).
fn position_columns(frame: &str) -> [String; 3] {
    ["x", "y", "z"].map(|a| format!("{a}_{frame}_mm"))
}

fn covariance_columns(frame: &str) -> [String; 7] {
    [
        format!("sigma_x_{frame}_mm"),
        format!("sigma_y_{frame}_mm"),
        format!("sigma_z_{frame}_mm"),
        format!("cov_xy_{frame}_mm2"),
        format!("cov_xz_{frame}_mm2"),
        format!("cov_yz_{frame}_mm2"),
        "sigma_position_mm".to_string(),
    ]
}

fn covariance_fields(c: &Matrix3<f64>) -> [String; 7] {
    let sd = |v: f64| num(v.max(0.0).sqrt());
    [
        sd(c[(0, 0)]),
        sd(c[(1, 1)]),
        sd(c[(2, 2)]),
        num(c[(0, 1)]),
        num(c[(0, 2)]),
        num(c[(1, 2)]),
        sd(c.trace()),
    ]
}

/// Runs `locate`.
pub fn run(config: &LocateConfig, output: Output) -> anyhow::Result<()> {
    let (count, rows, what) = match &config.target {
        LocateTarget::Plane { calibration, plane } => on_plane(config, calibration, plane)?,
        LocateTarget::Rig(rig) => with_rig(config, rig)?,
    };
    count.print_warnings();
    let summary = format!("locate: {rows} {what}: {}", count.summary());
    match (output, &config.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let target = match &config.target {
                LocateTarget::Plane { calibration, plane } => serde_json::json!({
                    "calibration": calibration.display().to_string(),
                    "plane_normal": plane.normal().as_slice(),
                    "plane_offset_mm": plane.offset_mm(),
                    "frame": "sensor",
                }),
                LocateTarget::Rig(rig) => serde_json::json!({
                    "rig": rig.display().to_string(),
                    "frame": "world",
                    "weighted": config.options.weight_rays,
                }),
            };
            let json = serde_json::json!({
                "command": "locate",
                "points": config.points.display().to_string(),
                "target": target,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "point_sigma_mm": config.point_sigma_given.then_some(config.options.point_sigma_mm),
                "rows": count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, Some(out)) => println!("{summary}; wrote {}", out.display()),
        (Output::Text, None) => eprintln!("{summary}"),
    }
    Ok(())
}

fn on_plane(
    config: &LocateConfig,
    calibration_path: &Path,
    plane: &Plane,
) -> anyhow::Result<(StatusCount, usize, String)> {
    let calibration = read_calibration(calibration_path)?;
    let sensor = calibrated_sensor(&calibration, calibration_path)?;
    let points = Points::read(&config.points)?;
    let mut added: Vec<String> = Vec::new();
    if points.amplitudes {
        added.extend(["x_mm".into(), "y_mm".into()]);
    }
    added.extend(["alpha_x_deg".into(), "alpha_y_deg".into()]);
    added.extend(position_columns("sensor"));
    added.push("range_mm".into());
    added.extend(covariance_columns("sensor"));
    added.push("status".into());
    refuse_existing_columns(&points, &added)?;
    warn_without_covariance(&sensor, calibration_path);
    let mut count = StatusCount::default();
    let mut values = Vec::with_capacity(points.rows.len());
    for row in &points.rows {
        let at = format!("{}:{}", points.source, row.line_no);
        let mut out = Vec::with_capacity(added.len());
        match sensor.locate_on_plane(&measurement(&row.input), plane, &config.options) {
            Ok(loc) => {
                let a = &loc.aoa.aoa;
                if points.amplitudes {
                    out.extend([num(a.measured.x), num(a.measured.y)]);
                }
                let p = loc.intersection.position;
                out.extend([
                    deg(a.alpha.x),
                    deg(a.alpha.y),
                    num(p.x),
                    num(p.y),
                    num(p.z),
                    num(loc.intersection.range_mm),
                ]);
                out.extend(covariance_fields(&loc.covariance()));
                let status = status_of(&loc.cautions);
                let warning = loc
                    .cautions
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
    let what = format!(
        "point{} of {} on the plane {:?}.P = {} mm (sensor frame of {})",
        if points.rows.len() == 1 { "" } else { "s" },
        points.source,
        plane.normal().as_slice(),
        plane.offset_mm(),
        calibration_path.display()
    );
    Ok((count, points.rows.len(), what))
}

/// The rig of a rig file: every calibration read, the shared views checked.
fn load_rig(path: &Path) -> anyhow::Result<(RigFile, Rig)> {
    let file = RigFile::read(path)?;
    let mut sensors = Vec::with_capacity(file.sensors.len());
    for record in &file.sensors {
        let calibration = read_calibration(&record.calibration_path)?;
        let sensor = calibrated_sensor(&calibration, &record.calibration_path)?;
        warn_without_covariance(&sensor, &record.calibration_path);
        sensors.push(RigSensor {
            id: record.id.clone(),
            sensor,
            world_from_sensor: record.world_from_sensor,
        });
    }
    let rig = Rig::new(sensors)?;
    if rig.view_pairs().is_empty() {
        eprintln!(
            "warning: {}: no two sensors share a field of view (no point in front of two sensors \
             falls on both active areas); emitters whose rays do not meet in view get status \
             no_shared_view: check each pose and whether it is world_from_sensor or \
             sensor_from_world",
            file.source
        );
    }
    Ok((file, rig))
}

fn with_rig(
    config: &LocateConfig,
    rig_path: &Path,
) -> anyhow::Result<(StatusCount, usize, String)> {
    let (file, rig) = load_rig(rig_path)?;
    let observations = RigObservations::read(&config.points)?;
    observations.check_against(&file)?;
    let mut header: Vec<String> = vec!["emitter".into(), "sensors".into()];
    header.extend(position_columns("world"));
    header.extend(covariance_columns("world"));
    header.extend(["max_miss_mm", "ray_angle_deg", "status"].map(String::from));
    let mut count = StatusCount::default();
    let mut rows = Vec::new();
    let options: LocateOptions = config.options;
    let emitters = observations.emitters();
    for (emitter, indices) in &emitters {
        let seen: Vec<(usize, Measurement)> = indices
            .iter()
            .map(|&i| {
                let row = &observations.rows[i];
                // check_against guarantees the sensor exists.
                let k = file.index_of(&row.sensor).unwrap_or(usize::MAX);
                (k, measurement(&row.input))
            })
            .collect();
        let sensor_ids: Vec<&str> = indices
            .iter()
            .map(|&i| observations.rows[i].sensor.as_str())
            .collect();
        let lines: Vec<String> = indices
            .iter()
            .map(|&i| observations.rows[i].line_no.to_string())
            .collect();
        let at = format!(
            "{}: emitter '{emitter}' (line{} {})",
            observations.source,
            if lines.len() == 1 { "" } else { "s" },
            lines.join(", ")
        );
        let mut out = vec![emitter.clone(), sensor_ids.join(";")];
        match rig.locate(&seen, &options) {
            Ok(loc) => {
                let t = &loc.triangulation;
                out.extend([num(t.position.x), num(t.position.y), num(t.position.z)]);
                out.extend(covariance_fields(&t.covariance));
                let max_miss = t.miss_mm.iter().copied().fold(0.0, f64::max);
                out.extend([num(max_miss), deg(t.max_ray_angle)]);
                let status = status_of(&loc.cautions);
                let warning = loc
                    .cautions
                    .first()
                    .map(|c| format!("{at}: {c}; answered anyway"));
                count.answered(&status, warning);
                out.push(status);
            }
            Err(e) => {
                out.extend(empty(header.len() - 3));
                out.push(e.status().to_string());
                count.failed(&e, &at);
            }
        }
        rows.push(out);
    }
    write_output(config.out.as_ref(), &header, &rows)?;
    let what = format!(
        "emitter{} of {} with the {} sensors of {} (world frame)",
        if emitters.len() == 1 { "" } else { "s" },
        observations.source,
        rig.sensors().len(),
        file.source
    );
    Ok((count, emitters.len(), what))
}
