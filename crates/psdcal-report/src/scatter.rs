//! Scatter plots: one filled circle per point, one colour per set.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{
    chart, chart_legend, color, finite, legend, to_png, to_svg, Figure, Frame, PointSet, MAX_LEGEND,
};

struct Scatter<'a> {
    sets: &'a [PointSet],
    frame: &'a Frame,
}

impl Figure for Scatter<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check("scatter plot")?;
        finite(
            "scatter plot",
            self.sets
                .iter()
                .flat_map(|s| s.points.iter().flat_map(|p| [p.0, p.1])),
        )?;
        let labelled = self.sets.len() > 1 && self.sets.len() <= MAX_LEGEND;
        let mut chart = if labelled {
            chart_legend(root, self.frame)?
        } else {
            chart(root, self.frame)?
        };
        for (k, set) in self.sets.iter().enumerate() {
            let c = color(k);
            chart
                .draw_series(set.points.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(draw_err)?;
        }
        if labelled {
            let entries: Vec<_> = (self.sets.iter().enumerate())
                .map(|(k, set)| (set.label.as_str(), color(k)))
                .collect();
            legend(root, &chart, &entries)?;
        }
        Ok(())
    }
}

/// Points as filled circles (one `<circle>` each), one colour per set, the
/// labels in a legend when there are 2 to 12 sets.
pub fn scatter_svg(sets: &[PointSet], frame: &Frame) -> Result<String, ReportError> {
    to_svg(&Scatter { sets, frame })
}

/// [`scatter_svg`] as a PNG file.
pub fn scatter_png(sets: &[PointSet], frame: &Frame, path: &Path) -> Result<(), ReportError> {
    to_png(&Scatter { sets, frame }, path)
}
