//! Plots and self-contained HTML reports of psdcal calibrations and studies.
//!
//! The core crates keep no plotting dependency: this crate draws from plain
//! data (points, arrows, values, titles). Every plot function returns SVG
//! text and has a `…_png` variant writing a PNG file; text is drawn with the
//! bundled DejaVu Sans, never a system font.
//!
//! | figure | functions |
//! | --- | --- |
//! | image coverage on the sensor (paper Fig. 8) | [`coverage_svg`] |
//! | residual vectors per image (Fig. 13) | [`residuals_svg`] |
//! | distortion field, corrected spiral (Fig. 16) | [`distortion_field_svg`], [`spiral_svg`] |
//! | AoA / position error maps (Fig. 9) | [`heat_map_svg`] |
//! | AoA sensitivity to Δx and Δf (Fig. 6) | [`aoa_sensitivity_svg`], [`line_plot_svg`] |
//! | Monte Carlo histograms | [`histogram_svg`] |
//! | scatter plots | [`scatter_svg`] |
//! | bar charts (per-image RMS) | [`bar_chart_svg`] |
//! | the template poses relative to the sensor, in 3-D | [`poses_svg`] |
//! | a positioning evaluation (error CDF, error vectors, error against distance) | [`evaluation_page`] |
//! | a PSD map fitted to a lensless scan (`psd-map --report`) | [`psd_map_page`] |
//!
//! Pages ([`Page`]) are one HTML file with inline SVG, an inline style
//! sheet, no script and nothing loaded from the network; every text is
//! escaped with [`escape_html`].

#![warn(missing_docs)]

pub mod bars;
pub mod calibration;
pub mod coverage;
pub mod distortion;
pub mod error;
pub mod error_map;
pub mod escape;
pub mod evaluation;
pub mod histogram;
pub mod html;
pub mod live;
pub mod number;
mod plot;
pub mod poses;
pub mod psd_map;
pub mod residuals;
pub mod scatter;
pub mod sensitivity;
pub mod study;

pub use bars::{bar_chart_png, bar_chart_svg, bar_frame};
pub use calibration::{calibration_page, CalibrationReport, Plot, PlotData};
pub use coverage::{coverage_png, coverage_svg};
pub use distortion::{distortion_field_png, distortion_field_svg, spiral_png, spiral_svg};
pub use error::ReportError;
pub use error_map::{grid_step, heat_map_png, heat_map_svg, HeatCell, COLORBAR_STEPS};
pub use escape::escape_html;
pub use evaluation::{cdf_points, evaluation_page, EvaluationReport};
pub use histogram::{
    bin_counts, counts_histogram_png, counts_histogram_svg, histogram_png, histogram_svg,
};
pub use html::{correlation_colour, inline_svg, Block, Page, Table};
pub use live::live_page;
pub use number::{num, unit_text, value_with_digits, value_with_sigma};
pub use plot::{count_label, tick_label, Arrow, ArrowSet, Frame, PointSet};
pub use poses::{poses_png, poses_svg, PoseOutline};
pub use psd_map::{psd_map_page, PsdMapReport};
pub use residuals::{residuals_png, residuals_svg, OUTLINE_LABEL};
pub use scatter::{scatter_png, scatter_svg};
pub use sensitivity::{
    aoa_sensitivity_svg, line_plot_png, line_plot_svg, paper_sensitivity_curves,
};
pub use study::{
    bias_cell, bias_table, estimate_cell, fig9_cells, paper_cell, paper_table, study_page,
    study_table, study_warnings, Fig9Map, Fig9Offset, StudyColumn, StudyContent, StudyRow,
    StudyStats, StudyTable, BIAS_FULL_SHADE, FEW_TRIALS, MAX_HISTOGRAM_CONDITIONS,
};
