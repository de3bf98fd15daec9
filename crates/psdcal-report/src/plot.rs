//! What every figure shares: the bundled font, the frame (title, axis labels
//! and ranges), colours, arrows, and rendering to SVG text or a PNG file.

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};

/// DejaVu Sans (Bitstream Vera licence, see assets/DejaVuSans-LICENSE.txt):
/// text never depends on a system font.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The font family every figure uses.
pub(crate) const FAMILY: &str = "sans-serif";

/// Registers the bundled font once.
pub(crate) fn ensure_font() -> Result<(), ReportError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(ReportError::Font)
    }
}

/// Title, axis labels and axis ranges of a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis (with its unit).
    pub x_label: String,
    /// Label of the y axis (with its unit).
    pub y_label: String,
    /// Range of the x axis.
    pub x_range: (f64, f64),
    /// Range of the y axis.
    pub y_range: (f64, f64),
}

impl Frame {
    /// A frame with explicit ranges.
    pub fn new(
        title: &str,
        x_label: &str,
        y_label: &str,
        x_range: (f64, f64),
        y_range: (f64, f64),
    ) -> Self {
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            x_range,
            y_range,
        }
    }

    /// A frame whose ranges hold every finite point, with a 5 % margin.
    pub fn fit(
        title: &str,
        x_label: &str,
        y_label: &str,
        points: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        let mut x = (f64::INFINITY, f64::NEG_INFINITY);
        let mut y = (f64::INFINITY, f64::NEG_INFINITY);
        for (px, py) in points {
            if px.is_finite() && py.is_finite() {
                x = (x.0.min(px), x.1.max(px));
                y = (y.0.min(py), y.1.max(py));
            }
        }
        Self::new(title, x_label, y_label, pad(x), pad(y))
    }

    /// The sensor's active area `lx × ly` mm centred on the origin, with a
    /// 10 % margin.
    pub fn sensor(title: &str, lx: f64, ly: f64) -> Self {
        Self::new(
            title,
            "x (mm)",
            "y (mm)",
            (-0.55 * lx, 0.55 * lx),
            (-0.55 * ly, 0.55 * ly),
        )
    }

    pub(crate) fn check(&self, what: &'static str) -> Result<(), ReportError> {
        let ok = |r: (f64, f64)| r.0.is_finite() && r.1.is_finite() && r.1 > r.0;
        if ok(self.x_range) && ok(self.y_range) {
            Ok(())
        } else {
            Err(ReportError::InvalidData {
                what,
                reason: format!(
                    "empty or invalid axis range x {:?}, y {:?}",
                    self.x_range, self.y_range
                ),
            })
        }
    }
}

/// A range with a 5 % margin; a single value or nothing gets a unit width.
pub(crate) fn pad(r: (f64, f64)) -> (f64, f64) {
    if !(r.0.is_finite() && r.1.is_finite()) {
        return (0.0, 1.0);
    }
    let w = r.1 - r.0;
    if w <= 0.0 {
        let h = if r.0 == 0.0 { 0.5 } else { 0.5 * r.0.abs() };
        return (r.0 - h, r.1 + h);
    }
    (r.0 - 0.05 * w, r.1 + 0.05 * w)
}

/// An arrow from `at` along `delta` (the plot scales `delta`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrow {
    /// Where the arrow starts.
    pub at: (f64, f64),
    /// Its direction and length, in the data's unit before scaling.
    pub delta: (f64, f64),
}

/// Points with a label (one image, one series).
#[derive(Debug, Clone, PartialEq)]
pub struct PointSet {
    /// Legend label (user text: escaped in the SVG).
    pub label: String,
    /// The points.
    pub points: Vec<(f64, f64)>,
}

/// Arrows with a label (the residuals of one image).
#[derive(Debug, Clone, PartialEq)]
pub struct ArrowSet {
    /// Legend label (user text: escaped in the SVG).
    pub label: String,
    /// The arrows.
    pub arrows: Vec<Arrow>,
}

/// Series colours (Tableau 10).
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// The colour of series `k`.
pub(crate) fn color(k: usize) -> RGBColor {
    let (r, g, b) = PALETTE[k % PALETTE.len()];
    RGBColor(r, g, b)
}

/// At most this many series get a legend entry.
pub(crate) const MAX_LEGEND: usize = 12;

/// A figure drawn on any backend.
pub(crate) trait Figure {
    /// Width and height in pixels.
    fn size(&self) -> (u32, u32) {
        (640, 560)
    }
    /// Draws on a white area.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError>;
}

/// The figure as SVG text.
pub(crate) fn to_svg<F: Figure>(figure: &F) -> Result<String, ReportError> {
    ensure_font()?;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, figure.size()).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        figure.draw(&root)?;
        root.present().map_err(draw_err)?;
    }
    Ok(buf)
}

/// The figure as a PNG file.
pub(crate) fn to_png<F: Figure>(figure: &F, path: &Path) -> Result<(), ReportError> {
    ensure_font()?;
    let root = BitMapBackend::new(path, figure.size()).into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    figure.draw(&root)?;
    root.present().map_err(|e| ReportError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

/// Tick labels per axis at most (plotters' ticks are then at least
/// `range / MAX_TICKS` apart).
const MAX_TICKS: usize = 8;

/// The text of a tick at `v` on an axis over `range`: enough decimals (or
/// mantissa digits, in scientific notation beyond 1e-3…1e5) that ticks
/// `range / (2 MAX_TICKS)` apart never print alike; `-0` printed `0`.
pub fn tick_label(v: f64, range: (f64, f64)) -> String {
    let step = ((range.1 - range.0).abs() / (2 * MAX_TICKS) as f64).max(f64::MIN_POSITIVE);
    let magnitude = range.0.abs().max(range.1.abs());
    let text = if !(1e-3..1e5).contains(&magnitude) {
        let digits = ((magnitude / step).log10().ceil().max(0.0) as usize).min(12);
        format!("{v:.digits$e}")
    } else {
        let decimals = ((-step.log10()).ceil().max(0.0) as usize).min(12);
        format!("{v:.decimals$}")
    };
    if text.starts_with('-') && text[1..].chars().all(|c| c == '0' || c == '.') {
        text[1..].to_string()
    } else {
        text
    }
}

/// The text of a tick on a count axis: integers only (other ticks blank).
pub fn count_label(v: f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{}", v.round().abs() as u64)
    } else {
        String::new()
    }
}

/// A chart in data coordinates (mm, degrees or counts on both axes).
pub(crate) type Chart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// The chart of a frame on `area`, with its mesh and axis labels drawn.
pub(crate) fn chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: &Frame,
) -> Result<Chart<'a, DB>, ReportError> {
    build_chart(area, frame, false, false, false)
}

/// [`chart`] with room on the right for a legend outside the data
/// ([`legend`]).
pub(crate) fn chart_legend<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: &Frame,
) -> Result<Chart<'a, DB>, ReportError> {
    build_chart(area, frame, false, false, true)
}

/// Width of the legend column right of the data, pixels.
pub(crate) const LEGEND_WIDTH: u32 = 150;

/// [`chart`], an axis a count axis (integer tick labels) when `x_counts`
/// or `y_counts`.
pub(crate) fn chart_with<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: &Frame,
    x_counts: bool,
    y_counts: bool,
) -> Result<Chart<'a, DB>, ReportError> {
    build_chart(area, frame, x_counts, y_counts, false)
}

/// The chart: count axes as asked, and a legend column when `legend`.
pub(crate) fn build_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: &Frame,
    x_counts: bool,
    y_counts: bool,
    legend: bool,
) -> Result<Chart<'a, DB>, ReportError> {
    let mut chart = ChartBuilder::on(area)
        .caption(&frame.title, (FAMILY, 20))
        .margin(12)
        .margin_right(if legend { 12 + LEGEND_WIDTH } else { 12 })
        .x_label_area_size(48)
        .y_label_area_size(78)
        .build_cartesian_2d(
            frame.x_range.0..frame.x_range.1,
            frame.y_range.0..frame.y_range.1,
        )
        .map_err(draw_err)?;
    let (xr, yr) = (frame.x_range, frame.y_range);
    let x_fmt = move |v: &f64| {
        if x_counts {
            count_label(*v)
        } else {
            tick_label(*v, xr)
        }
    };
    let y_fmt = move |v: &f64| {
        if y_counts {
            count_label(*v)
        } else {
            tick_label(*v, yr)
        }
    };
    chart
        .configure_mesh()
        .x_desc(frame.x_label.as_str())
        .y_desc(frame.y_label.as_str())
        .x_labels(MAX_TICKS)
        .y_labels(MAX_TICKS)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FAMILY, 15))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.12))
        .draw()
        .map_err(draw_err)?;
    Ok(chart)
}

/// The legend of a chart, in the column [`chart_legend`] keeps right of its
/// plotting area, drawn on the figure's `root` area: each entry a colour
/// swatch and its label. (A plotters series legend placed there would have
/// its swatches clipped to the plotting area.)
pub(crate) fn legend<DB: DrawingBackend, X: Ranged, Y: Ranged>(
    root: &DrawingArea<DB, Shift>,
    chart: &ChartContext<'_, DB, Cartesian2d<X, Y>>,
    entries: &[(&str, RGBColor)],
) -> Result<(), ReportError> {
    let area = chart.plotting_area();
    let (x0, y0) = area.get_base_pixel();
    let (r0, s0) = root.get_base_pixel();
    let x = x0 - r0 + area.dim_in_pixel().0 as i32 + 12;
    for (k, (label, c)) in entries.iter().enumerate() {
        let y = y0 - s0 + 10 + 20 * k as i32;
        root.draw(&Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()))
            .map_err(draw_err)?;
        root.draw(&Text::new(
            label.to_string(),
            (x + 18, y - 8),
            (FAMILY, 14).into_font().color(&BLACK),
        ))
        .map_err(draw_err)?;
    }
    Ok(())
}

/// A data point.
type Xy = (f64, f64);

/// The shaft (a path) and the head (a polygon) of an arrow from `a` to `b`,
/// the head `head` long in data units.
pub(crate) fn arrow_parts(
    a: (f64, f64),
    b: (f64, f64),
    head: f64,
    style: ShapeStyle,
) -> (PathElement<Xy>, Polygon<Xy>) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len = dx.hypot(dy);
    let h = head.min(0.4 * len);
    let (ux, uy) = if len > 0.0 {
        (dx / len, dy / len)
    } else {
        (1.0, 0.0)
    };
    let base = (b.0 - h * ux, b.1 - h * uy);
    let w = 0.45 * h;
    let left = (base.0 - w * uy, base.1 + w * ux);
    let right = (base.0 + w * uy, base.1 - w * ux);
    (
        PathElement::new(vec![a, b], style),
        Polygon::new(vec![b, left, right], style.color.filled()),
    )
}

/// Fails when a value is not finite.
pub(crate) fn finite(
    what: &'static str,
    values: impl IntoIterator<Item = f64>,
) -> Result<(), ReportError> {
    if values.into_iter().all(f64::is_finite) {
        Ok(())
    } else {
        Err(ReportError::InvalidData {
            what,
            reason: "a value is not finite".into(),
        })
    }
}
