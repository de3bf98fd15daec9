//! The page of a positioning evaluation (`psdcal evaluate --report`) from
//! plain content: the metrics as a table, the error CDF, the error vectors
//! on a floor plan (x–y) and the error against distance. The caller
//! computes every number; this module draws and lays them out.

use crate::html::{Block, Page, Table};
use crate::plot::{pad, Arrow, ArrowSet, Frame, PointSet};
use crate::residuals::residuals_svg;
use crate::scatter::scatter_svg;
use crate::sensitivity::line_plot_svg;
use crate::ReportError;

/// What the evaluation page shows.
#[derive(Debug, Clone, PartialEq)]
pub struct EvaluationReport {
    /// Page title.
    pub title: String,
    /// Paragraphs under the title (inputs, what was compared).
    pub intro: Vec<String>,
    /// Warnings (shown first).
    pub warnings: Vec<String>,
    /// Metric tables (positions, angles), already formatted.
    pub tables: Vec<Table>,
    /// Each emitter: true `(x, y)` on the floor plan, mm.
    pub floor: Vec<(f64, f64)>,
    /// Each emitter's horizontal error `(ex, ey)`, mm (same order).
    pub horizontal_errors: Vec<(f64, f64)>,
    /// Each emitter's 3-D error size, mm (same order).
    pub errors_mm: Vec<f64>,
    /// Each emitter's distance (to the nearest sensor or the origin), mm.
    pub distances_mm: Vec<f64>,
    /// What the distance is measured from, for the axis label.
    pub distance_from: String,
}

/// Figures as `(file stem, SVG text)`.
pub type NamedSvgs = Vec<(&'static str, String)>;

/// The empirical CDF of `values`: the steps `(v_(k), k/n)` and
/// `(v_(k), (k+1)/n)` of the sorted values, starting at `(v_(0), 0)`.
pub fn cdf_points(values: &[f64]) -> Vec<(f64, f64)> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let n = v.len() as f64;
    let mut out = Vec::with_capacity(2 * v.len());
    for (k, &x) in v.iter().enumerate() {
        out.push((x, k as f64 / n));
        out.push((x, (k + 1) as f64 / n));
    }
    out
}

/// The page: warnings, the introduction, the tables, then the three
/// figures side by side (their SVG also returned, named `error_cdf`,
/// `error_vectors`, `error_vs_distance`, to be written as files).
pub fn evaluation_page(report: &EvaluationReport) -> Result<(Page, NamedSvgs), ReportError> {
    let mut page = Page::new(&report.title);
    if !report.warnings.is_empty() {
        page.push(Block::Heading("Warnings".into()))
            .push(Block::List(report.warnings.clone()));
    }
    for p in &report.intro {
        page.push(Block::Paragraph(p.clone()));
    }
    for t in &report.tables {
        page.push(Block::Table(t.clone()));
    }
    let mut svgs = Vec::new();
    if !report.errors_mm.is_empty() {
        let cdf = PointSet {
            label: "3-D error".into(),
            points: cdf_points(&report.errors_mm),
        };
        let max = report.errors_mm.iter().copied().fold(0.0, f64::max);
        let frame = Frame::new(
            "Cumulative distribution of the position error",
            "3-D error (mm)",
            "fraction of emitters",
            (0.0, if max > 0.0 { 1.05 * max } else { 1.0 }),
            (0.0, 1.02),
        );
        svgs.push(("error_cdf", line_plot_svg(&[cdf], &frame)?));
        let largest = report
            .horizontal_errors
            .iter()
            .map(|e| e.0.hypot(e.1))
            .fold(0.0, f64::max);
        let mut frame = Frame::fit("", "x (mm)", "y (mm)", report.floor.iter().copied());
        let span = (frame.x_range.1 - frame.x_range.0).max(frame.y_range.1 - frame.y_range.0);
        let scale = if largest > 0.0 {
            0.08 * span / largest
        } else {
            1.0
        };
        frame.title = format!(
            "Horizontal error vectors on the floor plan (× {})",
            crate::num(scale)
        );
        let arrows = ArrowSet {
            label: "error".into(),
            arrows: report
                .floor
                .iter()
                .zip(&report.horizontal_errors)
                .map(|(&at, &delta)| Arrow { at, delta })
                .collect(),
        };
        svgs.push(("error_vectors", residuals_svg(&[arrows], scale, &frame)?));
        let points: Vec<(f64, f64)> = report
            .distances_mm
            .iter()
            .zip(&report.errors_mm)
            .map(|(&d, &e)| (d, e))
            .collect();
        let mut frame = Frame::fit(
            "Position error against distance",
            &format!("distance from {} (mm)", report.distance_from),
            "3-D error (mm)",
            points.iter().copied(),
        );
        frame.y_range = (0.0, pad((0.0, max)).1);
        let set = PointSet {
            label: "emitters".into(),
            points,
        };
        svgs.push(("error_vs_distance", scatter_svg(&[set], &frame)?));
        page.push(Block::Heading("Figures".into()))
            .push(Block::Figures(
                svgs.iter()
                    .zip([
                        "Fraction of emitters located within a given 3-D error.",
                        "Each arrow starts at the true position and points along the horizontal error (enlarged by the factor in the title).",
                        "3-D error of each emitter against its distance.",
                    ])
                    .map(|((_, svg), caption)| (svg.clone(), caption.to_string()))
                    .collect(),
            ));
    }
    Ok((page, svgs))
}
