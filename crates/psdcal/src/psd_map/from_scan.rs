//! `psdcal psd-map`: the PSD's non-linearity map from a lensless scan
//! (docs/model.md §8.3, scan.csv and psd_map.json in docs/formats.md):
//! read the scan, fit the map (psdcal-psdmap), build psd_map.json, its text
//! summary with a residual map, and write it (with, on request, its report:
//! `psd_map_report`); the scan's residuals per cell, for the reports and
//! calibration.json's `scan` summary.

use std::fmt::Write as _;
use std::path::PathBuf;

use nalgebra::Vector2;
use psdcal_io::{
    MapCandidateRecord, MapCoefficients, MapCovarianceRecord, MapFitRecord, MapResidualsRecord,
    PsdMapFile, PsdMapScanRecord, Scan, ScanResidualCells, SensorSize, PSD_MAP_FORMAT,
    PSD_MAP_VERSION,
};
use psdcal_model::stages::{MapBasis, PsdMap};
use psdcal_model::{ChannelGains, PsdGeometry, Stage};
use psdcal_psdmap::{fit_psd_map, residual_map, FitOptions, ModelChoice, PsdMapFit, ResidualCell};

use crate::base::error::{Error, Result};
use crate::base::provenance::{provenance, InputHashes};

/// Cells per side of the printed residual map.
pub const RESIDUAL_MAP_CELLS: usize = 6;

/// `auto`, `poly:N` or `spline:N` (`spline:NxM`) as a model choice.
pub fn parse_psd_map_model(text: &str) -> std::result::Result<ModelChoice, String> {
    if text.trim() == "auto" {
        return Ok(ModelChoice::Auto);
    }
    MapBasis::parse(text)
        .map(ModelChoice::Fixed)
        .ok_or_else(|| {
            format!(
                "'{text}' is not a map model; expected auto, poly:N (N = 0 to 12) or spline:N \
             (N = 1 to 20 cells per side)"
            )
        })
}

/// What `psd-map` is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub struct PsdMapRequest {
    /// scan.csv.
    pub scan: PathBuf,
    /// The model.
    pub model: ModelChoice,
    /// The sensor (for amplitudes, and the file's `sensor`).
    pub geometry: PsdGeometry,
    /// Seed of the cross-validation's folds.
    pub seed: u64,
    /// The command line, for the provenance.
    pub command: String,
    /// Folder for the report (psd_map.html with its figures), if asked.
    pub report: Option<PathBuf>,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
    /// Replace files in the report folder that psdcal did not write there.
    pub force: bool,
}

/// A fitted map as a file and its summary.
#[derive(Debug, Clone)]
pub struct PsdMapOutcome {
    /// psd_map.json's content.
    pub file: PsdMapFile,
    /// The fit.
    pub fit: PsdMapFit,
    /// The text summary (with the residual map).
    pub text: String,
    /// The scan read (an input the report must not overwrite).
    pub scan: PathBuf,
    /// Folder for the report, if asked.
    pub report: Option<PathBuf>,
    /// Replace files in the report folder that psdcal did not write there.
    pub force: bool,
}

/// The report page's file name in the report folder.
pub const PSD_MAP_PAGE: &str = "psd_map.html";

/// Cells per side of the scan's residual summary (the report's heat map,
/// calibration.json's `scan.residual_cells`).
pub const SCAN_SUMMARY_CELLS: usize = 10;

/// The residuals of psd_map.json's scan points, outliers left out, per
/// cell of `stage`'s frame ([`SCAN_SUMMARY_CELLS`] per side): the
/// non-empty cells.
pub(crate) fn residual_cells(file: &PsdMapFile, stage: &PsdMap) -> Vec<ResidualCell> {
    let r = &file.residuals;
    let kept: Vec<usize> = (0..r.x_mm.len())
        .filter(|i| !r.rejected.contains(i))
        .collect();
    let measured: Vec<Vector2<f64>> = kept
        .iter()
        .map(|&i| Vector2::new(r.x_mm[i], r.y_mm[i]))
        .collect();
    let residuals: Vec<Vector2<f64>> = kept
        .iter()
        .map(|&i| Vector2::new(r.dx_um[i], r.dy_um[i]) * 1e-3)
        .collect();
    residual_map(&stage.frame(), &measured, &residuals, SCAN_SUMMARY_CELLS)
        .into_iter()
        .filter(|c| c.points > 0)
        .collect()
}

/// calibration.json's summary of the scan a map was fitted to (its `fit`
/// and the residuals per cell).
pub(crate) fn scan_summary(file: &PsdMapFile, stage: &PsdMap) -> PsdMapScanRecord {
    let cells = residual_cells(file, stage);
    let column = |f: &dyn Fn(&ResidualCell) -> f64| cells.iter().map(f).collect::<Vec<f64>>();
    PsdMapScanRecord {
        model: file.model.clone(),
        fit: file.fit.clone(),
        residual_cells: ScanResidualCells {
            cells: SCAN_SUMMARY_CELLS,
            x_mm: column(&|c| c.centre.x),
            y_mm: column(&|c| c.centre.y),
            points: cells.iter().map(|c| c.points).collect(),
            dx_um: column(&|c| 1e3 * c.mean_mm.x),
            dy_um: column(&|c| 1e3 * c.mean_mm.y),
            rms_um: column(&|c| 1e3 * c.rms_mm),
        },
    }
}

/// Reads a scan and fits its map.
pub fn psd_map_from_scan(request: &PsdMapRequest) -> Result<PsdMapOutcome> {
    let mut inputs = InputHashes::default();
    let scan = inputs.read(&request.scan, |s, r| {
        Scan::from_reader_with(s, r, request.limits)
    })?;
    psd_map_of(&scan, &inputs, request)
}

/// Fits the map of a scan in memory (`request.scan` names it; `inputs`,
/// the files it was read from, for the provenance).
pub(crate) fn psd_map_of(
    scan: &Scan,
    inputs: &InputHashes,
    request: &PsdMapRequest,
) -> Result<PsdMapOutcome> {
    let points = scan.points(&request.geometry, &ChannelGains::UNIT)?;
    let options = FitOptions {
        model: request.model,
        seed: request.seed,
        ..FitOptions::default()
    };
    let fit = fit_psd_map(&points.stage, &points.measured, &options)
        .map_err(|e| Error::Input(format!("{}: {e}", points.source)))?;
    let um = |mm: f64| mm * 1e3;
    let k = fit.map.terms();
    let file = PsdMapFile {
        format: PSD_MAP_FORMAT.into(),
        version: PSD_MAP_VERSION,
        sensor: SensorSize {
            lx_mm: request.geometry.lx,
            ly_mm: request.geometry.ly,
        },
        model: fit.map.basis().label(),
        stage: fit.map.configuration(),
        coefficients: MapCoefficients {
            x: fit.block[..k].to_vec(),
            y: fit.block[k..].to_vec(),
        },
        covariance: MapCovarianceRecord {
            sigma_x_mm: fit.sigma_mm.x,
            sigma_y_mm: fit.sigma_mm.y,
            unit: (0..k)
                .map(|i| fit.unit_covariance.row(i).iter().copied().collect())
                .collect(),
        },
        fit: MapFitRecord {
            points: points.stage.len(),
            from_amplitudes: points.from_amplitudes,
            rejected_lines: fit.rejected.iter().map(|&i| points.lines[i]).collect(),
            folds: options.folds,
            cv_rms_um: um(fit.cv_rms_mm),
            rms_um: um(fit.rms_mm),
            sigma_x_um: um(fit.sigma_mm.x),
            sigma_y_um: um(fit.sigma_mm.y),
            map_sigma_um: um(fit.map_sigma_mm),
            effective_terms: fit.effective_terms,
            candidates: fit
                .candidates
                .iter()
                .map(|c| MapCandidateRecord {
                    model: c.basis.label(),
                    cv_rms_um: um(c.cv_rms_mm),
                })
                .collect(),
        },
        residuals: MapResidualsRecord {
            rejected: fit.rejected.clone(),
            x_mm: points.measured.iter().map(|p| p.x).collect(),
            y_mm: points.measured.iter().map(|p| p.y).collect(),
            dx_um: fit.residuals.iter().map(|r| um(r.x)).collect(),
            dy_um: fit.residuals.iter().map(|r| um(r.y)).collect(),
        },
        provenance: provenance(
            &request.command,
            serde_json::json!({"model": model_text(&request.model), "seed": request.seed}),
            inputs,
        ),
    };
    let mut text = summary_text(&file, &fit, &points.measured, &points.source);
    if let Some(dir) = &request.report {
        let page = dir.join(PSD_MAP_PAGE);
        let _ = writeln!(
            text,
            "  report: {} with its figures (SVG and PNG) in {}",
            page.display(),
            dir.display()
        );
    }
    Ok(PsdMapOutcome {
        file,
        fit,
        text,
        scan: request.scan.clone(),
        report: request.report.clone(),
        force: request.force,
    })
}

fn model_text(model: &ModelChoice) -> String {
    match model {
        ModelChoice::Auto => "auto".into(),
        ModelChoice::Fixed(b) => b.label(),
    }
}

fn summary_text(
    file: &PsdMapFile,
    fit: &PsdMapFit,
    measured: &[nalgebra::Vector2<f64>],
    source: &str,
) -> String {
    let f = &file.fit;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "PSD map from {source}: {} points{}, model {} ({} coefficients per axis)",
        f.points,
        if f.from_amplitudes {
            " (amplitudes)"
        } else {
            ""
        },
        file.model,
        fit.map.terms()
    );
    let _ = writeln!(
        t,
        "  cross-validated RMS {:.3} µm ({}-fold); residual RMS {:.3} µm; scan noise {:.3} / {:.3} µm (x / y)",
        f.cv_rms_um, f.folds, f.rms_um, f.sigma_x_um, f.sigma_y_um
    );
    let _ = writeln!(
        t,
        "  the map's own error at the scan points: {:.3} µm RMS",
        f.map_sigma_um
    );
    if !f.rejected_lines.is_empty() {
        let lines: Vec<String> = f
            .rejected_lines
            .iter()
            .take(10)
            .map(|l| l.to_string())
            .collect();
        let _ = writeln!(
            t,
            "  rejected {} outlying points (lines {}{})",
            f.rejected_lines.len(),
            lines.join(", "),
            if f.rejected_lines.len() > 10 {
                ", …"
            } else {
                ""
            }
        );
    }
    if f.candidates.len() > 1 {
        let list: Vec<String> = f
            .candidates
            .iter()
            .map(|c| format!("{} {:.3}", c.model, c.cv_rms_um))
            .collect();
        let _ = writeln!(t, "  candidates (CV RMS, µm): {}", list.join(", "));
    }
    let cells = residual_map(
        &fit.map.frame(),
        measured,
        &fit.residuals,
        RESIDUAL_MAP_CELLS,
    );
    let _ = writeln!(t, "  residual RMS per cell, µm (top row: largest y):");
    for row in (0..RESIDUAL_MAP_CELLS).rev() {
        let line: Vec<String> = cells
            .iter()
            .filter(|c| c.row == row)
            .map(|c| {
                if c.points == 0 {
                    "     -".to_string()
                } else {
                    format!("{:6.2}", c.rms_mm * 1e3)
                }
            })
            .collect();
        let _ = writeln!(t, "   {}", line.join(" "));
    }
    t
}
