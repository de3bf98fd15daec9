//! Line plots, and the AoA sensitivity to Δx and Δf (the paper's Figure 6,
//! equations P40–P41).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{
    chart, chart_legend, color, finite, legend, to_png, to_svg, Figure, Frame, PointSet,
};

struct Lines<'a> {
    curves: &'a [PointSet],
    frame: &'a Frame,
}

impl Figure for Lines<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check("line plot")?;
        finite(
            "line plot",
            self.curves
                .iter()
                .flat_map(|s| s.points.iter().flat_map(|p| [p.0, p.1])),
        )?;
        let labelled = self.curves.len() > 1;
        let mut chart = if labelled {
            chart_legend(root, self.frame)?
        } else {
            chart(root, self.frame)?
        };
        for (k, curve) in self.curves.iter().enumerate() {
            let c = color(k);
            chart
                .draw_series(LineSeries::new(
                    curve.points.iter().copied(),
                    c.stroke_width(2),
                ))
                .map_err(draw_err)?;
        }
        if labelled {
            let entries: Vec<_> = (self.curves.iter().enumerate())
                .map(|(k, curve)| (curve.label.as_str(), color(k)))
                .collect();
            legend(root, &chart, &entries)?;
        }
        Ok(())
    }
}

/// Curves as lines (one `<polyline>` each, one colour each, labels in the
/// legend).
pub fn line_plot_svg(curves: &[PointSet], frame: &Frame) -> Result<String, ReportError> {
    to_svg(&Lines { curves, frame })
}

/// [`line_plot_svg`] as a PNG file.
pub fn line_plot_png(curves: &[PointSet], frame: &Frame, path: &Path) -> Result<(), ReportError> {
    to_png(&Lines { curves, frame }, path)
}

/// The paper's AoA sensitivities (P40–P41) for focal length `f` mm over
/// `x ∈ [−half_width, half_width]` mm (`samples` points, at least 2):
/// `|∂αx/∂x| = |f/(f²+x²)|` and `|∂αx/∂f| = |x/(f²+x²)|`, in degrees per mm.
pub fn paper_sensitivity_curves(f: f64, half_width: f64, samples: usize) -> [PointSet; 2] {
    let n = samples.max(2);
    let xs: Vec<f64> = (0..n)
        .map(|k| -half_width + 2.0 * half_width * k as f64 / (n - 1) as f64)
        .collect();
    let curve = |label: String, g: &dyn Fn(f64) -> f64| PointSet {
        label,
        points: xs.iter().map(|&x| (x, g(x).to_degrees())).collect(),
    };
    [
        curve(format!("Δx: |f/(f²+x²)|, f = {f:.3} mm"), &|x| {
            (f / (f * f + x * x)).abs()
        }),
        curve(format!("Δf: |x/(f²+x²)|, f = {f:.3} mm"), &|x| {
            (x / (f * f + x * x)).abs()
        }),
    ]
}

/// [`line_plot_svg`] of [`paper_sensitivity_curves`] with its frame.
pub fn aoa_sensitivity_svg(f: f64, half_width: f64) -> Result<String, ReportError> {
    let curves = paper_sensitivity_curves(f, half_width, 101);
    let frame = Frame::fit(
        "AoA sensitivity to Δx and Δf (P40–P41)",
        "x (mm)",
        "deg per mm",
        curves
            .iter()
            .flat_map(|c| c.points.iter().copied())
            .chain([(0.0, 0.0)]),
    );
    line_plot_svg(&curves, &frame)
}
