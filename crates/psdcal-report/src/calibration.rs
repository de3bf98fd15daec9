//! The page of a calibration report from plain content: its tables and its
//! plots ([`CalibrationReport`], [`Plot`]). The caller computes the content
//! (points, arrows, cells, captions); this module draws and lays it out.

use std::path::Path;

use crate::bars::{bar_chart_png, bar_chart_svg};
use crate::coverage::{coverage_png, coverage_svg};
use crate::distortion::{distortion_field_png, distortion_field_svg, spiral_png, spiral_svg};
use crate::error::ReportError;
use crate::error_map::{heat_map_png, heat_map_svg, HeatCell};
use crate::histogram::{counts_histogram_png, counts_histogram_svg};
use crate::html::{Block, Page, Table};
use crate::plot::{Arrow, ArrowSet, Frame, PointSet};
use crate::poses::{poses_png, poses_svg, PoseOutline};
use crate::residuals::{residuals_png, residuals_svg};
use crate::sensitivity::{aoa_sensitivity_svg, line_plot_png, paper_sensitivity_curves};

/// What a plot shows.
#[derive(Debug, Clone, PartialEq)]
pub enum PlotData {
    /// Measured points of each image on the active area (Figure 8).
    Coverage {
        /// One set per image.
        sets: Vec<PointSet>,
        /// Active area, mm.
        lx: f64,
        /// Active area, mm.
        ly: f64,
        /// Title, labels, ranges.
        frame: Frame,
    },
    /// Residual vectors per image (Figure 13).
    Residuals {
        /// One set per image.
        sets: Vec<ArrowSet>,
        /// Arrow scale.
        scale: f64,
        /// Title, labels, ranges.
        frame: Frame,
    },
    /// The distortion correction over the sensor (Figure 16).
    DistortionField {
        /// Measured point → ideal point.
        arrows: Vec<Arrow>,
        /// Arrow scale.
        scale: f64,
        /// The valid region's boundary where the correction folds, as
        /// polylines in sensor mm (empty: the region holds the whole area).
        boundary: Vec<Vec<(f64, f64)>>,
        /// Title, labels, ranges.
        frame: Frame,
    },
    /// A measured spiral and its correction (Figure 16).
    Spiral {
        /// Measured points.
        measured: Vec<(f64, f64)>,
        /// Corrected points.
        corrected: Vec<(f64, f64)>,
        /// Title, labels, ranges.
        frame: Frame,
    },
    /// The AoA sensitivity to Δx and Δf (Figure 6, P40–P41).
    Sensitivity {
        /// Focal length, mm.
        f: f64,
        /// Half the sensor width, mm.
        half_width: f64,
    },
    /// A histogram of values with a count axis.
    Histogram {
        /// The values.
        values: Vec<f64>,
        /// Number of bins.
        bins: usize,
        /// Title.
        title: String,
        /// Label of the value axis (with its unit).
        x_label: String,
        /// Label of the count axis.
        y_label: String,
    },
    /// One bar per item (an image's RMS error).
    Bars {
        /// The values, in item order.
        values: Vec<f64>,
        /// Title, labels, ranges.
        frame: Frame,
    },
    /// The template poses relative to the sensor, an oblique 3-D view.
    Poses {
        /// One outline per image, sensor frame.
        poses: Vec<PoseOutline>,
        /// Active area, mm.
        sensor: (f64, f64),
        /// Title.
        title: String,
    },
    /// A heat map over the sensor (Figure 9).
    HeatMap {
        /// Cells.
        cells: Vec<HeatCell>,
        /// Cell size, mm.
        step: (f64, f64),
        /// Title, labels, ranges.
        frame: Frame,
        /// Label of the colour bar.
        label: String,
    },
}

/// One plot: its file stem, caption and content.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// File stem (`coverage`, …).
    pub name: &'static str,
    /// Caption.
    pub caption: String,
    /// Content.
    pub data: PlotData,
}

impl Plot {
    /// The plot as SVG text.
    pub fn svg(&self) -> Result<String, ReportError> {
        match &self.data {
            PlotData::Coverage {
                sets,
                lx,
                ly,
                frame,
            } => coverage_svg(sets, *lx, *ly, frame),
            PlotData::Residuals { sets, scale, frame } => residuals_svg(sets, *scale, frame),
            PlotData::DistortionField {
                arrows,
                scale,
                boundary,
                frame,
            } => distortion_field_svg(arrows, *scale, boundary, frame),
            PlotData::Spiral {
                measured,
                corrected,
                frame,
            } => spiral_svg(measured, corrected, frame),
            PlotData::Sensitivity { f, half_width } => aoa_sensitivity_svg(*f, *half_width),
            PlotData::Histogram {
                values,
                bins,
                title,
                x_label,
                y_label,
            } => counts_histogram_svg(values, *bins, title, x_label, y_label),
            PlotData::Bars { values, frame } => bar_chart_svg(values, frame),
            PlotData::HeatMap {
                cells,
                step,
                frame,
                label,
            } => heat_map_svg(cells, *step, frame, label),
            PlotData::Poses {
                poses,
                sensor,
                title,
            } => poses_svg(poses, *sensor, title),
        }
    }

    /// Writes the plot as a PNG file.
    pub fn png(&self, path: &Path) -> Result<(), ReportError> {
        match &self.data {
            PlotData::Coverage {
                sets,
                lx,
                ly,
                frame,
            } => coverage_png(sets, *lx, *ly, frame, path),
            PlotData::Residuals { sets, scale, frame } => residuals_png(sets, *scale, frame, path),
            PlotData::DistortionField {
                arrows,
                scale,
                boundary,
                frame,
            } => distortion_field_png(arrows, *scale, boundary, frame, path),
            PlotData::Spiral {
                measured,
                corrected,
                frame,
            } => spiral_png(measured, corrected, frame, path),
            PlotData::Sensitivity { f, half_width } => {
                let curves = paper_sensitivity_curves(*f, *half_width, 101);
                let frame = Frame::fit(
                    "AoA sensitivity to Δx and Δf (P40–P41)",
                    "x (mm)",
                    "deg per mm",
                    curves
                        .iter()
                        .flat_map(|c| c.points.iter().copied())
                        .chain([(0.0, 0.0)]),
                );
                line_plot_png(&curves, &frame, path)
            }
            PlotData::Histogram {
                values,
                bins,
                title,
                x_label,
                y_label,
            } => counts_histogram_png(values, *bins, title, x_label, y_label, path),
            PlotData::Bars { values, frame } => bar_chart_png(values, frame, path),
            PlotData::HeatMap {
                cells,
                step,
                frame,
                label,
            } => heat_map_png(cells, *step, frame, label, path),
            PlotData::Poses {
                poses,
                sensor,
                title,
            } => poses_png(poses, *sensor, title, path),
        }
    }
}

/// A calibration report's content.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationReport {
    /// Page title.
    pub title: String,
    /// Where it came from (files, software, sensor).
    pub sources: Vec<String>,
    /// Parameters ± σ.
    pub parameters: Table,
    /// The model choice's candidates, when the data chose the model.
    pub model_choice: Option<Table>,
    /// Fit summary.
    pub fit: Table,
    /// The plots.
    pub plots: Vec<Plot>,
    /// Per image: pose and RMS from the calibration.
    pub images: Table,
    /// Per image: residuals recomputed from the data, if given.
    pub recomputed: Option<Table>,
    /// What the calibration noticed about itself, one line each
    /// (`code (severity): message`), and warnings about the data; empty
    /// when there is nothing to say. Shown first.
    pub diagnostics: Vec<String>,
    /// Provenance: version, command, inputs with their SHA-256.
    pub provenance: Option<Table>,
    /// The estimated parameters' correlation matrix: names and rows.
    pub correlation: Option<(Vec<String>, Vec<Vec<f64>>)>,
    /// The points with the largest residuals.
    pub worst_points: Option<Table>,
}

/// The page of a report; `svgs` are its plots' SVG texts, in order.
pub fn calibration_page(report: &CalibrationReport, svgs: &[String]) -> Page {
    let mut page = Page::new(&report.title);
    page.push(Block::Heading("Diagnostics".into()));
    if report.diagnostics.is_empty() {
        page.push(Block::Paragraph(
            "The calibration raised no diagnostic.".into(),
        ));
    } else {
        page.push(Block::List(report.diagnostics.clone()));
    }
    page.push(Block::List(report.sources.clone()));
    page.push(Block::Heading("Parameters".into()));
    page.push(Block::Table(report.parameters.clone()));
    if let Some((names, values)) = &report.correlation {
        page.push(Block::Correlation {
            caption: "Correlations of the estimated parameters (|ρ| near 1: the data hardly \
                      separate them)"
                .into(),
            names: names.clone(),
            values: values.clone(),
        });
    }
    if let Some(t) = &report.model_choice {
        page.push(Block::Heading("The model".into()));
        page.push(Block::Table(t.clone()));
    }
    page.push(Block::Table(report.fit.clone()));
    if let Some(t) = &report.provenance {
        page.push(Block::Table(t.clone()));
    }
    page.push(Block::Heading("Plots".into()));
    page.push(Block::Figures(
        svgs.iter()
            .zip(&report.plots)
            .map(|(svg, p)| (svg.clone(), p.caption.clone()))
            .collect(),
    ));
    if let Some(t) = &report.worst_points {
        page.push(Block::Heading("Worst points".into()));
        page.push(Block::Table(t.clone()));
    }
    page.push(Block::Heading("Images".into()));
    page.push(Block::Table(report.images.clone()));
    if let Some(t) = &report.recomputed {
        page.push(Block::Table(t.clone()));
    }
    page
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(diagnostics: Vec<String>) -> CalibrationReport {
        let table = Table {
            caption: String::new(),
            headers: Vec::new(),
            rows: Vec::new(),
        };
        CalibrationReport {
            title: "t".into(),
            sources: Vec::new(),
            parameters: table.clone(),
            model_choice: None,
            fit: table.clone(),
            plots: Vec::new(),
            images: table,
            recomputed: None,
            diagnostics,
            provenance: None,
            correlation: None,
            worst_points: None,
        }
    }

    #[test]
    fn the_page_lists_the_diagnostics_escaped_or_says_there_are_none() {
        let html = calibration_page(&report(Vec::new()), &[]).render();
        assert!(html.contains("<h2>Diagnostics</h2>"));
        assert!(html.contains("raised no diagnostic"));
        let line = "model_misfit (warning): residual <structure> & more".to_string();
        let html = calibration_page(&report(vec![line]), &[]).render();
        assert!(
            html.contains("<li>model_misfit (warning): residual &lt;structure&gt; &amp; more</li>")
        );
        assert!(!html.contains("raised no diagnostic"));
    }
}
