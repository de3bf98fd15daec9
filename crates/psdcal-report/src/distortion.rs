//! The distortion field and the correction of a measured spiral (the
//! paper's Figure 16).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{
    chart_legend, color, finite, legend, to_png, to_svg, Arrow, ArrowSet, Figure, Frame,
};
use crate::residuals::Arrows;

fn field_sets(arrows: &[Arrow]) -> [ArrowSet; 1] {
    [ArrowSet {
        label: String::new(),
        arrows: arrows.to_vec(),
    }]
}

/// The distortion field: one arrow per grid point from the measured point
/// to its ideal (corrected) point, lengths × `scale`. One `<polygon>` arrow
/// head per arrow. `boundary`: the valid region's boundary where the
/// correction folds (docs/model.md §8.2), as polylines in sensor mm, drawn
/// in black (one `<polyline>` each) with the legend entry
/// [`OUTLINE_LABEL`](crate::OUTLINE_LABEL); empty when the region holds the
/// whole active area.
pub fn distortion_field_svg(
    arrows: &[Arrow],
    scale: f64,
    boundary: &[Vec<(f64, f64)>],
    frame: &Frame,
) -> Result<String, ReportError> {
    let sets = field_sets(arrows);
    to_svg(&Arrows {
        sets: &sets,
        scale,
        frame,
        what: "distortion field",
        outline: boundary,
    })
}

/// [`distortion_field_svg`] as a PNG file.
pub fn distortion_field_png(
    arrows: &[Arrow],
    scale: f64,
    boundary: &[Vec<(f64, f64)>],
    frame: &Frame,
    path: &Path,
) -> Result<(), ReportError> {
    let sets = field_sets(arrows);
    to_png(
        &Arrows {
            sets: &sets,
            scale,
            frame,
            what: "distortion field",
            outline: boundary,
        },
        path,
    )
}

struct Spiral<'a> {
    measured: &'a [(f64, f64)],
    corrected: &'a [(f64, f64)],
    frame: &'a Frame,
}

impl Figure for Spiral<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check("spiral")?;
        finite(
            "spiral",
            self.measured
                .iter()
                .chain(self.corrected)
                .flat_map(|p| [p.0, p.1]),
        )?;
        let mut chart = chart_legend(root, self.frame)?;
        let red = color(3);
        let blue = color(0);
        chart
            .draw_series(LineSeries::new(
                self.measured.iter().copied(),
                red.stroke_width(1),
            ))
            .map_err(draw_err)?;
        chart
            .draw_series(
                self.measured
                    .iter()
                    .map(|&p| Circle::new(p, 2, red.filled())),
            )
            .map_err(draw_err)?;
        chart
            .draw_series(LineSeries::new(
                self.corrected.iter().copied(),
                blue.stroke_width(2),
            ))
            .map_err(draw_err)?;
        legend(root, &chart, &[("measured", red), ("corrected", blue)])?;
        Ok(())
    }
}

/// A measured spiral (thin red line, one circle per point) and its
/// correction (thick blue line).
pub fn spiral_svg(
    measured: &[(f64, f64)],
    corrected: &[(f64, f64)],
    frame: &Frame,
) -> Result<String, ReportError> {
    to_svg(&Spiral {
        measured,
        corrected,
        frame,
    })
}

/// [`spiral_svg`] as a PNG file.
pub fn spiral_png(
    measured: &[(f64, f64)],
    corrected: &[(f64, f64)],
    frame: &Frame,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(
        &Spiral {
            measured,
            corrected,
            frame,
        },
        path,
    )
}
