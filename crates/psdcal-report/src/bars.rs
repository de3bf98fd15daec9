//! Bar charts: one bar per item (an image's RMS error), items numbered
//! 1, 2, … along x in their order (integer ticks).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{chart_with, color, finite, to_png, to_svg, Figure, Frame};

struct Bars<'a> {
    values: &'a [f64],
    frame: &'a Frame,
}

impl Figure for Bars<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check("bar chart")?;
        finite("bar chart", self.values.iter().copied())?;
        let mut chart = chart_with(root, self.frame, true, false)?;
        let fill = color(0).mix(0.8).filled();
        chart
            .draw_series(self.values.iter().enumerate().map(|(k, &v)| {
                let x = (k + 1) as f64;
                Rectangle::new([(x - 0.4, 0.0), (x + 0.4, v)], fill)
            }))
            .map_err(draw_err)?;
        Ok(())
    }
}

/// A bar (one `<rect>`) per value at x = 1, 2, …; `frame` sets the
/// ranges (see [`bar_frame`]).
pub fn bar_chart_svg(values: &[f64], frame: &Frame) -> Result<String, ReportError> {
    to_svg(&Bars { values, frame })
}

/// [`bar_chart_svg`] as a PNG file.
pub fn bar_chart_png(values: &[f64], frame: &Frame, path: &Path) -> Result<(), ReportError> {
    to_png(&Bars { values, frame }, path)
}

/// The frame of a bar chart of `values`: x from 0.4 to n + 0.6, y from 0
/// to 5 % above the largest value.
pub fn bar_frame(title: &str, x_label: &str, y_label: &str, values: &[f64]) -> Frame {
    let top = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    Frame::new(
        title,
        x_label,
        y_label,
        (0.4, values.len() as f64 + 0.6),
        (0.0, if top > 0.0 { 1.05 * top } else { 1.0 }),
    )
}
