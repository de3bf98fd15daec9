//! The tables of a calibration report: sources, parameters ± σ, the fit
//! summary, the per-image poses and the residuals recomputed from the data.

use std::path::{Path, PathBuf};

use psdcal_io::{Calibration, CostKind, Template};
use psdcal_model::{Param, SensorModel};
use psdcal_report::{num, value_with_sigma, CalibrationReport, Plot, Table};

use crate::calibration::residuals::ResidualTable;
use crate::reports::choice_table::choice_table;

/// How many points the worst-points table lists.
pub(crate) const WORST_POINTS: usize = 10;

/// A parameter in words.
fn plain_name(p: Param) -> String {
    let what = match p {
        Param::F => "focal length",
        Param::Cx | Param::Cy => "optical centre",
        Param::Skew => "skew",
        Param::K1 | Param::K2 | Param::K3 => "lens radial distortion",
        Param::P1 | Param::P2 => "lens tangential distortion",
        Param::L1 | Param::L2 => "PSD radial distortion",
    };
    format!("{what} {}", p.name())
}

/// The solver's termination in words.
fn plain_termination(code: &str) -> String {
    match code {
        "ExactFit" => "exact fit (noise-free data)".into(),
        "CostConverged" => "converged: the cost stopped falling".into(),
        "StepConverged" => "converged: the steps became negligible".into(),
        "DampingSaturated" => "converged to the precision of the arithmetic".into(),
        "MaxIterations" => "stopped: the iteration budget ran out (not converged)".into(),
        other => other.to_string(),
    }
}

/// The points with the largest sensor residuals (at most [`WORST_POINTS`]).
pub(crate) fn worst_points(table: &ResidualTable, template: &Template) -> Table {
    let mut all: Vec<(f64, &str, &str, f64)> = table
        .images
        .iter()
        .filter_map(|im| Some((im, im.residuals.as_ref()?)))
        .flat_map(|(im, r)| {
            r.iter().filter_map(move |p| {
                let s = p.on_sensor?.norm();
                let t = p.on_template.map_or(f64::NAN, |t| t.norm());
                let led = template.leds.get(p.led).map_or("?", |l| l.id.as_str());
                Some((s, im.id.as_str(), led, t))
            })
        })
        .collect();
    all.sort_by(|a, b| b.0.total_cmp(&a.0));
    Table {
        caption: format!(
            "The {} points with the largest residuals on the sensor",
            all.len().min(WORST_POINTS)
        ),
        headers: ["image", "LED", "sensor residual", "template-plane residual"]
            .map(String::from)
            .to_vec(),
        rows: all
            .iter()
            .take(WORST_POINTS)
            .map(|(s, image, led, t)| {
                vec![
                    image.to_string(),
                    led.to_string(),
                    format!("{} µm", num(1e3 * s)),
                    if t.is_finite() {
                        format!("{} mm", num(*t))
                    } else {
                        "–".into()
                    },
                ]
            })
            .collect(),
    }
}

/// The provenance table of a version-2 calibration.
fn provenance(calibration: &Calibration) -> Option<Table> {
    calibration.provenance.as_ref().map(provenance_table)
}

/// A provenance record (calibration.json's, psd_map.json's) as a table.
pub(crate) fn provenance_table(p: &psdcal_io::Provenance) -> Table {
    let mut rows = vec![
        vec!["psdcal version".into(), p.psdcal_version.clone()],
        vec!["command".into(), p.command.clone()],
        vec!["written (UTC)".into(), p.created_utc.clone()],
    ];
    for input in &p.inputs {
        rows.push(vec![
            format!("input {}", input.path),
            format!("SHA-256 {}", input.sha256),
        ]);
    }
    Table {
        caption: "Provenance".into(),
        headers: vec!["".into(), "".into()],
        rows,
    }
}

/// The correlation matrix of the calibration's covariance.
fn correlation(calibration: &Calibration) -> Option<(Vec<String>, Vec<Vec<f64>>)> {
    let c = &calibration.covariance;
    if c.parameters.is_empty() {
        return None;
    }
    let sd: Vec<f64> = (0..c.parameters.len())
        .map(|i| c.matrix[i][i].max(0.0).sqrt())
        .collect();
    let rows = (0..sd.len())
        .map(|i| {
            (0..sd.len())
                .map(|j| {
                    let d = sd[i] * sd[j];
                    if d > 0.0 {
                        c.matrix[i][j] / d
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        })
        .collect();
    Some((c.parameters.clone(), rows))
}

/// Per image: residuals recomputed from the data.
pub(crate) fn residual_rows(table: &ResidualTable) -> Table {
    let rms = |v: Option<f64>| v.map_or("–".to_string(), num);
    Table {
        caption: "Per image: residuals recomputed from the data".into(),
        headers: [
            "image",
            "points",
            "RMS template plane (mm)",
            "RMS sensor (mm)",
        ]
        .map(String::from)
        .to_vec(),
        rows: table
            .images
            .iter()
            .map(|image| match image.residuals {
                None => vec![
                    image.id.clone(),
                    image.points.to_string(),
                    "not in the calibration".into(),
                    "–".into(),
                ],
                Some(_) => {
                    let (t, s) = image.rms();
                    vec![image.id.clone(), image.points.to_string(), rms(t), rms(s)]
                }
            })
            .collect(),
    }
}

/// Where a report's content comes from: the calibration file's name and
/// the data files, and the calibration's software and sensor.
pub(crate) struct Sources {
    /// The calibration file's name (the page's title).
    pub short: String,
    /// One line per source.
    pub lines: Vec<String>,
}

impl Sources {
    /// The sources of a report of `calibration` read from
    /// `calibration_file`, with the calibration `data` files if given.
    pub(crate) fn new(
        calibration_file: &Path,
        data: Option<&(PathBuf, PathBuf)>,
        calibration: &Calibration,
    ) -> Self {
        let file_name = |p: &Path| p.display().to_string();
        let short = calibration_file.file_name().map_or_else(
            || file_name(calibration_file),
            |n| n.to_string_lossy().into_owned(),
        );
        let mut lines = vec![format!("calibration: {}", file_name(calibration_file))];
        if let Some((t, o)) = data {
            lines.push(format!("template: {}", file_name(t)));
            lines.push(format!("observations: {}", file_name(o)));
        }
        lines.push(format!(
            "written by {} {}; sensor {} × {} mm",
            calibration.software.name,
            calibration.software.version,
            calibration.sensor.lx_mm,
            calibration.sensor.ly_mm
        ));
        Self { short, lines }
    }
}

/// The report's content from its tables and plots.
pub(crate) fn tables(
    Sources {
        short,
        lines: sources,
    }: Sources,
    calibration: &Calibration,
    model: &SensorModel,
    plots: Vec<Plot>,
    recomputed: Option<Table>,
    worst: Option<Table>,
    warnings: Vec<String>,
) -> CalibrationReport {
    let parameters = Table {
        caption: "Model parameters ± one standard deviation (rounded by the σ)".into(),
        headers: ["parameter", "value", ""].map(String::from).to_vec(),
        rows: Param::ALL
            .iter()
            .filter(|p| calibration.estimated.contains(p) || model.get(**p) != 0.0)
            .map(|p| {
                let sigma = calibration.std.get(p.name());
                vec![
                    plain_name(*p),
                    value_with_sigma(model.get(*p), sigma, p.unit()),
                    if calibration.estimated.contains(p) {
                        "estimated"
                    } else {
                        "held fixed"
                    }
                    .to_string(),
                ]
            })
            .chain(calibration.aspect.map(|a| {
                let sigma = calibration.std.get("a");
                vec![
                    "y axis's own scale a (fy = f (1 + a))".to_string(),
                    value_with_sigma(a.a, sigma, "1"),
                    if a.estimated {
                        "estimated"
                    } else {
                        "held fixed"
                    }
                    .to_string(),
                ]
            }))
            .collect(),
    };
    let fit = &calibration.fit;
    let fit = Table {
        caption: "Fit summary".into(),
        headers: vec!["".into(), "value".into()],
        rows: vec![
            vec![
                "what was minimised".into(),
                match fit.cost {
                    CostKind::Template => "the error on the template plane (the paper's cost)",
                    CostKind::Image => "the reprojection error on the sensor",
                }
                .into(),
            ],
            vec![
                "sum of squared errors".into(),
                value_with_sigma(fit.residual_mm2, None, "mm^2"),
            ],
            vec![
                "RMS error on the template plane".into(),
                format!("{} mm", num(fit.rms_template_mm)),
            ],
            vec![
                "RMS error on the sensor".into(),
                format!("{} µm", num(1e3 * fit.rms_image_mm)),
            ],
            vec!["iterations".into(), fit.iterations.to_string()],
            vec!["points".into(), fit.points.to_string()],
            vec!["images".into(), fit.images.to_string()],
            vec!["outcome".into(), plain_termination(&fit.termination)],
        ],
    };
    let images = Table {
        caption: "Per image: fitted pose and RMS error".into(),
        headers: ["image", "points", "RMS error (µm)", "t (mm)", "rvec (rad)"]
            .map(String::from)
            .to_vec(),
        rows: calibration
            .images
            .iter()
            .map(|i| {
                vec![
                    i.id.clone(),
                    i.points.to_string(),
                    num(1e3 * i.rms_mm),
                    format!("{:.2}, {:.2}, {:.2}", i.t_mm[0], i.t_mm[1], i.t_mm[2]),
                    format!("{:.4}, {:.4}, {:.4}", i.rvec[0], i.rvec[1], i.rvec[2]),
                ]
            })
            .collect(),
    };
    CalibrationReport {
        title: format!("psdcal calibration report: {short}"),
        sources,
        parameters,
        model_choice: choice_table(calibration.fit.model_choice.as_ref()),
        fit,
        plots,
        images,
        recomputed,
        diagnostics: calibration
            .diagnostics
            .iter()
            .map(|d| format!("{} ({}): {}", d.code, d.severity.as_str(), d.message))
            .chain(warnings)
            .collect(),
        provenance: provenance(calibration),
        correlation: correlation(calibration),
        worst_points: worst,
    }
}
