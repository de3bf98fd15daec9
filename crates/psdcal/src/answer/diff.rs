//! `psdcal diff`: two calibrations of one sensor compared in angles of
//! arrival over the active area, with the combined σ (psdcal-locate's
//! `calibration_diff`, docs/model.md §8.8): map.csv, the summary and a
//! page with heat maps.

use std::path::PathBuf;

use psdcal_io::write_atomic_bytes;
use psdcal_locate::{diff_calibrations, CalibrationDiff};
use psdcal_report::{grid_step, heat_map_svg, Block, Frame, HeatCell, Page};
use serde_json::json;

use crate::answer::loaded_sensor::{covariance_warning, LoadedSensor};
use crate::base::error::{Error, Result};
use crate::base::table::{deg, empty, num, Table};

/// Default grid points per side.
pub const DEFAULT_DIFF_GRID: usize = 41;

/// What to compare.
#[derive(Debug, Clone, PartialEq)]
pub struct DiffRequest {
    /// Calibration A (the reference).
    pub a: PathBuf,
    /// Calibration B.
    pub b: PathBuf,
    /// Grid points per side.
    pub grid: usize,
    /// map.csv to write.
    pub out: Option<PathBuf>,
    /// Folder for diff.html and its heat maps.
    pub report: Option<PathBuf>,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
    /// Replace files in the report folder that psdcal did not write there.
    pub force: bool,
}

/// The comparison.
#[derive(Debug, Clone)]
pub struct Diffed {
    /// The request.
    pub request: DiffRequest,
    /// The difference over the grid.
    pub diff: CalibrationDiff,
    /// The active area (both calibrations').
    pub geometry: psdcal_model::PsdGeometry,
    /// What the reader should know (calibrations without covariance).
    pub warnings: Vec<String>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// map.csv's columns.
pub const DIFF_COLUMNS: [&str; 14] = [
    "x_mm",
    "y_mm",
    "alpha_x_a_deg",
    "alpha_y_a_deg",
    "alpha_x_b_deg",
    "alpha_y_b_deg",
    "delta_x_deg",
    "delta_y_deg",
    "delta_deg",
    "sigma_x_deg",
    "sigma_y_deg",
    "sigma_deg",
    "z",
    "status",
];

/// Compares the calibrations and writes what was asked.
pub fn diff(request: &DiffRequest) -> Result<Diffed> {
    let a = LoadedSensor::read_with(&request.a, request.limits)?;
    let b = LoadedSensor::read_with(&request.b, request.limits)?;
    let diff = diff_calibrations(&a.sensor, &b.sensor, request.grid)?;
    let warnings = [&a, &b]
        .into_iter()
        .filter_map(covariance_warning)
        .collect();
    let mut done = Diffed {
        request: request.clone(),
        diff,
        geometry: a.sensor.geometry,
        warnings,
        files: Vec::new(),
    };
    if let Some(out) = &request.out {
        done.table().write_to(Some(out))?;
        done.files.push(out.clone());
    }
    if let Some(dir) = &request.report {
        done.write_report(dir)?;
    }
    Ok(done)
}

impl Diffed {
    /// map.csv as a table.
    pub fn table(&self) -> Table {
        let header = DIFF_COLUMNS.iter().map(|s| s.to_string()).collect();
        let rows = self
            .diff
            .points
            .iter()
            .map(|p| {
                let mut row = vec![num(p.measured.x), num(p.measured.y)];
                match &p.values {
                    Ok(v) => {
                        let d = v.delta();
                        let c = &v.covariance;
                        row.extend([
                            deg(v.alpha_a.x),
                            deg(v.alpha_a.y),
                            deg(v.alpha_b.x),
                            deg(v.alpha_b.y),
                            deg(d.x),
                            deg(d.y),
                            deg(d.norm()),
                            deg(c[(0, 0)].max(0.0).sqrt()),
                            deg(c[(1, 1)].max(0.0).sqrt()),
                            deg(v.sigma_along()),
                            v.z().map_or_else(String::new, num),
                            "ok".to_string(),
                        ]);
                    }
                    Err(status) => {
                        row.extend(empty(11));
                        row.push(status.to_string());
                    }
                }
                row
            })
            .collect();
        Table { header, rows }
    }

    fn lines(&self) -> Vec<String> {
        let d = &self.diff;
        let n = d.grid * d.grid;
        let (max, at) = d.max_delta;
        let mut lines = vec![
            format!(
                "{} − {} over the active area ({} × {} grid, {} of {n} points answered by both)",
                self.request.b.display(),
                self.request.a.display(),
                d.grid,
                d.grid,
                d.answered
            ),
            format!(
                "AoA difference: max {:.3e}° at ({:.3}, {:.3}) mm, RMS {:.3e}°",
                max.to_degrees(),
                at.x,
                at.y,
                d.rms_delta.to_degrees()
            ),
        ];
        lines.push(match d.max_z {
            Some((z, at)) => format!(
                "largest |Δ|/σ {z:.2} at ({:.3}, {:.3}) mm (σ from both calibrations' covariances): {}",
                at.x,
                at.y,
                if z > 3.0 {
                    "significant, the calibrations differ by more than their uncertainty explains"
                } else {
                    "not significant (below 3)"
                }
            ),
            None => "|Δ|/σ: no σ (neither calibration has a covariance)".into(),
        });
        lines
    }

    /// The text summary.
    pub fn summary(&self) -> String {
        let mut lines = self.lines();
        lines.extend(self.files.iter().map(|f| format!("wrote {}", f.display())));
        lines.join("\n")
    }

    /// The JSON summary.
    pub fn to_json(&self) -> serde_json::Value {
        let d = &self.diff;
        let (max, at) = d.max_delta;
        json!({
            "a": self.request.a.display().to_string(),
            "b": self.request.b.display().to_string(),
            "grid": d.grid,
            "points": d.grid * d.grid,
            "answered": d.answered,
            "max_delta_deg": max.to_degrees(),
            "max_delta_at_mm": [at.x, at.y],
            "rms_delta_deg": d.rms_delta.to_degrees(),
            "max_z": d.max_z.map(|(z, _)| z),
            "max_z_at_mm": d.max_z.map(|(_, at)| [at.x, at.y]),
            "significant": d.max_z.is_some_and(|(z, _)| z > 3.0),
            "warnings": self.warnings,
            "files": self.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
        })
    }

    /// Writes diff.html with the heat maps of `|Δ|` and `|Δ|/σ` (also as
    /// SVG files) into `dir` (created if missing).
    fn write_report(&mut self, dir: &std::path::Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(|e| Error::OutputFolder {
            path: dir.to_path_buf(),
            message: format!("cannot create the output folder {}: {e}", dir.display()),
        })?;
        let names: Vec<String> = ["delta_map.svg", "z_map.svg", "diff.html"]
            .map(String::from)
            .to_vec();
        let folder = psdcal_io::OutputFolder::claim(dir, &names, self.request.force)?;
        let d = &self.diff;
        let (lx, ly) = (self.geometry.lx, self.geometry.ly);
        let step = (
            grid_step(d.points.iter().map(|p| p.measured.x)),
            grid_step(d.points.iter().map(|p| p.measured.y)),
        );
        let mut page = Page::new("Calibration difference");
        page.push(Block::List(self.lines()));
        page.push(Block::Paragraph(
            "Δ = α_B − α_A at each measured point of the grid; σ is the standard deviation of \
             the difference along Δ from both calibrations' covariances (independent \
             calibrations). Grid points either calibration cannot answer are left blank."
                .into(),
        ));
        let mut figures = Vec::new();
        for (name, title, label, z) in [
            ("delta_map", "AoA difference |Δ|", "|Δ| (deg)", false),
            ("z_map", "Significance |Δ|/σ", "|Δ|/σ", true),
        ] {
            let cells: Vec<HeatCell> = d
                .points
                .iter()
                .filter_map(|p| {
                    let v = p.values.as_ref().ok()?;
                    let value = if z {
                        v.z()?
                    } else {
                        v.delta().norm().to_degrees()
                    };
                    Some(HeatCell {
                        x: p.measured.x,
                        y: p.measured.y,
                        value,
                    })
                })
                .collect();
            if cells.is_empty() {
                continue;
            }
            let svg = heat_map_svg(&cells, step, &Frame::sensor(title, lx, ly), label)?;
            let path = dir.join(format!("{name}.svg"));
            write_atomic_bytes(&path, svg.as_bytes())?;
            self.files.push(path);
            figures.push((svg, title.to_string()));
        }
        page.push(Block::Figures(figures));
        let html = dir.join("diff.html");
        write_atomic_bytes(&html, page.render().as_bytes())?;
        self.files.push(html);
        Ok(folder.finish()?)
    }
}
