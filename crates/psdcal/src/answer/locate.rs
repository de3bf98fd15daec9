//! Emitter positions with their 3-D covariance: on a plane in the sensor
//! frame (one calibrated sensor) or from the rays of a rig of sensors with
//! known poses in a world frame. The table `psdcal locate` writes.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector2};
use psdcal_io::{ReadLimits, RigFile, RigObservations};
use psdcal_locate::{LocateOptions, Measurement, Plane, Rig, RigSensor};

use crate::answer::aoa::measurement;
use crate::answer::loaded_sensor::{covariance_warning, LoadedSensor};
use crate::answer::point_rows::answer_points;
use crate::base::error::Result;
use crate::base::summary::{path_json, Summary};
use crate::base::table::{deg, empty, num, StatusCount, Table};

/// Where the emitters are located.
#[derive(Debug, Clone, PartialEq)]
pub enum LocateTarget {
    /// A plane in the sensor frame of one calibration.
    Plane {
        /// calibration.json.
        calibration: PathBuf,
        /// The plane.
        plane: Plane,
    },
    /// A rig file (sensors with calibrations and world poses).
    Rig(PathBuf),
}

/// The located emitters (the table is written as it is computed).
#[derive(Debug, Clone)]
pub struct LocateTable {
    /// Status counts and per-row warnings.
    pub count: StatusCount,
    /// Rows answered (points or emitters).
    pub rows: usize,
    /// What was located, in words (for the summary line).
    pub what: String,
    /// Warnings about the inputs (before any row).
    pub warnings: Vec<String>,
}

impl LocateTable {
    /// The summary of `locate` on `target` for the `points` file, its table
    /// written to `out` (`None`: standard output); `point_sigma_mm` as the
    /// user gave it.
    pub fn summary(
        &self,
        target: &LocateTarget,
        points: &Path,
        out: Option<&Path>,
        options: &LocateOptions,
        point_sigma_mm: Option<f64>,
    ) -> Summary {
        let target_json = match target {
            LocateTarget::Plane { calibration, plane } => serde_json::json!({
                "calibration": calibration.display().to_string(),
                "plane_normal": plane.normal().as_slice(),
                "plane_offset_mm": plane.offset_mm(),
                "frame": "sensor",
            }),
            LocateTarget::Rig(rig) => serde_json::json!({
                "rig": rig.display().to_string(),
                "frame": "world",
                "weighted": options.weight_rays,
            }),
        };
        let json = serde_json::json!({
            "command": "locate",
            "points": points.display().to_string(),
            "target": target_json,
            "out": path_json(out),
            "point_sigma_mm": point_sigma_mm,
            "rows": self.count.to_json(),
        });
        let text = format!(
            "locate: {} {}: {}",
            self.rows,
            self.what,
            self.count.summary()
        );
        Summary::new(text, json)
            .table_at(out)
            .warn(&self.warnings)
            .warn(self.count.warning_lines())
    }
}

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

/// A position covariance (mm²) as its CSV fields: σx, σy, σz (mm), the
/// covariances xy, xz, yz (mm²), the position σ √trace (mm).
pub(crate) fn covariance_fields(c: &Matrix3<f64>) -> [String; 7] {
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

/// Locates the emitters of `points` on `target` and writes the table to
/// `out` (standard output when `None`); on a plane the points are streamed.
/// The files read whole are bounded by `limits`.
pub fn locate_table(
    target: &LocateTarget,
    points: &Path,
    options: &LocateOptions,
    out: Option<&Path>,
    limits: ReadLimits,
) -> Result<LocateTable> {
    match target {
        LocateTarget::Plane { calibration, plane } => {
            on_plane(calibration, plane, points, options, out, limits)
        }
        LocateTarget::Rig(rig) => {
            let (located, table) = with_rig(rig, points, options, limits)?;
            table.write_to(out)?;
            Ok(located)
        }
    }
}

fn on_plane(
    calibration: &Path,
    plane: &Plane,
    points: &Path,
    options: &LocateOptions,
    out: Option<&Path>,
    limits: ReadLimits,
) -> Result<LocateTable> {
    let loaded = LoadedSensor::read_with(calibration, limits)?;
    let added = |amplitudes: bool| {
        let mut added: Vec<String> = Vec::new();
        if amplitudes {
            added.extend(["x_mm".into(), "y_mm".into()]);
        }
        added.extend(["alpha_x_deg".into(), "alpha_y_deg".into()]);
        added.extend(position_columns("sensor"));
        added.push("range_mm".into());
        added.extend(covariance_columns("sensor"));
        added.push("status".into());
        added
    };
    let sensor = &loaded.sensor;
    let answer = answer_points(points, out, added, |m| {
        let loc = sensor.locate_on_plane(m, plane, options)?;
        let a = &loc.aoa.aoa;
        let mut values = Vec::with_capacity(16);
        if matches!(m, Measurement::Amplitudes(_)) {
            values.extend([num(a.measured.x), num(a.measured.y)]);
        }
        let p = loc.intersection.position;
        values.extend([
            deg(a.alpha.x),
            deg(a.alpha.y),
            num(p.x),
            num(p.y),
            num(p.z),
            num(loc.intersection.range_mm),
        ]);
        values.extend(covariance_fields(&loc.covariance()));
        Ok((values, loc.cautions.clone()))
    })?;
    let what = format!(
        "point{} of {} on the plane {:?}.P = {} mm (sensor frame of {})",
        if answer.rows == 1 { "" } else { "s" },
        answer.source,
        plane.normal().as_slice(),
        plane.offset_mm(),
        calibration.display()
    );
    Ok(LocateTable {
        count: answer.count,
        rows: answer.rows,
        what,
        warnings: covariance_warning(&loaded).into_iter().collect(),
    })
}

/// The rig of a rig file: every calibration read (each file once, within
/// `limits`).
pub(crate) fn load_rig(
    path: &Path,
    limits: ReadLimits,
    warnings: &mut Vec<String>,
) -> Result<(RigFile, Rig)> {
    let file = RigFile::read_with(path, limits)?;
    let mut loaded: HashMap<&Path, LoadedSensor> = HashMap::new();
    let mut sensors = Vec::with_capacity(file.sensors.len());
    for record in &file.sensors {
        let path = record.calibration_path.as_path();
        let sensor = match loaded.get(path) {
            Some(known) => known.sensor.clone(),
            None => {
                let new = LoadedSensor::read_with(path, limits)?;
                warnings.extend(covariance_warning(&new));
                let sensor = new.sensor.clone();
                loaded.insert(path, new);
                sensor
            }
        };
        sensors.push(RigSensor {
            id: record.id.clone(),
            sensor,
            world_from_sensor: record.world_from_sensor,
        });
    }
    let rig = Rig::new(sensors)?;
    Ok((file, rig))
}

/// The warning when no two sensors that observe one emitter together share
/// a field of view (only those pairs are checked: linear in the emitters).
fn shared_view_warning(rig: &Rig, emitters: &[Vec<usize>], file: &RigFile) -> Option<String> {
    let any_shared = emitters.iter().any(|sensors| {
        sensors
            .iter()
            .enumerate()
            .any(|(a, &i)| sensors[a + 1..].iter().any(|&j| rig.shares_view(i, j)))
    });
    (!any_shared).then(|| {
        format!(
            "{}: no two sensors that observe an emitter together share a field of view (no point \
             in front of both falls on both active areas); emitters whose rays do not meet in \
             view get status no_shared_view: check each pose and whether it is \
             world_from_sensor or sensor_from_world",
            file.source
        )
    })
}

fn with_rig(
    rig_path: &Path,
    points: &Path,
    options: &LocateOptions,
    limits: ReadLimits,
) -> Result<(LocateTable, Table)> {
    let mut warnings = Vec::new();
    let (file, rig) = load_rig(rig_path, limits, &mut warnings)?;
    let observations = RigObservations::read_with(points, limits)?;
    observations.check_against(&file)?;
    let mut header: Vec<String> = vec!["emitter".into(), "sensors".into()];
    header.extend(position_columns("world"));
    header.extend(covariance_columns("world"));
    header.extend(["max_miss_mm", "ray_angle_deg", "status"].map(String::from));
    let mut count = StatusCount::default();
    let mut rows = Vec::new();
    let emitters = observations.emitters();
    let index = file.index();
    // check_against guarantees every sensor exists.
    let sensor_of = |i: usize| {
        index
            .get(observations.rows[i].sensor.as_str())
            .copied()
            .unwrap_or(usize::MAX)
    };
    let observed: Vec<Vec<usize>> = emitters
        .iter()
        .map(|(_, indices)| indices.iter().map(|&i| sensor_of(i)).collect())
        .collect();
    warnings.extend(shared_view_warning(&rig, &observed, &file));
    for (emitter, indices) in &emitters {
        let seen: Vec<(usize, Measurement)> = indices
            .iter()
            .map(|&i| {
                let row = &observations.rows[i];
                let k = sensor_of(i);
                let m = measurement(&row.input);
                (
                    k,
                    m.unwrap_or(Measurement::Point(Vector2::new(f64::NAN, f64::NAN))),
                )
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
        match rig.locate(&seen, options) {
            Ok(loc) => {
                let t = &loc.triangulation;
                out.extend([num(t.position.x), num(t.position.y), num(t.position.z)]);
                out.extend(covariance_fields(&t.covariance));
                let max_miss = t.miss_mm.iter().copied().fold(0.0, f64::max);
                out.extend([num(max_miss), deg(t.max_ray_angle)]);
                out.push(count.answered_with(&at, &loc.cautions));
            }
            Err(e) => {
                out.extend(empty(header.len() - 3));
                out.push(e.status().to_string());
                count.failed(&e, &at);
            }
        }
        rows.push(out);
    }
    let what = format!(
        "emitter{} of {} with the {} sensors of {} (world frame)",
        if emitters.len() == 1 { "" } else { "s" },
        observations.source,
        rig.sensors().len(),
        file.source
    );
    let located = LocateTable {
        count,
        rows: emitters.len(),
        what,
        warnings,
    };
    Ok((located, Table { header, rows }))
}
