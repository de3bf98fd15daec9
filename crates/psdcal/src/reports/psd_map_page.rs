//! `psdcal psd-map --report DIR`: the page of a PSD map fitted to a
//! lensless scan (docs/model.md §8.3) and its figures, as SVG and PNG, in
//! one folder; psdcal-report draws and lays it out.
//!
//! What it shows, from psd_map.json's content (the numbers printed are the
//! file's):
//! - the fitted displacement `d(m) = map(m)` (measured → corrected point)
//!   as arrows on a 15 × 15 grid and `|d|` in µm as a heat map on a 31 × 31
//!   grid over the active area, only inside the scan's hull (the map's
//!   domain: outside it a point is `outside_valid_region`), the hull drawn;
//! - the scan points on the active area (rejected outliers apart) with the
//!   hull;
//! - the residuals `r_i = d_i − map(m_i)` (stage position minus corrected
//!   point) of the kept points: one arrow per point, scaled so that the RMS
//!   residual is about 0.7 of the mean spacing `√(A_hull / n)`; their RMS
//!   per cell of a 10 × 10 grid of the map's frame; a histogram of `|r_i|`;
//! - the model, every candidate's cross-validated RMS, the noise, the map's
//!   own error, and the provenance.
//!
//! Every file is written atomically; none may be the scan or psd_map.json
//! (refused before anything is written).

use std::path::{Path, PathBuf};

use nalgebra::Vector2;
use psdcal_io::write_psd_map;
use psdcal_model::stages::MapBasis;
use psdcal_model::Stage;
use psdcal_report::{
    psd_map_page, Arrow, Frame, HeatCell, Plot, PlotData, PointSet, PsdMapReport, Table,
};

use crate::base::error::{Error, Result};
use crate::psd_map::from_scan::{residual_cells, PsdMapOutcome, PSD_MAP_PAGE, SCAN_SUMMARY_CELLS};
use crate::reports::calibration_page::{plot_files, write_plots};
use crate::reports::calibration_plots::{arrow_scale_for, scale_text};

/// Grid points per side of the field's arrows.
const ARROW_GRID: usize = 15;
/// Grid points per side of the field's size map.
const HEAT_GRID: usize = 31;
/// Spacing of the points drawn along the hull's edges, mm.
const HULL_STEP_MM: f64 = 0.05;

impl PsdMapOutcome {
    /// Writes psd_map.json atomically and, when asked, the report into its
    /// folder (this module); refuses, before writing anything,
    /// a report file that is the scan or `path`.
    pub fn write(&self, path: &Path) -> Result<()> {
        let report = match &self.report {
            Some(dir) => Some(prepare(self, dir, path)?),
            None => None,
        };
        write_psd_map(path, &self.file)?;
        if let Some(report) = report {
            report.write()?;
        }
        Ok(())
    }
}

/// A report ready to be written: every figure drawn, the files checked.
pub(crate) struct PreparedReport {
    folder: psdcal_io::OutputFolder,
    dir: PathBuf,
    page: String,
    plots: Vec<Plot>,
    svgs: Vec<String>,
}

impl PreparedReport {
    /// Writes the page and the figures (into the folder [`prepare`] made).
    pub(crate) fn write(self) -> Result<Vec<PathBuf>> {
        let html = self.dir.join(PSD_MAP_PAGE);
        psdcal_io::write_atomic_bytes(&html, self.page.as_bytes())?;
        let mut files = vec![html];
        files.extend(write_plots(&self.dir, &self.plots, &self.svgs)?);
        self.folder.finish()?;
        Ok(files)
    }
}

/// The report of `outcome` for the folder `dir`, psd_map.json going to
/// `out`: refused when a file of it would be the scan or `out`; the folder
/// is made once every figure is drawn.
pub(crate) fn prepare(outcome: &PsdMapOutcome, dir: &Path, out: &Path) -> Result<PreparedReport> {
    let content = content(outcome);
    let files: Vec<PathBuf> = std::iter::once(dir.join(PSD_MAP_PAGE))
        .chain(plot_files(dir, &content.plots))
        .collect();
    let mut outputs: Vec<(&str, &Path)> = vec![("--out", out)];
    outputs.extend(files.iter().map(|f| ("--report", f.as_path())));
    psdcal_io::refuse_overwrite(&[("--scan", outcome.scan.as_path())], &outputs)?;
    let svgs: Vec<String> = content
        .plots
        .iter()
        .map(Plot::svg)
        .collect::<std::result::Result<_, _>>()?;
    let page = psd_map_page(&content, &svgs).render();
    // The folder before psd_map.json: a folder that cannot be made leaves
    // nothing behind.
    std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
        path: dir.to_path_buf(),
        message: format!("cannot create the report folder {}: {e}", dir.display()),
    })?;
    let names: Vec<String> = std::iter::once(PathBuf::from(PSD_MAP_PAGE))
        .chain(plot_files(Path::new(""), &content.plots))
        .map(|p| p.display().to_string())
        .collect();
    let folder = psdcal_io::OutputFolder::claim(dir, &names, outcome.force)?;
    Ok(PreparedReport {
        folder,
        dir: dir.to_path_buf(),
        page,
        plots: content.plots,
        svgs,
    })
}

/// The page's content.
fn content(outcome: &PsdMapOutcome) -> PsdMapReport {
    let file = &outcome.file;
    let fit = &file.fit;
    let map = &outcome.fit.map;
    let (lx, ly) = (file.sensor.lx_mm, file.sensor.ly_mm);
    let hull: Vec<(f64, f64)> = map
        .hull()
        .map(|h| {
            let v = h.vertices();
            (0..=v.len())
                .map(|i| (v[i % v.len()].x, v[i % v.len()].y))
                .collect()
        })
        .unwrap_or_default();
    let mut plots = field_plots(outcome, &hull, lx, ly);
    let r = &file.residuals;
    let kept: Vec<usize> = (0..r.x_mm.len())
        .filter(|i| !r.rejected.contains(i))
        .collect();
    plots.push(scan_points_plot(outcome, &kept, &hull, lx, ly));
    plots.extend(residual_plots(outcome, &kept, &hull, lx, ly));
    let scan_name = outcome.scan.display().to_string();
    let hull_share = map
        .hull()
        .map_or(100.0, |h| (100.0 * h.area() / (lx * ly)).min(100.0));
    let rejected = if fit.rejected_lines.is_empty() {
        "Rejected as outliers: none".to_string()
    } else {
        let lines: Vec<String> = fit
            .rejected_lines
            .iter()
            .take(20)
            .map(|l| l.to_string())
            .collect();
        format!(
            "Rejected as outliers (residual beyond 5 robust σ, left out of the fit and of the \
             residual plots): {} points, scan lines {}{}",
            fit.rejected_lines.len(),
            lines.join(", "),
            if fit.rejected_lines.len() > 20 {
                ", …"
            } else {
                ""
            }
        )
    };
    let auto = file
        .provenance
        .options
        .get("model")
        .and_then(|m| m.as_str())
        == Some("auto");
    let summary = vec![
        format!(
            "Scan: {scan_name}, {} points{} on a {lx} mm × {ly} mm sensor",
            fit.points,
            if fit.from_amplitudes {
                " (from electrode amplitudes)"
            } else {
                ""
            }
        ),
        format!(
            "Model: {} ({} coefficients per axis, {:.1} effective), {}",
            file.model,
            map.terms(),
            fit.effective_terms,
            if auto {
                "chosen by cross-validation"
            } else {
                "as given (--model)"
            }
        ),
        format!(
            "Cross-validated RMS error: {:.3} µm ({}-fold)",
            fit.cv_rms_um, fit.folds
        ),
        format!(
            "Residual RMS: {:.3} µm; scan noise σx {:.3} µm, σy {:.3} µm",
            fit.rms_um, fit.sigma_x_um, fit.sigma_y_um
        ),
        format!(
            "The map's own error at the scan points: {:.3} µm RMS (1σ)",
            fit.map_sigma_um
        ),
        rejected,
        format!(
            "The scan's hull covers {hull_share:.1} % of the active area: the map is known only \
             inside it, and calibrate, aoa, locate and correct answer points outside it \
             outside_valid_region"
        ),
    ];
    let cross_validation = Table {
        caption: "Cross-validation: every candidate model's held-out RMS error".into(),
        headers: vec![
            "model".into(),
            "coefficients per axis".into(),
            "CV RMS (µm)".into(),
            "".into(),
        ],
        rows: fit
            .candidates
            .iter()
            .map(|c| {
                vec![
                    c.model.clone(),
                    MapBasis::parse(&c.model).map_or(String::new(), |b| b.terms().to_string()),
                    format!("{:.3}", c.cv_rms_um),
                    if c.model == file.model {
                        "chosen".into()
                    } else {
                        String::new()
                    },
                ]
            })
            .collect(),
    };
    let choice = if auto {
        format!(
            "Each candidate was fitted to {0} of {1} folds of the scan points and scored on \
             the held-out fold, in turn; the chosen model is the one with the fewest \
             coefficients whose held-out mean squared error is within one standard error of \
             the best (a more flexible model must earn its coefficients by more than the \
             noise in the score).",
            fit.folds.saturating_sub(1),
            fit.folds
        )
    } else {
        "The model was given with --model: only it was fitted, and its cross-validated RMS \
         is reported."
            .into()
    };
    PsdMapReport {
        title: format!(
            "PSD map from {}",
            outcome
                .scan
                .file_name()
                .map_or(scan_name.clone(), |n| n.to_string_lossy().into_owned())
        ),
        summary,
        cross_validation,
        choice,
        plots,
        provenance: Some(crate::reports::calibration_tables::provenance_table(
            &file.provenance,
        )),
    }
}

/// Grid points over the active area inside the map's domain.
fn grid_inside(
    outcome: &PsdMapOutcome,
    lx: f64,
    ly: f64,
    n: usize,
) -> impl Iterator<Item = Vector2<f64>> + '_ {
    (0..n * n)
        .map(move |k| {
            Vector2::new(
                lx * (-0.5 + (k % n) as f64 / (n - 1) as f64),
                ly * (-0.5 + (k / n) as f64 / (n - 1) as f64),
            )
        })
        .filter(|m| outcome.fit.map.contains_input(m))
}

/// The field as arrows and its size as a heat map.
fn field_plots(outcome: &PsdMapOutcome, hull: &[(f64, f64)], lx: f64, ly: f64) -> Vec<Plot> {
    let (map, block) = (&outcome.fit.map, &outcome.fit.block);
    let arrows: Vec<Arrow> = grid_inside(outcome, lx, ly, ARROW_GRID)
        .map(|m| {
            let d = map.displacement(block, &m);
            Arrow {
                at: (m.x, m.y),
                delta: (d.x, d.y),
            }
        })
        .collect();
    let cells: Vec<HeatCell> = grid_inside(outcome, lx, ly, HEAT_GRID)
        .map(|m| HeatCell {
            x: m.x,
            y: m.y,
            value: 1e3 * map.displacement(block, &m).norm(),
        })
        .collect();
    let longest = arrows
        .iter()
        .map(|a| a.delta.0.hypot(a.delta.1))
        .fold(0.0, f64::max);
    let largest = cells.iter().map(|c| c.value).fold(0.0, f64::max);
    let scale = arrow_scale_for(longest, 1.1 * lx.max(ly));
    let boundary = if hull.is_empty() {
        Vec::new()
    } else {
        vec![hull.to_vec()]
    };
    let mut plots = vec![Plot {
        name: "psd_map_field",
        caption: format!(
            "The fitted map: measured → corrected point on a {ARROW_GRID} × {ARROW_GRID} grid, \
             arrows scaled × {}, only inside the scan's hull (black; outside it the map is not \
             known)",
            scale_text(scale)
        ),
        data: PlotData::DistortionField {
            arrows,
            scale,
            boundary,
            frame: Frame::sensor(&format!("PSD map × {}", scale_text(scale)), lx, ly),
        },
    }];
    if !cells.is_empty() {
        plots.push(Plot {
            name: "psd_map_magnitude",
            caption: format!(
                "Size of the map's correction |map(m)| over the active area, largest {} µm \
                 (blank: outside the scan's hull)",
                psdcal_report::num(largest)
            ),
            data: PlotData::HeatMap {
                cells,
                step: (lx / (HEAT_GRID - 1) as f64, ly / (HEAT_GRID - 1) as f64),
                frame: Frame::sensor("PSD map correction size", lx, ly),
                label: "correction (µm)".into(),
            },
        });
    }
    plots
}

/// The scan points on the active area, rejected ones apart, and the hull.
fn scan_points_plot(
    outcome: &PsdMapOutcome,
    kept: &[usize],
    hull: &[(f64, f64)],
    lx: f64,
    ly: f64,
) -> Plot {
    let r = &outcome.file.residuals;
    let at = |i: &usize| (r.x_mm[*i], r.y_mm[*i]);
    let mut sets = vec![PointSet {
        label: format!("scan points ({})", kept.len()),
        points: kept.iter().map(at).collect(),
    }];
    if !r.rejected.is_empty() {
        sets.push(PointSet {
            label: format!("rejected ({})", r.rejected.len()),
            points: r.rejected.iter().map(at).collect(),
        });
    }
    if hull.len() > 1 {
        let mut along = Vec::new();
        for w in hull.windows(2) {
            let (a, b) = (w[0], w[1]);
            let n = ((b.0 - a.0).hypot(b.1 - a.1) / HULL_STEP_MM)
                .ceil()
                .max(1.0) as usize;
            along.extend((0..n).map(|k| {
                let t = k as f64 / n as f64;
                (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
            }));
        }
        sets.push(PointSet {
            label: "the scan's hull".into(),
            points: along,
        });
    }
    Plot {
        name: "psd_map_scan_points",
        caption: format!(
            "Where the scan measured: {} points kept{} on the {lx} × {ly} mm active area \
             (outlined), and their convex hull, the map's valid region",
            kept.len(),
            if r.rejected.is_empty() {
                String::new()
            } else {
                format!(", {} rejected as outliers", r.rejected.len())
            }
        ),
        data: PlotData::Coverage {
            sets,
            lx,
            ly,
            frame: Frame::sensor("Scan points", lx, ly),
        },
    }
}

/// The kept points' residuals: arrows, RMS per cell, histogram of sizes.
fn residual_plots(
    outcome: &PsdMapOutcome,
    kept: &[usize],
    hull: &[(f64, f64)],
    lx: f64,
    ly: f64,
) -> Vec<Plot> {
    let r = &outcome.file.residuals;
    if kept.is_empty() {
        return Vec::new();
    }
    let arrows: Vec<Arrow> = kept
        .iter()
        .map(|&i| Arrow {
            at: (r.x_mm[i], r.y_mm[i]),
            delta: (1e-3 * r.dx_um[i], 1e-3 * r.dy_um[i]),
        })
        .collect();
    let sizes: Vec<f64> = kept.iter().map(|&i| r.dx_um[i].hypot(r.dy_um[i])).collect();
    let rms_mm = 1e-3 * (sizes.iter().map(|s| s * s).sum::<f64>() / sizes.len() as f64).sqrt();
    let area = outcome.fit.map.hull().map_or(lx * ly, |h| h.area());
    let spacing = (area / kept.len() as f64).sqrt();
    // arrow_scale_for makes `rms_mm` 8 % of the span: 0.7 of the spacing.
    let scale = arrow_scale_for(rms_mm, 0.7 * spacing / 0.08);
    let boundary = if hull.is_empty() {
        Vec::new()
    } else {
        vec![hull.to_vec()]
    };
    let frame = outcome.fit.map.frame();
    let cells = residual_cells(&outcome.file, &outcome.fit.map);
    let n = SCAN_SUMMARY_CELLS as f64;
    let step = (
        (frame.max.x - frame.min.x) / n,
        (frame.max.y - frame.min.y) / n,
    );
    let worst = cells.iter().map(|c| 1e3 * c.rms_mm).fold(0.0, f64::max);
    let bins = ((sizes.len() as f64).sqrt().round() as usize).clamp(5, 30);
    let noise = outcome
        .file
        .fit
        .sigma_x_um
        .hypot(outcome.file.fit.sigma_y_um);
    vec![
        Plot {
            name: "psd_map_residuals",
            caption: format!(
                "The scan's residuals (stage position − corrected point) at each of the {} kept \
                 points, arrows scaled × {}, RMS {} µm; the scan's hull in black",
                kept.len(),
                scale_text(scale),
                psdcal_report::num(1e3 * rms_mm)
            ),
            data: PlotData::DistortionField {
                arrows,
                scale,
                boundary,
                frame: Frame::sensor(&format!("Scan residuals × {}", scale_text(scale)), lx, ly),
            },
        },
        Plot {
            name: "psd_map_residual_rms",
            caption: format!(
                "RMS residual per cell of a {SCAN_SUMMARY_CELLS} × {SCAN_SUMMARY_CELLS} grid, \
                 largest {} µm; against the scan noise √(σx² + σy²) = {} µm, a cell well above \
                 it is where the map does not follow the sensor",
                psdcal_report::num(worst),
                psdcal_report::num(noise)
            ),
            data: PlotData::HeatMap {
                cells: cells
                    .iter()
                    .map(|c| HeatCell {
                        x: c.centre.x,
                        y: c.centre.y,
                        value: 1e3 * c.rms_mm,
                    })
                    .collect(),
                step,
                frame: Frame::sensor("Scan residual RMS per cell", lx, ly),
                label: "RMS residual (µm)".into(),
            },
        },
        Plot {
            name: "psd_map_residual_histogram",
            caption: format!(
                "How large the {} kept residuals are; with noise alone their RMS would be the \
                 scan noise √(σx² + σy²) = {} µm",
                sizes.len(),
                psdcal_report::num(noise)
            ),
            data: PlotData::Histogram {
                values: sizes,
                bins,
                title: "Scan residual sizes".into(),
                x_label: "|residual| (µm)".into(),
                y_label: "scan points".into(),
            },
        },
    ]
}
