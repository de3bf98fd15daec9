//! `psdcal evaluate`: estimated positions (and angles) against a surveyed
//! truth by the standard metrics (psdcal-locate's `evaluate`: mean, median,
//! RMS, 75th/95th percentiles, CE95/SE95, bias, the fraction of truths inside
//! the 95 % covariance ellipsoid), as text, JSON and an HTML page.
//!
//! Inputs: truth.csv and the estimates (psdcal-io's `positioning`: the CSV
//! `psdcal locate` or `psdcal aoa` writes), matched by `emitter`. Estimates
//! that were not answered (a failure status, empty values) are failures:
//! counted, reported as the success rate, and entered as infinite errors in
//! the failure-inclusive percentiles (psdcal-locate's `with_failures`); the
//! mean, RMS and bias are over the located emitters. With a rig file, the page plots the error
//! against the distance to the nearest sensor; otherwise against the
//! distance from the frame's origin.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use psdcal_io::{write_atomic_bytes, PositionEstimates, PositionTruth, RigFile};
use psdcal_locate::{
    evaluate_angles, evaluate_positions, with_failures, AngleEvaluation, AnglePair, ErrorStats,
    FailureStats, PositionEvaluation, PositionPair,
};
use psdcal_report::{evaluation_page, EvaluationReport, Table};
use serde_json::{json, Value};

use crate::base::error::{Error, Result};

/// What to evaluate.
#[derive(Debug, Clone, PartialEq)]
pub struct EvaluateRequest {
    /// truth.csv.
    pub truth: PathBuf,
    /// The estimates (the CSV of `psdcal locate` or `psdcal aoa`).
    pub estimates: PathBuf,
    /// A rig file: the page plots the error against the distance to the
    /// nearest sensor.
    pub rig: Option<PathBuf>,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
}

/// The evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// truth.csv, as named.
    pub truth: String,
    /// The estimates, as named.
    pub estimates: String,
    /// The frame of the estimated positions (`world`, `sensor`, or empty).
    pub frame: Option<String>,
    /// Positions compared (when both files give positions).
    pub positions: Option<PositionEvaluation>,
    /// Angles compared (when both files give angles).
    pub angles: Option<AngleEvaluation>,
    /// Emitters the estimates did not answer, with their status.
    pub not_located: Vec<(String, String)>,
    /// The position statistics counting the truths without an estimated
    /// position as failures (with positions).
    pub position_failures: Option<FailureStats>,
    /// The same for angles (with angles).
    pub angle_failures: Option<FailureStats>,
    /// CE95 with the failures as infinite horizontal errors (`None`:
    /// infinite), with positions.
    pub ce95_with_failures: Option<f64>,
    /// The true positions of the compared emitters, mm (positions only).
    pub true_positions: Vec<Vector3<f64>>,
    /// Each compared emitter's distance to the nearest sensor (or the
    /// origin), mm.
    pub distances_mm: Vec<f64>,
    /// What the distances are measured from.
    pub distance_from: String,
}

/// Reads both files, matches them and computes the metrics.
pub fn evaluate(request: &EvaluateRequest) -> Result<Evaluation> {
    let truth = PositionTruth::read_with(&request.truth, request.limits)?;
    let estimates = PositionEstimates::read_with(&request.estimates, request.limits)?;
    let matched = estimates.matched(&truth)?;
    let sensors: Option<Vec<Vector3<f64>>> = match &request.rig {
        Some(path) => Some(
            RigFile::read_with(path, request.limits)?
                .sensors
                .iter()
                .map(|s| s.world_from_sensor.t)
                .collect(),
        ),
        None => None,
    };
    let mut not_located = Vec::new();
    let mut positions = Vec::new();
    let mut true_positions = Vec::new();
    let mut angles = Vec::new();
    let (mut missing_positions, mut missing_angles) = (0usize, 0usize);
    for m in &matched {
        let e = m.estimate;
        missing_positions += usize::from(m.truth.position.is_some() && e.position.is_none());
        missing_angles += usize::from(m.truth.alpha.is_some() && e.alpha.is_none());
        if e.position.is_none() && e.alpha.is_none() {
            not_located.push((e.emitter.clone(), e.status.clone()));
            continue;
        }
        if let (Some(t), Some(p)) = (m.truth.position, e.position) {
            positions.push(PositionPair {
                truth: t,
                estimate: p,
                covariance: e.position_covariance,
            });
            true_positions.push(t);
        }
        if let (Some(t), Some(a)) = (m.truth.alpha, e.alpha) {
            angles.push(AnglePair {
                truth: t,
                estimate: a,
                covariance: e.alpha_covariance,
            });
        }
    }
    if positions.is_empty() && angles.is_empty() {
        return Err(Error::Input(format!(
            "nothing to compare: {} and {} share no located emitter with a position (x_mm, \
             y_mm, z_mm) or angles (alpha_x_deg, alpha_y_deg) in both; {} emitter(s) were not \
             located",
            truth.source,
            estimates.source,
            not_located.len()
        )));
    }
    let distance_from = if sensors.is_some() {
        "the nearest sensor"
    } else {
        "the origin"
    };
    let distances_mm = true_positions
        .iter()
        .map(|t| match &sensors {
            Some(s) => s
                .iter()
                .map(|c| (t - c).norm())
                .fold(f64::INFINITY, f64::min),
            None => t.norm(),
        })
        .collect();
    let positions = (!positions.is_empty())
        .then(|| evaluate_positions(&positions))
        .transpose()?;
    let angles = (!angles.is_empty())
        .then(|| evaluate_angles(&angles))
        .transpose()?;
    let position_failures = positions.as_ref().and_then(|p| {
        let d: Vec<f64> = p.errors.iter().map(|e| e.norm()).collect();
        with_failures(&d, missing_positions)
    });
    let ce95_with_failures = positions.as_ref().and_then(|p| {
        let mut h: Vec<f64> = p.errors.iter().map(|e| e.x.hypot(e.y)).collect();
        h.sort_by(f64::total_cmp);
        psdcal_locate::percentile_with_failures(&h, missing_positions, 0.95)
    });
    let angle_failures = angles.as_ref().and_then(|a| {
        let d: Vec<f64> = a.errors.iter().map(|e| e.norm()).collect();
        with_failures(&d, missing_angles)
    });
    Ok(Evaluation {
        truth: truth.source.clone(),
        estimates: estimates.source.clone(),
        frame: estimates.frame.clone(),
        positions,
        angles,
        not_located,
        position_failures,
        angle_failures,
        ce95_with_failures,
        true_positions,
        distances_mm,
        distance_from: distance_from.to_string(),
    })
}

fn stats_json(
    s: &ErrorStats,
    unit: &str,
    scale: f64,
    within: &str,
) -> serde_json::Map<String, Value> {
    let mut m = serde_json::Map::new();
    m.insert("n".into(), json!(s.n));
    for (k, v) in [
        ("mean", s.mean),
        ("median", s.median),
        ("rms", s.rms),
        ("p75", s.p75),
        ("p95", s.p95),
        ("max", s.max),
    ] {
        m.insert(format!("{k}_{unit}"), json!(v * scale));
    }
    m.insert(
        format!("bias_{unit}"),
        json!(s.bias.iter().map(|b| b * scale).collect::<Vec<_>>()),
    );
    m.insert(within.into(), json!(s.within_95));
    m
}

/// The failure-aware keys (`attempted`, `success_rate`,
/// `median_with_failures_…`, …; `null`: infinite).
fn failures_json(f: &FailureStats, unit: &str, scale: f64, m: &mut serde_json::Map<String, Value>) {
    m.insert("attempted".into(), json!(f.attempted));
    m.insert("failures".into(), json!(f.failures));
    m.insert("success_rate".into(), json!(f.success_rate));
    for (k, v) in [("median", f.median), ("p75", f.p75), ("p95", f.p95)] {
        m.insert(
            format!("{k}_with_failures_{unit}"),
            json!(v.map(|v| v * scale)),
        );
    }
}

impl Evaluation {
    /// Warnings: emitters that were not located.
    pub fn warnings(&self) -> Vec<String> {
        if self.not_located.is_empty() {
            return Vec::new();
        }
        let first: Vec<String> = self
            .not_located
            .iter()
            .take(10)
            .map(|(id, status)| format!("{id} ({status})"))
            .collect();
        vec![format!(
            "{}: {} emitter(s) not located, counted as failures (success rate and the \
             percentiles with failures; mean, RMS and bias are over the located ones): {}{}",
            self.estimates,
            self.not_located.len(),
            first.join(", "),
            if self.not_located.len() > 10 {
                ", …"
            } else {
                ""
            }
        )]
    }

    /// The metrics as JSON: the position metrics at the top level (`n`,
    /// `mean_mm`, `median_mm`, `rms_mm`, `p75_mm`, `p95_mm`, `max_mm`,
    /// `bias_mm`, `within_95_ellipsoid`, `ce95_mm`, `se95_mm`), the angle
    /// metrics under `angles` (degrees, `within_95_ellipse`); with each,
    /// the failures: `attempted`, `failures`, `success_rate`,
    /// `median_with_failures_mm`, `p75_with_failures_mm`,
    /// `p95_with_failures_mm`, `ce95_with_failures_mm` (`null`: infinite,
    /// the failures reach the percentile).
    pub fn to_json(&self) -> Value {
        let mut m = serde_json::Map::new();
        m.insert("command".into(), json!("evaluate"));
        m.insert("truth".into(), json!(self.truth));
        m.insert("estimates".into(), json!(self.estimates));
        m.insert("frame".into(), json!(self.frame));
        m.insert("not_located".into(), json!(self.not_located.len()));
        if let Some(p) = &self.positions {
            m.extend(stats_json(&p.stats, "mm", 1.0, "within_95_ellipsoid"));
            m.insert("ce95_mm".into(), json!(p.ce95));
            m.insert("se95_mm".into(), json!(p.se95));
            if let Some(f) = &self.position_failures {
                failures_json(f, "mm", 1.0, &mut m);
                m.insert(
                    "ce95_with_failures_mm".into(),
                    json!(self.ce95_with_failures),
                );
            }
        }
        if let Some(a) = &self.angles {
            let mut am = stats_json(&a.stats, "deg", 1f64.to_degrees(), "within_95_ellipse");
            if let Some(f) = &self.angle_failures {
                failures_json(f, "deg", 1f64.to_degrees(), &mut am);
            }
            m.insert("angles".into(), Value::Object(am));
        }
        Value::Object(m)
    }

    /// The metrics as rows `(metric, value)` in words and units.
    fn rows(&self) -> Vec<(String, Vec<[String; 2]>)> {
        let mut out = Vec::new();
        let f = |v: f64, unit: &str| format!("{} {unit}", psdcal_report::num(v));
        let g = |v: Option<f64>, unit: &str, k: f64| {
            v.map_or("infinite (too many failures)".to_string(), |v| {
                f(k * v, unit)
            })
        };
        let failures = |fs: &Option<FailureStats>, unit: &str, k: f64| -> Vec<[String; 2]> {
            let Some(fs) = fs else { return Vec::new() };
            vec![
                [
                    "located / attempted (success rate)".to_string(),
                    format!(
                        "{} / {} ({:.1} %)",
                        fs.attempted - fs.failures,
                        fs.attempted,
                        100.0 * fs.success_rate
                    ),
                ],
                ["median, failures as infinite".into(), g(fs.median, unit, k)],
                [
                    "75th percentile, failures as infinite".into(),
                    g(fs.p75, unit, k),
                ],
                [
                    "95th percentile, failures as infinite".into(),
                    g(fs.p95, unit, k),
                ],
            ]
        };
        let common = |s: &ErrorStats, unit: &str, k: f64, axes: &[&str]| {
            let mut rows = vec![
                ["emitters compared (located)".to_string(), s.n.to_string()],
                ["mean error".into(), f(k * s.mean, unit)],
                ["median error".into(), f(k * s.median, unit)],
                ["RMS error".into(), f(k * s.rms, unit)],
                ["75th percentile (EvAAL score)".into(), f(k * s.p75, unit)],
                ["95th percentile".into(), f(k * s.p95, unit)],
                ["largest error".into(), f(k * s.max, unit)],
            ];
            for (axis, b) in axes.iter().zip(&s.bias) {
                rows.push([format!("bias in {axis}"), f(k * b, unit)]);
            }
            rows
        };
        if let Some(p) = &self.positions {
            let mut rows = common(&p.stats, "mm", 1.0, &["x", "y", "z"]);
            rows.insert(6, ["CE95 (horizontal, 95 %)".into(), f(p.ce95, "mm")]);
            rows.insert(7, ["SE95 (3-D, 95 %)".into(), f(p.se95, "mm")]);
            rows.extend(failures(&self.position_failures, "mm", 1.0));
            if self
                .position_failures
                .as_ref()
                .is_some_and(|f| f.failures > 0)
            {
                rows.push([
                    "CE95, failures as infinite".into(),
                    g(self.ce95_with_failures, "mm", 1.0),
                ]);
            }
            rows.push([
                "truths inside the 95 % ellipsoid".into(),
                p.stats
                    .within_95
                    .map_or("no covariance given".into(), within_text),
            ]);
            out.push(("Position error".to_string(), rows));
        }
        if let Some(a) = &self.angles {
            let mut rows = common(&a.stats, "°", 1f64.to_degrees(), &["αx", "αy"]);
            rows.extend(failures(&self.angle_failures, "°", 1f64.to_degrees()));
            rows.push([
                "truths inside the 95 % ellipse".into(),
                a.stats
                    .within_95
                    .map_or("no covariance given".into(), within_text),
            ]);
            out.push(("Angle-of-arrival error".to_string(), rows));
        }
        out
    }

    /// The summary, with the report's `files` (the page first) when one
    /// was written.
    pub fn summary(&self, files: &[PathBuf]) -> crate::base::summary::Summary {
        let mut json = self.to_json();
        json["report"] = json!(files.first().map(|f| f.display().to_string()));
        let mut text = self.text();
        if let Some(page) = files.first() {
            text.push_str(&format!(
                "wrote {} and {} figures\n",
                page.display(),
                files.len() - 1
            ));
        }
        crate::base::summary::Summary::new(text, json).warn(self.warnings())
    }

    /// The metrics as text, one per line.
    pub fn text(&self) -> String {
        let mut out = format!("evaluate: {} against {}\n", self.estimates, self.truth);
        for (title, rows) in self.rows() {
            out.push_str(&format!("{title}:\n"));
            for [k, v] in rows {
                out.push_str(&format!("  {k:<34} {v}\n"));
            }
        }
        out
    }

    /// Writes `evaluation.html` and its figures (SVG) into `dir` (created if
    /// missing), replacing only files psdcal wrote there unless `force`
    /// ([`psdcal_io::OutputFolder`]); returns the files written.
    pub fn write_report(&self, dir: &Path, force: bool) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
            path: dir.to_path_buf(),
            message: format!("cannot create the output folder {}: {e}", dir.display()),
        })?;
        let (floor, horizontal_errors, errors_mm) = match &self.positions {
            Some(p) => (
                self.true_positions.iter().map(|t| (t.x, t.y)).collect(),
                p.errors.iter().map(|e| (e.x, e.y)).collect(),
                p.errors.iter().map(|e| e.norm()).collect(),
            ),
            None => (Vec::new(), Vec::new(), Vec::new()),
        };
        let frame = match self.frame.as_deref() {
            Some("") | None => String::new(),
            Some(f) => format!(" ({f} frame)"),
        };
        let report = EvaluationReport {
            title: "Positioning evaluation".into(),
            intro: vec![format!(
                "Estimates {}{frame} against the truth {}, matched by emitter. Percentiles \
                 interpolate linearly between the sorted errors.",
                self.estimates, self.truth
            )],
            warnings: self.warnings(),
            tables: self
                .rows()
                .into_iter()
                .map(|(caption, rows)| Table {
                    caption,
                    headers: vec!["metric".into(), "value".into()],
                    rows: rows.into_iter().map(|r| r.to_vec()).collect(),
                })
                .collect(),
            floor,
            horizontal_errors,
            errors_mm,
            distances_mm: self.distances_mm.clone(),
            distance_from: self.distance_from.clone(),
        };
        let (page, svgs) = evaluation_page(&report)?;
        let names: Vec<String> = std::iter::once("evaluation.html".to_string())
            .chain(svgs.iter().map(|(name, _)| format!("{name}.svg")))
            .collect();
        let folder = psdcal_io::OutputFolder::claim(dir, &names, force)?;
        let html = dir.join("evaluation.html");
        write_atomic_bytes(&html, page.render().as_bytes())?;
        let mut files = vec![html];
        for (name, svg) in svgs {
            let path = dir.join(format!("{name}.svg"));
            write_atomic_bytes(&path, svg.as_bytes())?;
            files.push(path);
        }
        folder.finish()?;
        Ok(files)
    }
}

/// The fraction of truths inside their 95 % region, in words: every emitter
/// located with one calibration shares its error, so one rig's fraction is
/// one draw (near 100 % or far below are both normal); 95 % is what many
/// calibrations give on average (docs/positioning.md).
fn within_text(fraction: f64) -> String {
    format!(
        "{:.1} % (one shared calibration error: near 100 % or far below is normal for one rig; \
         95 % on average over many calibrations)",
        100.0 * fraction
    )
}
