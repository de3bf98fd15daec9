//! The tables of a calibration report: sources, parameters ± σ, the fit
//! summary, the per-image poses and the residuals recomputed from the data.

use std::path::Path;

use psdcal_io::Calibration;
use psdcal_model::{Param, SensorModel};
use psdcal_report::{CalibrationReport, Plot, Table};

use crate::report::ReportRequest;
use crate::residuals::ResidualTable;

/// Per image: residuals recomputed from the data.
pub(crate) fn residual_rows(table: &ResidualTable) -> Table {
    let rms = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.4}"));
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

/// The report's content from its tables and plots.
pub(crate) fn tables(
    request: &ReportRequest,
    calibration: &Calibration,
    model: &SensorModel,
    plots: Vec<Plot>,
    recomputed: Option<Table>,
) -> CalibrationReport {
    let file_name = |p: &Path| p.display().to_string();
    let short = request.calibration.file_name().map_or_else(
        || file_name(&request.calibration),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut sources = vec![format!("calibration: {}", file_name(&request.calibration))];
    if let Some((t, o)) = &request.data {
        sources.push(format!("template: {}", file_name(t)));
        sources.push(format!("observations: {}", file_name(o)));
    }
    sources.push(format!(
        "written by {} {}; sensor {} × {} mm",
        calibration.software.name,
        calibration.software.version,
        calibration.sensor.lx_mm,
        calibration.sensor.ly_mm
    ));
    let parameters = Table {
        caption: "Model parameters ± one standard deviation".into(),
        headers: ["parameter", "value", "σ", "unit", ""]
            .map(String::from)
            .to_vec(),
        rows: Param::ALL
            .iter()
            .map(|p| {
                let name = p.name();
                vec![
                    name.to_string(),
                    format!("{:.6e}", model.get(*p)),
                    calibration
                        .std
                        .get(name)
                        .map_or("–".into(), |s| format!("{s:.3e}")),
                    p.unit().to_string(),
                    if calibration.estimated.contains(p) {
                        "estimated"
                    } else {
                        "fixed"
                    }
                    .to_string(),
                ]
            })
            .collect(),
    };
    let fit = &calibration.fit;
    let fit = Table {
        caption: "Fit summary".into(),
        headers: vec!["".into(), "value".into()],
        rows: vec![
            vec!["cost".into(), format!("{:?}", fit.cost)],
            vec!["residual (mm²)".into(), format!("{:.6e}", fit.residual_mm2)],
            vec![
                "RMS template-plane error (mm)".into(),
                format!("{:.4e}", fit.rms_template_mm),
            ],
            vec![
                "RMS image error (mm)".into(),
                format!("{:.4e}", fit.rms_image_mm),
            ],
            vec!["iterations".into(), fit.iterations.to_string()],
            vec!["points".into(), fit.points.to_string()],
            vec!["images".into(), fit.images.to_string()],
            vec!["termination".into(), fit.termination.clone()],
        ],
    };
    let images = Table {
        caption: "Per image: fitted pose and RMS error".into(),
        headers: ["image", "points", "RMS (mm)", "t (mm)", "rvec (rad)"]
            .map(String::from)
            .to_vec(),
        rows: calibration
            .images
            .iter()
            .map(|i| {
                vec![
                    i.id.clone(),
                    i.points.to_string(),
                    format!("{:.4e}", i.rms_mm),
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
        fit,
        plots,
        images,
        recomputed,
        diagnostics: calibration
            .diagnostics
            .iter()
            .map(|d| format!("{} ({}): {}", d.code, d.severity.as_str(), d.message))
            .collect(),
    }
}
