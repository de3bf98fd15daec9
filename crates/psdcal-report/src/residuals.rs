//! Residual vectors per image, on the template and on the sensor (the
//! paper's Figure 13).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{
    arrow_parts, chart, chart_legend, color, finite, legend, to_png, to_svg, ArrowSet, Figure,
    Frame, MAX_LEGEND,
};

pub(crate) struct Arrows<'a> {
    pub(crate) sets: &'a [ArrowSet],
    pub(crate) scale: f64,
    pub(crate) frame: &'a Frame,
    pub(crate) what: &'static str,
    /// Polylines drawn over the arrows in black, with one legend entry
    /// [`OUTLINE_LABEL`] (the distortion field's valid-region boundary).
    pub(crate) outline: &'a [Vec<(f64, f64)>],
}

/// Legend entry of `Arrows::outline`.
pub const OUTLINE_LABEL: &str = "valid region boundary";

impl Figure for Arrows<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check(self.what)?;
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(ReportError::InvalidData {
                what: self.what,
                reason: format!("the arrow scale {} is not positive", self.scale),
            });
        }
        finite(
            self.what,
            self.sets.iter().flat_map(|s| {
                s.arrows
                    .iter()
                    .flat_map(|a| [a.at.0, a.at.1, a.delta.0, a.delta.1])
            }),
        )?;
        finite(
            self.what,
            self.outline.iter().flatten().flat_map(|p| [p.0, p.1]),
        )?;
        let labelled = self.sets.len() > 1 && self.sets.len() <= MAX_LEGEND;
        let outlined = self.outline.iter().any(|l| l.len() > 1);
        let mut chart = if labelled || outlined {
            chart_legend(root, self.frame)?
        } else {
            chart(root, self.frame)?
        };
        let span = (self.frame.x_range.1 - self.frame.x_range.0)
            .max(self.frame.y_range.1 - self.frame.y_range.0);
        let head = 0.018 * span;
        for (k, set) in self.sets.iter().enumerate() {
            let c = color(k);
            let ends: Vec<((f64, f64), (f64, f64))> = set
                .arrows
                .iter()
                .map(|a| {
                    let b = (
                        a.at.0 + self.scale * a.delta.0,
                        a.at.1 + self.scale * a.delta.1,
                    );
                    (a.at, b)
                })
                .collect();
            let style = c.stroke_width(1);
            chart
                .draw_series(ends.iter().map(|&(a, b)| arrow_parts(a, b, head, style).0))
                .map_err(draw_err)?;
            chart
                .draw_series(ends.iter().map(|&(a, b)| arrow_parts(a, b, head, style).1))
                .map_err(draw_err)?;
        }
        for line in self.outline.iter().filter(|l| l.len() > 1) {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    line.clone(),
                    BLACK.stroke_width(2),
                )))
                .map_err(draw_err)?;
        }
        let mut entries: Vec<_> = Vec::new();
        if labelled {
            entries.extend(
                (self.sets.iter().enumerate()).map(|(k, set)| (set.label.as_str(), color(k))),
            );
        }
        if outlined {
            entries.push((OUTLINE_LABEL, BLACK));
        }
        if !entries.is_empty() {
            legend(root, &chart, &entries)?;
        }
        Ok(())
    }
}

/// Residual vectors: for each image (one colour, legend up to 12 images) an
/// arrow per point from the point along its residual × `scale` (state the
/// scale in the title). One `<polygon>` arrow head per residual.
pub fn residuals_svg(sets: &[ArrowSet], scale: f64, frame: &Frame) -> Result<String, ReportError> {
    to_svg(&Arrows {
        sets,
        scale,
        frame,
        what: "residuals",
        outline: &[],
    })
}

/// [`residuals_svg`] as a PNG file.
pub fn residuals_png(
    sets: &[ArrowSet],
    scale: f64,
    frame: &Frame,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(
        &Arrows {
            sets,
            scale,
            frame,
            what: "residuals",
            outline: &[],
        },
        path,
    )
}
