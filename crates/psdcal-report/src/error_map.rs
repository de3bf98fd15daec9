//! AoA and position error maps as heat maps (the paper's Figure 9).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{chart, finite, to_png, to_svg, Figure, Frame, FAMILY};

/// Steps of the colour bar (one `<rect>` each).
pub const COLORBAR_STEPS: usize = 32;

/// Viridis, sampled.
const STOPS: [(f64, f64, f64); 5] = [
    (68.0, 1.0, 84.0),
    (59.0, 82.0, 139.0),
    (33.0, 145.0, 140.0),
    (94.0, 201.0, 98.0),
    (253.0, 231.0, 37.0),
];

/// The colour of `t` in [0, 1].
fn heat(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (STOPS.len() - 1) as f64;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let u = s - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * u).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// One cell of a heat map: its centre and value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeatCell {
    /// Centre x.
    pub x: f64,
    /// Centre y.
    pub y: f64,
    /// The value.
    pub value: f64,
}

struct HeatMap<'a> {
    cells: &'a [HeatCell],
    cell_size: (f64, f64),
    frame: &'a Frame,
    value_label: &'a str,
}

impl Figure for HeatMap<'_> {
    fn size(&self) -> (u32, u32) {
        (500, 420)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check("heat map")?;
        if self.cells.is_empty() {
            return Err(ReportError::InvalidData {
                what: "heat map",
                reason: "no cells".into(),
            });
        }
        finite(
            "heat map",
            self.cells.iter().flat_map(|c| [c.x, c.y, c.value]),
        )?;
        let lo = self
            .cells
            .iter()
            .map(|c| c.value)
            .fold(f64::INFINITY, f64::min);
        let mut hi = self
            .cells
            .iter()
            .map(|c| c.value)
            .fold(f64::NEG_INFINITY, f64::max);
        if hi <= lo {
            hi = lo + if lo == 0.0 { 1.0 } else { lo.abs() * 1e-3 };
        }
        let width = root.dim_in_pixel().0;
        let (left, right) = root.split_horizontally(width.saturating_sub(124));
        let mut chart = chart(&left, self.frame)?;
        // 20 % more than a cell (a pixel or more at the figure's size):
        // neighbours overlap, so no hairline of the background shows between
        // cells when the scaled SVG is antialiased (plotters rounds to whole
        // pixels, and abutting cells would leave seams).
        let (w, h) = (0.6 * self.cell_size.0, 0.6 * self.cell_size.1);
        chart
            .draw_series(self.cells.iter().map(|c| {
                Rectangle::new(
                    [(c.x - w, c.y - h), (c.x + w, c.y + h)],
                    heat((c.value - lo) / (hi - lo)).filled(),
                )
            }))
            .map_err(draw_err)?;
        let mut bar = ChartBuilder::on(&right)
            .margin_top(42)
            .margin_bottom(54)
            .margin_right(8)
            .y_label_area_size(78)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(draw_err)?;
        bar.configure_mesh()
            .disable_x_mesh()
            .disable_y_mesh()
            .disable_x_axis()
            .y_desc(self.value_label)
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 16))
            .y_labels(8)
            .y_label_formatter(&|v| crate::plot::tick_label(*v, (lo, hi)))
            .draw()
            .map_err(draw_err)?;
        let step = (hi - lo) / COLORBAR_STEPS as f64;
        bar.draw_series((0..COLORBAR_STEPS).map(|k| {
            let v0 = lo + k as f64 * step;
            // Each step overlaps the next (no seams); the last ends at `hi`.
            let v1 = if k + 1 < COLORBAR_STEPS {
                v0 + 1.5 * step
            } else {
                hi
            };
            Rectangle::new(
                [(0.0, v0), (1.0, v1)],
                heat((k as f64 + 0.5) / COLORBAR_STEPS as f64).filled(),
            )
        }))
        .map_err(draw_err)?;
        Ok(())
    }
}

/// A heat map: one filled `<rect>` per cell (`cell_size` wide and high,
/// viridis colours from the smallest to the largest value) and a colour bar
/// of [`COLORBAR_STEPS`] rects labelled `value_label`.
pub fn heat_map_svg(
    cells: &[HeatCell],
    cell_size: (f64, f64),
    frame: &Frame,
    value_label: &str,
) -> Result<String, ReportError> {
    to_svg(&HeatMap {
        cells,
        cell_size,
        frame,
        value_label,
    })
}

/// [`heat_map_svg`] as a PNG file.
pub fn heat_map_png(
    cells: &[HeatCell],
    cell_size: (f64, f64),
    frame: &Frame,
    value_label: &str,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(
        &HeatMap {
            cells,
            cell_size,
            frame,
            value_label,
        },
        path,
    )
}

/// The spacing of a regular grid along one axis: the smallest positive gap
/// between distinct sorted coordinates (1 when there is none).
pub fn grid_step(coordinates: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = coordinates.into_iter().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let step = v
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 1e-12)
        .fold(f64::INFINITY, f64::min);
    if step.is_finite() {
        step
    } else {
        1.0
    }
}
