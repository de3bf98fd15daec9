//! `psdcal plan`: template poses that minimise the predicted angle-of-arrival
//! uncertainty (docs/model.md §8.6; the science is
//! `psdcal_calib::plan`), written as poses.csv, with the prediction as text,
//! JSON and, on request, a heat map of the AoA σ over the active area.
//!
//! The nominal model is the pinhole of `f` (centre at the electrical
//! centre, no distortion) with `--set` assignments applied, or, for
//! `--next`, the calibration's model and poses (every LED of the template
//! assumed seen in each); the point noise is the default signal
//! chain's at the SNR (`psdcal simulate`'s chain); the freed parameters are
//! `--fit` (default `f, cx, cy, k1, k2`) or the calibration's.

use std::path::{Path, PathBuf};

use psdcal_calib::plan::{self, Objective, Plan, PlanOptions, PlanSetup, PoseRanges};
use psdcal_io::{write_poses, PoseRow, Template};
use psdcal_model::{ChannelGains, CostKind, Model, Param, PsdGeometry, SensorModel};
use psdcal_report::{heat_map_png, heat_map_svg, Frame, HeatCell};
use serde_json::json;

use crate::answer::loaded_sensor::LoadedSensor;
use crate::base::error::{Error, Result};
use crate::base::option_text::FitList;
use crate::simulation::simulate::{chain_with_record, DEFAULT_RECORD_CYCLES};
use psdcal_model::stages::{with_aspect, Aspect};

/// What to plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    /// Nominal focal length, mm (required without `next`).
    pub f_mm: Option<f64>,
    /// template.csv.
    pub template: PathBuf,
    /// Per-channel SNR, dB.
    pub snr_db: f64,
    /// Number of poses (ignored with `next`: one).
    pub images: usize,
    /// Active area (ignored with `next`: the calibration's).
    pub geometry: PsdGeometry,
    /// Distance range of the template's centre, mm.
    pub distance_mm: Option<(f64, f64)>,
    /// Largest tilt, degrees.
    pub tilt_max_deg: f64,
    /// Margin of every LED inside the active area, mm.
    pub margin_mm: f64,
    /// Freed parameters and whether the gains are freed too (`None`: the
    /// calibration default, or the calibration's with `next`).
    pub fit: Option<FitList>,
    /// Nominal values of other parameters (`k1=…`).
    pub set: Vec<(Param, f64)>,
    /// Minimise the largest σ instead of the RMS.
    pub minimise_max: bool,
    /// Seed of the candidate poses.
    pub seed: u64,
    /// The current calibration: plan the one next pose.
    pub next: Option<PathBuf>,
    /// poses.csv to write.
    pub out: PathBuf,
    /// Folder for the heat map (plan_sigma.svg, plan_sigma.png).
    pub report: Option<PathBuf>,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
    /// Replace files in the report folder that psdcal did not write there.
    pub force: bool,
}

/// A plan with its printable forms.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The plan.
    pub plan: Plan,
    /// The summary for people.
    pub text: String,
    /// The summary as JSON.
    pub json: serde_json::Value,
}

fn setup(request: &PlanRequest) -> Result<(PlanSetup, Option<LoadedSensor>)> {
    let template = Template::read_with(&request.template, request.limits)?;
    let leds = template
        .leds
        .iter()
        .map(|l| nalgebra::Vector2::new(l.x_mm, l.y_mm))
        .collect();
    let snr = request.snr_db;
    let relative_noise = chain_with_record(DEFAULT_RECORD_CYCLES)?
        .amplitude_std(1.0, snr)
        .map_err(|e| Error::Options(format!("--snr {snr}: {e}")))?;
    let (mut sensor, geometry, loaded) = match &request.next {
        Some(path) => {
            let loaded = LoadedSensor::read_with(path, request.limits)?;
            (loaded.sensor.model, loaded.sensor.geometry, Some(loaded))
        }
        None => {
            let f = request.f_mm.ok_or_else(|| {
                Error::Options(
                    "give the nominal focal length with --f MM (or --next --calibration FILE)"
                        .into(),
                )
            })?;
            (SensorModel::pinhole(f, 0.0, 0.0), request.geometry, None)
        }
    };
    for (p, v) in &request.set {
        sensor.set(*p, *v);
    }
    let gains = psdcal_model::stages::gains::GAIN_NAMES;
    let free: Vec<String> = match (&request.fit, &loaded) {
        (Some(fit), _) => fit
            .params
            .iter()
            .map(|p| p.name())
            .chain(gains.into_iter().filter(|_| fit.gains))
            .chain(Some(Aspect::NAME).filter(|_| fit.aspect))
            .map(str::to_string)
            .collect(),
        (None, Some(l)) => {
            let names = l.sensor.covariance.names();
            let standard = names.iter().filter(|n| n.parse::<Param>().is_ok());
            let fitted = names
                .iter()
                .filter(|n| gains.contains(&n.as_str()) || n.as_str() == Aspect::NAME);
            standard.chain(fitted).cloned().collect()
        }
        (None, None) => psdcal_calib::RefineOptions::default().free_names(),
    };
    if free.is_empty() {
        return Err(Error::Options(
            "the calibration estimated none of the sensor's parameters; give --fit".into(),
        ));
    }
    let model = if free.iter().any(|n| gains.contains(&n.as_str())) {
        let nominal = loaded.as_ref().and_then(|l| l.sensor.gains);
        Model::standard_with_gains(&sensor, geometry, &nominal.unwrap_or(ChannelGains::UNIT))
    } else {
        Model::standard(&sensor)
    };
    let model = if free.iter().any(|n| n == Aspect::NAME) {
        let a = loaded.as_ref().and_then(|l| l.sensor.aspect).unwrap_or(0.0);
        with_aspect(&model, a)?
    } else {
        model
    };
    model.validate()?;
    Ok((
        PlanSetup {
            model,
            template: leds,
            geometry,
            free,
            cost: CostKind::Template,
            relative_noise,
        },
        loaded,
    ))
}

/// Plans, writes poses.csv (and the heat map), and returns the summary.
pub fn plan_poses(request: &PlanRequest) -> Result<Planned> {
    let mut inputs: Vec<(&str, &Path)> = vec![("--template", &request.template)];
    if let Some(c) = &request.next {
        inputs.push(("--calibration", c));
    }
    psdcal_io::refuse_overwrite(&inputs, &[("--out", &request.out)])?;
    let (setup, loaded) = setup(request)?;
    let options = PlanOptions {
        images: request.images,
        ranges: PoseRanges {
            distance_mm: request.distance_mm,
            tilt_max: request.tilt_max_deg.to_radians(),
            margin_mm: request.margin_mm,
        },
        seed: request.seed,
        objective: if request.minimise_max {
            Objective::Max
        } else {
            Objective::Rms
        },
        ..PlanOptions::default()
    };
    let plan = match &loaded {
        Some(l) => {
            let taken: Vec<psdcal_model::Pose> = l
                .record
                .images
                .iter()
                .map(|i| psdcal_model::Pose::new(i.rvec.into(), i.t_mm.into()))
                .collect();
            plan::plan_next(&setup, &options, &taken)?
        }
        None => plan::plan(&setup, &options)?,
    };
    let rows: Vec<PoseRow> = plan
        .poses
        .iter()
        .enumerate()
        .map(|(i, c)| PoseRow {
            line_no: 0,
            image: format!("{}", i + 1),
            rvec: c.pose.rvec.into(),
            t_mm: c.pose.t.into(),
        })
        .collect();
    let comment = format!(
        "psdcal plan: {} pose(s), seed {}; predicted AoA sigma RMS {:.5} deg, max {:.5} deg",
        rows.len(),
        request.seed,
        plan.prediction.rms.to_degrees(),
        plan.prediction.max.to_degrees()
    );
    write_poses(&request.out, &comment, &rows)?;
    if let Some(dir) = &request.report {
        write_heat_map(dir, &setup, &plan, request.force)?;
    }
    Ok(Planned {
        text: text(request, &setup, &plan),
        json: summary_json(request, &setup, &plan),
        plan,
    })
}

fn write_heat_map(dir: &Path, setup: &PlanSetup, plan: &Plan, force: bool) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
        path: dir.to_path_buf(),
        message: format!("cannot create the report folder {}: {e}", dir.display()),
    })?;
    let names = ["plan_sigma.svg".to_string(), "plan_sigma.png".to_string()];
    let folder = psdcal_io::OutputFolder::claim(dir, &names, force)?;
    let p = &plan.prediction;
    let cells: Vec<HeatCell> = p
        .grid
        .iter()
        .zip(&p.sigma)
        .map(|(m, s)| HeatCell {
            x: m.x,
            y: m.y,
            value: s.to_degrees(),
        })
        .collect();
    let n = (p.grid.len() as f64).sqrt().round().max(1.0);
    let (lx, ly) = (setup.geometry.lx, setup.geometry.ly);
    let frame = Frame::new(
        "Predicted AoA σ over the active area",
        "x (mm)",
        "y (mm)",
        (-0.5 * lx, 0.5 * lx),
        (-0.5 * ly, 0.5 * ly),
    );
    let size = (lx / n, ly / n);
    let svg = heat_map_svg(&cells, size, &frame, "AoA σ (°)")?;
    psdcal_io::write_atomic_bytes(dir.join("plan_sigma.svg"), svg.as_bytes())?;
    psdcal_io::write_atomic_at(dir.join("plan_sigma.png"), |tmp| {
        heat_map_png(&cells, size, &frame, "AoA σ (°)", tmp)
    })?;
    Ok(folder.finish()?)
}

fn text(request: &PlanRequest, setup: &PlanSetup, plan: &Plan) -> String {
    let p = &plan.prediction;
    let mut out = String::new();
    if let Some((rms, max)) = plan.before {
        out += &format!(
            "now: predicted AoA sigma RMS {:.5} deg, max {:.5} deg\n",
            rms.to_degrees(),
            max.to_degrees()
        );
    }
    out += &format!(
        "{} pose(s) chosen from {} candidates (seed {}); predicted AoA sigma over the active area: RMS {:.5} deg, max {:.5} deg\n",
        plan.poses.len(),
        plan.candidates,
        request.seed,
        p.rms.to_degrees(),
        p.max.to_degrees()
    );
    for (i, c) in plan.poses.iter().enumerate() {
        out += &format!(
            "  pose {}: distance {:.0} mm, tilt {:.1} deg, t = ({:.1}, {:.1}, {:.1}) mm\n",
            i + 1,
            c.distance_mm,
            c.tilt.to_degrees(),
            c.pose.t.x,
            c.pose.t.y,
            c.pose.t.z
        );
    }
    let sigmas: Vec<String> = setup
        .free
        .iter()
        .filter_map(|n| p.covariance.std(n).map(|s| format!("{n} ±{s:.3e}")))
        .collect();
    out += &format!("predicted parameter sigma: {}\n", sigmas.join(", "));
    out += &format!("wrote {}", request.out.display());
    if let Some(dir) = &request.report {
        out += &format!(
            ", {}/plan_sigma.svg, {}/plan_sigma.png",
            dir.display(),
            dir.display()
        );
    }
    out
}

fn summary_json(request: &PlanRequest, setup: &PlanSetup, plan: &Plan) -> serde_json::Value {
    let p = &plan.prediction;
    let poses: Vec<_> = plan
        .poses
        .iter()
        .enumerate()
        .map(|(i, c)| {
            json!({
                "image": format!("{}", i + 1),
                "rvec": [c.pose.rvec.x, c.pose.rvec.y, c.pose.rvec.z],
                "t_mm": [c.pose.t.x, c.pose.t.y, c.pose.t.z],
                "distance_mm": c.distance_mm,
                "tilt_deg": c.tilt.to_degrees(),
            })
        })
        .collect();
    let sigma: serde_json::Map<String, serde_json::Value> = setup
        .free
        .iter()
        .filter_map(|n| p.covariance.std(n).map(|s| (n.clone(), json!(s))))
        .collect();
    json!({
        "out": request.out.display().to_string(),
        "candidates": plan.candidates,
        "seed": request.seed,
        "poses": poses,
        "aoa_sigma_deg": { "rms": p.rms.to_degrees(), "max": p.max.to_degrees() },
        "before_aoa_sigma_deg": plan.before.map(|(r, m)| json!({ "rms": r.to_degrees(), "max": m.to_degrees() })),
        "parameter_sigma": sigma,
    })
}
