//! In-situ calibration (`psdcal calibrate-in-situ`, docs/model.md §8.4):
//! the sensor mounted where it works, emitters at surveyed room positions
//! (template.csv with `Z_mm`), one or several sensor orientations (images).
//! The result is calibration.json (the same record as `calibrate`) and
//! the sensor's pose in the room per orientation, written as rig.json
//! sensor entries (`sensor_from_world`, which is what the fit estimates, with
//! its 6 × 6 covariance and the sensor's position in the room with its 3 × 3
//! covariance), so a rig for `locate --rig` takes them as they are.
//!
//! The sensor's position in the room from `sensor_from_world = (R, t)`:
//! `c = −Rᵀ t`; `∂c/∂t = −Rᵀ`, `∂c/∂r_k = −(∂R/∂r_k)ᵀ t`; its covariance
//! `J C_pose Jᵀ`.

use std::path::Path;

use nalgebra::{Matrix3, SMatrix, Vector3};
use psdcal_calib::{
    calibrate_surveyed, ImageObservations, Observation, SurveyedCalibration, SurveyedData,
    SurveyedOptions, UncertaintyVerdict,
};
use psdcal_io::{
    write_atomic_bytes, write_calibration, Calibration, FitSummary, ImageFit, StdDevs,
    ValidRegionRecord,
};
use psdcal_model::{Pose, ValidRegion};
use serde_json::{json, Value};

use crate::base::error::{Error, Result};
use crate::base::provenance::provenance;
use crate::base::summary::Summary;
use crate::dataset::data_set::DataSet;

/// An in-situ calibration with its records.
#[derive(Debug, Clone)]
pub struct InSitu {
    /// psdcal-calib's result.
    pub result: SurveyedCalibration,
    /// calibration.json (version 2, with provenance).
    pub record: Calibration,
    /// Per orientation (image id), the sensor's pose record.
    pub poses: Vec<SensorPose>,
    /// The survey σ used, mm.
    pub survey_sigma_mm: f64,
}

/// The sensor's pose in the room for one orientation.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorPose {
    /// The image (orientation) id.
    pub id: String,
    /// `sensor_from_world` as estimated.
    pub sensor_from_world: Pose,
    /// Its covariance, `(rx, ry, rz, tx, ty, tz)` (rad, mm).
    pub covariance: SMatrix<f64, 6, 6>,
    /// The sensor's position in the room, mm.
    pub position_mm: Vector3<f64>,
    /// Its covariance, mm².
    pub position_covariance: Matrix3<f64>,
}

/// `c = −Rᵀ t` and `∂c/∂(rvec, t)` (module documentation).
pub fn position_with_jacobian(sensor_from_world: &Pose) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
    sensor_from_world.centre_with_jacobian()
}

/// The surveyed data of a validated data set (its template must have `Z_mm`).
fn surveyed_data(set: &DataSet) -> Result<SurveyedData> {
    let t = &set.template;
    if t.leds.iter().any(|l| l.z_mm.is_none()) {
        return Err(Error::Input(format!(
            "{} has no Z_mm column: an in-situ calibration needs the emitters' surveyed 3-D \
             positions (led, X_mm, Y_mm, Z_mm in the room's frame); for a planar template in \
             several poses use psdcal calibrate",
            t.source
        )));
    }
    Ok(SurveyedData {
        points: t
            .leds
            .iter()
            .map(|l| Vector3::new(l.x_mm, l.y_mm, l.z_mm.unwrap_or(0.0)))
            .collect(),
        names: t.leds.iter().map(|l| l.id.clone()).collect(),
        images: set
            .validated
            .images
            .iter()
            .map(|im| ImageObservations {
                id: im.id.clone(),
                points: im
                    .points
                    .iter()
                    .map(|&(led, measured)| Observation { led, measured })
                    .collect(),
            })
            .collect(),
        geometry: set.options.geometry,
    })
}

/// Calibrates `set` in situ with the survey σ `survey_sigma_mm` (mm per
/// coordinate).
pub fn calibrate_in_situ(set: &DataSet, survey_sigma_mm: f64) -> Result<InSitu> {
    let data = surveyed_data(set)?;
    let options = SurveyedOptions {
        survey_sigma_mm,
        ..SurveyedOptions::default()
    };
    let result = calibrate_surveyed(&data, &options).map_err(Error::Calibrate)?;
    let geometry = &set.options.geometry;
    let mut record = Calibration::from_model(&result.model.sensor_model(), geometry);
    record.set_estimated(&options.free);
    let cov = &result.covariance;
    record.std = StdDevs(
        cov.names()
            .iter()
            .map(|n| (n.clone(), cov.std(n).unwrap_or(0.0)))
            .collect(),
    );
    record.covariance = psdcal_io::Covariance::from(cov);
    let ray_rms = ray_point_rms(&data, &result);
    record.fit = FitSummary {
        cost: psdcal_model::CostKind::Image,
        noise: "uniform".into(),
        residual_mm2: ray_rms.0,
        rms_template_mm: ray_rms.1,
        rms_image_mm: result.rms_image_mm,
        iterations: result.report.iterations,
        points: result.points,
        images: data.images.len(),
        termination: format!("{:?}", result.report.termination),
        uncertainty: "linear+survey".into(),
        bootstrap: None,
        model_choice: None,
    };
    record.images = data
        .images
        .iter()
        .zip(&result.poses)
        .zip(&result.rms_per_image_mm)
        .map(|((im, pose), rms)| ImageFit::new(&im.id, pose, *rms, im.points.len()))
        .collect();
    record.diagnostics = result.diagnostics.diagnostics.clone();
    let region = ValidRegion::of_model(&result.model, geometry);
    record.valid_region = Some(ValidRegionRecord::from_region(&region));
    record.provenance = Some(provenance(
        "",
        json!({ "survey_sigma_mm": survey_sigma_mm, "fit": options.free.iter().map(|p| p.name()).collect::<Vec<_>>() }),
        &set.inputs,
    ));
    let poses = data
        .images
        .iter()
        .zip(&result.poses)
        .zip(&result.pose_covariances)
        .map(|((im, pose), c)| {
            let (position_mm, j) = position_with_jacobian(pose);
            SensorPose {
                id: im.id.clone(),
                sensor_from_world: *pose,
                covariance: *c,
                position_mm,
                position_covariance: j * c * j.transpose(),
            }
        })
        .collect();
    Ok(InSitu {
        result,
        record,
        poses,
        survey_sigma_mm,
    })
}

/// Σ and RMS of the distance between each emitter and its measured ray
/// (mm, room frame): what the template-plane error is for a planar template.
fn ray_point_rms(data: &SurveyedData, r: &SurveyedCalibration) -> (f64, f64) {
    let mut ss = 0.0;
    for (image, pose) in data.images.iter().zip(&r.poses) {
        for o in &image.points {
            let p = pose.transform(&data.points[o.led]);
            let ab = r.model.ray(&o.measured);
            let d = Vector3::new(ab.x, ab.y, 1.0).normalize();
            ss += (p - d * p.dot(&d)).norm_squared();
        }
    }
    (ss, (ss / r.points.max(1) as f64).sqrt())
}

impl InSitu {
    /// Records the command line in calibration.json's provenance.
    pub fn set_command(&mut self, command: &str) {
        if let Some(p) = &mut self.record.provenance {
            p.command = command.to_string();
        }
    }

    /// The sensor poses as a rig file: one entry per orientation, its
    /// `calibration` the given path (as the rig should refer to it).
    pub fn poses_json(&self, calibration: &str) -> Value {
        let rows = |m: &dyn Fn(usize, usize) -> f64, n: usize| -> Vec<Vec<f64>> {
            (0..n).map(|a| (0..n).map(|b| m(a, b)).collect()).collect()
        };
        let sensors: Vec<Value> = self
            .poses
            .iter()
            .map(|p| {
                let pose = &p.sensor_from_world;
                json!({
                    "id": p.id,
                    "calibration": calibration,
                    "sensor_from_world": {
                        "rvec": [pose.rvec.x, pose.rvec.y, pose.rvec.z],
                        "t_mm": [pose.t.x, pose.t.y, pose.t.z],
                    },
                    "sensor_from_world_covariance": {
                        "parameters": ["rx", "ry", "rz", "tx_mm", "ty_mm", "tz_mm"],
                        "matrix": rows(&|a, b| p.covariance[(a, b)], 6),
                    },
                    "position_world_mm": [p.position_mm.x, p.position_mm.y, p.position_mm.z],
                    "position_world_covariance_mm2": rows(&|a, b| p.position_covariance[(a, b)], 3),
                })
            })
            .collect();
        json!({
            "format": psdcal_io::RIG_FORMAT,
            "version": psdcal_io::RIG_VERSION,
            "note": "sensor poses from psdcal calibrate-in-situ: one entry per orientation; a rig for locate lists each sensor once",
            "survey_sigma_mm": self.survey_sigma_mm,
            "sensors": sensors,
        })
    }

    /// Writes calibration.json and, if asked, the poses file (atomically).
    pub fn write(&self, calibration: &Path, poses: Option<&Path>) -> Result<()> {
        write_calibration(calibration, &self.record)?;
        if let Some(path) = poses {
            let name = calibration_reference(calibration, path);
            let text = serde_json::to_string_pretty(&self.poses_json(&name))
                .map_err(|e| Error::Input(format!("cannot encode the poses: {e}")))?;
            write_atomic_bytes(path, text.as_bytes())?;
        }
        Ok(())
    }

    /// What the command prints.
    pub fn text(&self) -> String {
        let r = &self.result;
        let mut out = format!(
            "in-situ calibration: {} points in {} orientation(s), survey σ {} mm; RMS image \
             error {:.3e} mm, point noise σ {:.3e} mm\n",
            r.points,
            r.poses.len(),
            self.survey_sigma_mm,
            r.rms_image_mm,
            r.point_variance.sqrt()
        );
        for name in r.covariance.names() {
            let v = r.model.get(name).unwrap_or(0.0);
            let s = r.covariance.std(name).unwrap_or(0.0);
            out.push_str(&format!("  {name:<3} = {v:.6e} ± {s:.2e}\n"));
        }
        for p in &self.poses {
            let d = p.position_covariance.diagonal().map(f64::sqrt);
            let rot = p.covariance.diagonal();
            let rot_deg = (rot[0] + rot[1] + rot[2]).sqrt().to_degrees();
            out.push_str(&format!(
                "  orientation '{}': sensor at ({:.1}, {:.1}, {:.1}) ± ({:.1}, {:.1}, {:.1}) mm \
                 in the room, orientation σ {:.3}°\n",
                p.id, p.position_mm.x, p.position_mm.y, p.position_mm.z, d.x, d.y, d.z, rot_deg
            ));
        }
        if let UncertaintyVerdict::Unreliable { reason } = &r.linearity.verdict {
            out.push_str(&format!("  linearity at ±3σ: {reason}\n"));
        }
        out
    }

    /// The summary after writing calibration.json to `out` (and the poses
    /// to `poses`): the text, the `--json` summary, and as warnings the
    /// fit's warnings and diagnostics (as `calibrate` shows them).
    pub fn summary(&self, out: &Path, poses: Option<&Path>) -> Summary {
        let diagnostics = self.result.diagnostics.diagnostics.iter();
        Summary::new(self.text(), self.json())
            .wrote(std::iter::once(out).chain(poses))
            .warn(&self.result.warnings)
            .warn(diagnostics.map(|d| &d.message))
    }

    /// The `--json` summary.
    pub fn json(&self) -> Value {
        let r = &self.result;
        json!({
            "parameters": r.covariance.names().iter().map(|n| json!({
                "name": n, "value": r.model.get(n), "std": r.covariance.std(n)
            })).collect::<Vec<_>>(),
            "rms_image_mm": r.rms_image_mm,
            "point_sigma_mm": r.point_variance.sqrt(),
            "points": r.points,
            "iterations": r.report.iterations,
            "poses": self.poses_json("calibration.json")["sensors"].clone(),
            "warnings": psdcal_calib::warning_texts(&r.warnings),
            "diagnostics": r.diagnostics.diagnostics,
            "linearity": r.linearity,
        })
    }
}

/// The calibration's path as the poses file should name it: its file name
/// when both sit in one folder, else the path as given.
fn calibration_reference(calibration: &Path, poses: &Path) -> String {
    let same_dir = calibration
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
        == poses.parent().map(Path::to_path_buf).unwrap_or_default();
    match (same_dir, calibration.file_name()) {
        (true, Some(name)) => name.to_string_lossy().into_owned(),
        _ => calibration.display().to_string(),
    }
}
