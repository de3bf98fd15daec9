//! `psdcal calibrate-network`: the files read ([`crate::network::network_input`]),
//! the network calibrated (psdcal-network), then written: rig.json (format
//! `psdcal-rig` 1, each sensor's `sensor_from_world` with its covariance
//! and its optical centre in the world with its covariance) and, beside
//! it, each sensor's refined calibration.json (`<rig stem>.<sensor>.json`:
//! the lab record with the refined lens, its covariance from the network,
//! the lab file named in its provenance), so that `locate --rig` and
//! `track --rig` use them as they are.
//!
//! rig.json is the file `--out` names (replaced as any `--out` is); the
//! refined calibrations beside it and the report page are named by psdcal,
//! so they replace only files psdcal wrote there (psdcal-io's
//! `OutputFolder`: refused before anything is written, unless `force`).

use std::path::{Path, PathBuf};

use psdcal_io::{
    refuse_overwrite, write_atomic_bytes, write_calibration, Calibration, ReadLimits, StdDevs,
};
use psdcal_network::{calibrate_network, NetworkOptions, NetworkResult};
use serde_json::{json, Value};

use crate::base::error::{Error, Result};
use crate::base::provenance::{provenance, InputHashes};
use crate::base::summary::Summary;
use crate::network::network_input::{read_network, NetworkFiles, NetworkInput};
use crate::network::network_outputs::{claim_calibrations, claim_page};

/// Calibrate a room of sensors from a waved wand: every pose and lens, no surveyed emitters (rig.json)
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct NetworkRequest {
    /// The input files.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub files: NetworkFiles,
    /// Output rig.json (each sensor's refined calibration is written beside it)
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub out: PathBuf,
    /// Also write a report page (index.html) into this folder
    #[cfg_attr(feature = "clap", arg(long, value_name = "DIR"))]
    pub report: Option<PathBuf>,
    /// Replace files beside `out` and in `report` that psdcal did not write
    /// there (otherwise refused before anything is written; docs/formats.md,
    /// "Output folders"). The command line's global `--force`.
    #[cfg_attr(feature = "clap", arg(skip))]
    pub force: bool,
}

/// A calibrated network and where it goes.
#[derive(Debug, Clone)]
pub struct NetworkCalibrated {
    /// What was read.
    pub input: NetworkInput,
    /// The calibration.
    pub result: NetworkResult,
    /// rig.json.
    pub out: PathBuf,
    /// Each sensor's refined calibration.json.
    pub calibrations: Vec<PathBuf>,
    /// Replace files psdcal did not write ([`NetworkRequest::force`]).
    pub force: bool,
}

/// A sensor id as a file-name part (characters other than letters, digits,
/// `-`, `_` and `.` become `_`).
fn file_part(id: &str) -> String {
    id.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Reads, calibrates; nothing written yet.
pub fn calibrate_network_files(
    request: &NetworkRequest,
    limits: ReadLimits,
) -> Result<NetworkCalibrated> {
    let input = read_network(&request.files, limits)?;
    let stem = request
        .out
        .file_stem()
        .map_or("rig".to_string(), |s| s.to_string_lossy().into_owned());
    let folder = request
        .out
        .parent()
        .unwrap_or_else(|| Path::new(""))
        .to_path_buf();
    let calibrations: Vec<PathBuf> = input
        .data
        .sensors
        .iter()
        .map(|s| folder.join(format!("{stem}.{}.json", file_part(&s.id))))
        .collect();
    let mut ins: Vec<(&str, &Path)> = vec![
        ("--sensors", &request.files.sensors),
        ("--wand", &request.files.wand),
        ("--observations", &request.files.observations),
    ];
    if let Some(f) = &request.files.frame {
        ins.push(("--frame", f));
    }
    for (_, lab) in &input.labs {
        ins.push(("a lab calibration", lab));
    }
    let mut outs: Vec<(&str, &Path)> = vec![("--out", &request.out)];
    for c in &calibrations {
        outs.push(("a refined calibration", c));
    }
    refuse_overwrite(&ins, &outs)?;
    // Refused before the calibration's work when a file psdcal names is not
    // psdcal's; claimed again when written.
    claim_calibrations(&request.out, &calibrations, request.force)?;
    if let Some(dir) = &request.report {
        claim_page(dir, request.force)?;
    }
    let result = calibrate_network(&input.data, &NetworkOptions::default())?;
    Ok(NetworkCalibrated {
        input,
        result,
        out: request.out.clone(),
        calibrations,
        force: request.force,
    })
}

fn rows(m: &dyn Fn(usize, usize) -> f64, n: usize) -> Vec<Vec<f64>> {
    (0..n).map(|a| (0..n).map(|b| m(a, b)).collect()).collect()
}

impl NetworkCalibrated {
    /// Sensor `k`'s refined calibration record.
    pub fn refined(&self, k: usize, command: &str) -> Calibration {
        let (lab, lab_path) = &self.input.labs[k];
        let e = &self.result.sensors[k];
        let model = e.model.sensor_model();
        let mut record = Calibration::from_model(&model, &lab.geometry());
        record.set_estimated(&lab.estimated);
        record.gains = lab.gains.map(|mut g| {
            g.estimated = false;
            g
        });
        let names = &e.lens_names;
        record.std = StdDevs(
            names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.clone(), e.lens_covariance[(i, i)].max(0.0).sqrt()))
                .collect(),
        );
        record.covariance = psdcal_io::Covariance {
            parameters: names.clone(),
            matrix: rows(&|a, b| e.lens_covariance[(a, b)], names.len()),
        };
        record.fit = psdcal_io::FitSummary {
            cost: psdcal_model::CostKind::Image,
            noise: "uniform".into(),
            residual_mm2: e.residual_mm2,
            rms_template_mm: e.rms_image_mm(),
            rms_image_mm: e.rms_image_mm(),
            iterations: self.result.iterations,
            points: e.points,
            images: self.result.frames_used,
            termination: format!("{:?}", self.result.report.termination),
            uncertainty: "network (lab prior included)".into(),
            bootstrap: None,
            model_choice: None,
        };
        record.store_valid_region();
        let mut inputs = InputHashes::default();
        inputs.0 = self.input.inputs.clone();
        record.provenance = Some(provenance(
            command,
            json!({ "network": true, "lab_calibration": lab_path.display().to_string(),
                    "sensor": self.input.data.sensors[k].id }),
            &inputs,
        ));
        record
    }

    /// The rig.json value.
    pub fn rig_json(&self) -> Value {
        let r = &self.result;
        let sensors: Vec<Value> = r
            .sensors
            .iter()
            .enumerate()
            .map(|(k, e)| {
                let p = &e.sensor_from_world;
                let name = self.calibrations[k]
                    .file_name()
                    .map_or(String::new(), |n| n.to_string_lossy().into_owned());
                json!({
                    "id": self.input.data.sensors[k].id,
                    "calibration": name,
                    "sensor_from_world": { "rvec": p.rvec.as_slice(), "t_mm": p.t.as_slice() },
                    "sensor_from_world_covariance": {
                        "parameters": ["rx", "ry", "rz", "tx_mm", "ty_mm", "tz_mm"],
                        "matrix": rows(&|a, b| e.pose_covariance[(a, b)], 6),
                    },
                    "position_world_mm": e.position_mm.as_slice(),
                    "position_world_covariance_mm2": rows(&|a, b| e.position_covariance[(a, b)], 3),
                    "points": e.points,
                })
            })
            .collect();
        json!({
            "format": psdcal_io::RIG_FORMAT,
            "version": psdcal_io::RIG_VERSION,
            "note": format!("psdcal calibrate-network; {}", r.gauge.describe(&self.input.data.sensors[0].id)),
            "gauge": r.gauge,
            "point_sigma_mm": r.sigma_mm,
            "sensors": sensors,
        })
    }

    /// Writes rig.json and the refined calibrations (refused before any
    /// write when a calibration's name holds a file psdcal did not write).
    pub fn write(&self, command: &str) -> Result<()> {
        let folder = claim_calibrations(&self.out, &self.calibrations, self.force)?;
        let text = serde_json::to_string_pretty(&self.rig_json())
            .map_err(|e| Error::Input(format!("cannot encode rig.json: {e}")))?;
        if let Some(dir) = self.out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
                path: dir.to_path_buf(),
                message: format!("cannot create the output folder {}: {e}", dir.display()),
            })?;
        }
        for k in 0..self.result.sensors.len() {
            write_calibration(&self.calibrations[k], &self.refined(k, command))?;
        }
        write_atomic_bytes(&self.out, (text + "\n").as_bytes())?;
        folder.finish()?;
        Ok(())
    }

    /// What the command prints.
    pub fn summary(&self) -> Summary {
        let r = &self.result;
        let d = &self.input.data;
        let dropped_outliers = r
            .dropped
            .iter()
            .filter(|x| x.1 == psdcal_network::DropReason::Outlier)
            .count();
        let mut text = format!(
            "network of {} sensors calibrated from {} frames ({} dropped: {} with a bad sighting, \
             {} not placed); point noise σ {:.3e} mm; wand-length RMS {:.3} mm\n{}\n",
            d.sensors.len(),
            r.frames_used,
            r.dropped.len(),
            dropped_outliers,
            r.dropped.len() - dropped_outliers,
            r.sigma_mm,
            r.diagnostics.wand_length_rms_mm,
            r.gauge.describe(&d.sensors[0].id),
        );
        let mut sensors = Vec::new();
        for (k, e) in r.sensors.iter().enumerate() {
            let (sd, rot) = (e.position_sigma_mm(), e.orientation_sigma_deg());
            let f = e.model.get("f").unwrap_or(f64::NAN);
            text.push_str(&format!(
                "  {}: at ({:.1}, {:.1}, {:.1}) ± ({:.2}, {:.2}, {:.2}) mm, orientation σ {:.4}°, \
                 f {:.4} mm, {} points, {:.0} % of its area covered\n",
                d.sensors[k].id,
                e.position_mm.x,
                e.position_mm.y,
                e.position_mm.z,
                sd.x,
                sd.y,
                sd.z,
                rot,
                f,
                e.points,
                100.0 * r.diagnostics.coverage[k].fraction
            ));
            sensors.push(json!({
                "id": d.sensors[k].id,
                "points": e.points,
                "calibration": self.calibrations[k].display().to_string(),
                "position_world_mm": e.position_mm.as_slice(),
                "position_sigma_mm": sd.as_slice(),
                "orientation_sigma_deg": rot,
                "rms_image_mm": e.rms_image_mm(),
                "coverage": r.diagnostics.coverage[k].fraction,
                "lens": e.lens_names.iter().map(|n| (n.clone(), json!(e.model.get(n)))).collect::<serde_json::Map<_, _>>(),
            }));
        }
        for item in &r.diagnostics.items {
            text.push_str(&format!("  [{}] {}\n", item.code, item.message));
        }
        text.push_str(&format!(
            "wrote {} and {} calibrations beside it\n",
            self.out.display(),
            self.calibrations.len()
        ));
        let json = json!({
            "out": self.out.display().to_string(),
            "sensors": sensors,
            "gauge": r.gauge,
            "frames": d.frames.len(),
            "frames_used": r.frames_used,
            "frames_dropped": r.dropped.len(),
            "dropped": r.dropped.iter().map(|(f, why)| json!({"frame": d.frames[*f], "reason": why})).collect::<Vec<_>>(),
            "point_sigma_mm": r.sigma_mm,
            "wand_length_rms_mm": r.diagnostics.wand_length_rms_mm,
            "worst_frames": r.diagnostics.worst_frames.iter().map(|(f, e)| json!({"frame": d.frames[*f], "wand_length_error_mm": e})).collect::<Vec<_>>(),
            "frames_to_halve_sigma": r.diagnostics.frames_to_halve_sigma,
            "iterations": r.iterations,
            "termination": r.report.termination,
            "diagnostics": r.diagnostics.items,
        });
        let warnings: Vec<String> = r
            .diagnostics
            .items
            .iter()
            .filter(|i| i.severity == psdcal_model::Severity::Warning)
            .map(|i| i.message.clone())
            .collect();
        Summary::new(text, json).warn(warnings)
    }
}
