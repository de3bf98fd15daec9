//! A 3-D view of the template poses relative to the sensor, drawn as an
//! oblique (orthographic) projection.
//!
//! Points are in the sensor frame (mm: `X`, `Y` across the sensor, `Z`
//! along the optical axis, towards the template). The view turns the scene
//! by the azimuth `a` about `Y`, then by the elevation `e` about the new
//! `X`, and drops the depth:
//!
//! ```text
//! x' = cos a · X + sin a · Z
//! y' = cos e · Y + sin e · (−sin a · X + cos a · Z)
//! ```
//!
//! so `Z` recedes up and to the right ([`VIEW_AZIMUTH_DEG`],
//! [`VIEW_ELEVATION_DEG`]). A parallel projection keeps parallel lines
//! parallel and one scale for every direction of the image plane; the
//! projected coordinates carry no axis ticks (they are no measure of any
//! one axis). The sensor frame's axes are drawn as labelled arrows of a
//! stated length, each template outline as a closed polygon and its LEDs
//! as dots; the legend sits right of the data.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{
    arrow_parts, color, finite, to_png, to_svg, Figure, FAMILY, LEGEND_WIDTH, MAX_LEGEND,
};

/// Azimuth of the view about the sensor's `Y` axis, degrees.
pub const VIEW_AZIMUTH_DEG: f64 = 55.0;
/// Elevation of the view, degrees.
pub const VIEW_ELEVATION_DEG: f64 = 25.0;

/// One template pose in the sensor frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseOutline {
    /// Legend label (user text: escaped in the SVG).
    pub label: String,
    /// The template's outline, a closed polygon (first point not repeated),
    /// sensor frame, mm.
    pub outline: Vec<[f64; 3]>,
    /// The LEDs, sensor frame, mm.
    pub leds: Vec<[f64; 3]>,
}

/// The projection of a sensor-frame point (module documentation).
pub fn project(p: [f64; 3]) -> (f64, f64) {
    let (sa, ca) = VIEW_AZIMUTH_DEG.to_radians().sin_cos();
    let (se, ce) = VIEW_ELEVATION_DEG.to_radians().sin_cos();
    (
        ca * p[0] + sa * p[2],
        ce * p[1] + se * (-sa * p[0] + ca * p[2]),
    )
}

struct Poses<'a> {
    poses: &'a [PoseOutline],
    /// Active area, mm.
    sensor: (f64, f64),
    axis_mm: f64,
    title: &'a str,
}

/// A round length as text (`100`, `0.5`).
fn round_length(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        format!("{}", (v * 1e9).round() / 1e9)
    }
}

/// A length of 1, 2 or 5 × 10ⁿ mm near a fifth of `extent`.
pub fn axis_length(extent: f64) -> f64 {
    let target = (0.2 * extent).max(1e-9);
    let p = 10f64.powf(target.log10().floor());
    let m = target / p;
    p * if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    }
}

impl Figure for Poses<'_> {
    fn size(&self) -> (u32, u32) {
        (720, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        finite(
            "pose view",
            self.poses
                .iter()
                .flat_map(|p| p.outline.iter().chain(&p.leds).flatten().copied()),
        )?;
        let axes = [
            ([self.axis_mm, 0.0, 0.0], "X"),
            ([0.0, self.axis_mm, 0.0], "Y"),
            ([0.0, 0.0, self.axis_mm], "Z (optical axis)"),
        ];
        let mut xs = vec![0.0];
        let mut ys = vec![0.0];
        for p in self
            .poses
            .iter()
            .flat_map(|p| p.outline.iter().chain(&p.leds))
            .copied()
            .chain(axes.iter().map(|a| a.0))
        {
            let (x, y) = project(p);
            xs.push(x);
            ys.push(y);
        }
        let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (x0, x1, y0, y1) = (lo(&xs), hi(&xs), lo(&ys), hi(&ys));
        // One scale on both axes: the plotting area is (720 − 24 − legend)
        // × (560 − 24 − caption) pixels; widen the shorter range to match.
        let (pw, ph) = (720.0 - 24.0 - LEGEND_WIDTH as f64, 560.0 - 24.0 - 40.0);
        let w = (x1 - x0).max(1e-9) * 1.1;
        let h = (y1 - y0).max(1e-9) * 1.1;
        let scale = (w / pw).max(h / ph);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let (hw, hh) = (0.5 * scale * pw, 0.5 * scale * ph);
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, (FAMILY, 20))
            .margin(12)
            .margin_right(12 + LEGEND_WIDTH)
            .build_cartesian_2d(cx - hw..cx + hw, cy - hh..cy + hh)
            .map_err(draw_err)?;
        let head = 0.03 * (2.0 * hw).max(2.0 * hh);
        for (end, name) in axes {
            let (shaft, tip) = arrow_parts((0.0, 0.0), project(end), head, BLACK.stroke_width(2));
            chart.draw_series([shaft]).map_err(draw_err)?;
            chart.draw_series([tip]).map_err(draw_err)?;
            let at = project(end);
            chart
                .draw_series([Text::new(
                    name.to_string(),
                    at,
                    (FAMILY, 15).into_font().color(&BLACK),
                )])
                .map_err(draw_err)?;
        }
        let (hx, hy) = (0.5 * self.sensor.0, 0.5 * self.sensor.1);
        let area: Vec<(f64, f64)> = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]
            .iter()
            .map(|&(x, y)| project([x, y, 0.0]))
            .collect();
        chart
            .draw_series([PathElement::new(area, BLACK.stroke_width(2))])
            .map_err(draw_err)?;
        let mut entries = vec![(
            format!("sensor; axes {} mm", round_length(self.axis_mm)),
            BLACK,
        )];
        let labelled = self.poses.len() <= MAX_LEGEND;
        for (k, pose) in self.poses.iter().enumerate() {
            let c = if labelled { color(k) } else { color(0) };
            let mut ring: Vec<(f64, f64)> = pose.outline.iter().map(|&p| project(p)).collect();
            if let Some(&first) = ring.first() {
                ring.push(first);
            }
            chart
                .draw_series([PathElement::new(ring, c.stroke_width(2))])
                .map_err(draw_err)?;
            if labelled {
                entries.push((pose.label.clone(), c));
            } else if k == 0 {
                entries.push((format!("{} template poses", self.poses.len()), c));
            }
            chart
                .draw_series(
                    pose.leds
                        .iter()
                        .map(|&p| Circle::new(project(p), 2, c.filled())),
                )
                .map_err(draw_err)?;
        }
        // The legend on the root area, in the column right of the data (a
        // series legend there would have its swatches clipped).
        let (w, _) = root.dim_in_pixel();
        let x = w as i32 - LEGEND_WIDTH as i32 - 14;
        for (k, (label, c)) in entries.iter().enumerate() {
            let y = 52 + 20 * k as i32;
            root.draw(&Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()))
                .map_err(draw_err)?;
            root.draw(&Text::new(
                label.clone(),
                (x + 18, y - 8),
                (FAMILY, 14).into_font().color(&BLACK),
            ))
            .map_err(draw_err)?;
        }
        Ok(())
    }
}

/// The view as SVG text: `sensor` the active area (mm); the axes' length is
/// chosen from the scene ([`axis_length`]).
pub fn poses_svg(
    poses: &[PoseOutline],
    sensor: (f64, f64),
    title: &str,
) -> Result<String, ReportError> {
    to_svg(&figure(poses, sensor, title))
}

/// [`poses_svg`] as a PNG file.
pub fn poses_png(
    poses: &[PoseOutline],
    sensor: (f64, f64),
    title: &str,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(&figure(poses, sensor, title), path)
}

fn figure<'a>(poses: &'a [PoseOutline], sensor: (f64, f64), title: &'a str) -> Poses<'a> {
    let extent = poses
        .iter()
        .flat_map(|p| p.outline.iter().chain(&p.leds))
        .map(|p| p.iter().map(|v| v.abs()).fold(0.0, f64::max))
        .filter(|v| v.is_finite())
        .fold(sensor.0.max(sensor.1), f64::max);
    Poses {
        poses,
        sensor,
        axis_mm: axis_length(extent),
        title,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_projection_is_the_stated_rotation() {
        // Orthographic: the projected length of a unit vector is at most 1,
        // and the three unit axes' squared projections sum to 2 (the trace
        // of a rank-2 orthogonal projector).
        let sum: f64 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .iter()
            .map(|&p| {
                let (x, y) = project(p);
                assert!(x * x + y * y <= 1.0 + 1e-12);
                x * x + y * y
            })
            .sum();
        assert!((sum - 2.0).abs() < 1e-12, "{sum}");
        // Z recedes up and to the right.
        let z = project([0.0, 0.0, 1.0]);
        assert!(z.0 > 0.0 && z.1 > 0.0);
        // Linear: the projection of a sum is the sum of the projections.
        let (a, b) = ([1.0, -2.0, 3.0], [0.5, 4.0, -1.0]);
        let s = project([a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
        let (pa, pb) = (project(a), project(b));
        assert!((s.0 - pa.0 - pb.0).abs() < 1e-12 && (s.1 - pa.1 - pb.1).abs() < 1e-12);
    }

    #[test]
    fn axis_lengths_are_round() {
        assert_eq!(axis_length(500.0), 100.0);
        assert_eq!(axis_length(1200.0), 200.0);
        assert_eq!(axis_length(30.0), 5.0);
    }

    #[test]
    fn the_view_draws_every_pose_and_escapes_labels() {
        let pose = |k: usize, z: f64| PoseOutline {
            label: format!("im<{k}>"),
            outline: vec![
                [-100.0, -100.0, z],
                [100.0, -100.0, z],
                [100.0, 100.0, z + 30.0],
                [-100.0, 100.0, z + 30.0],
            ],
            leds: vec![[0.0, 0.0, z + 15.0], [50.0, 50.0, z + 22.0]],
        };
        let poses: Vec<_> = (0..3).map(|k| pose(k, 400.0 + 50.0 * k as f64)).collect();
        let svg = poses_svg(&poses, (9.0, 9.0), "Template poses").unwrap();
        assert!(svg.contains("im&lt;2&gt;"), "labels escaped");
        assert!(svg.contains("Z (optical axis)"));
        assert!(svg.contains("axes 100 mm"));
        assert!(!svg.contains("<script"));
        // 3 outlines + the active area, each a polyline.
        assert!(svg.matches("<polyline").count() >= 4);
        let many: Vec<_> = (0..40).map(|k| pose(k, 400.0 + 5.0 * k as f64)).collect();
        let svg = poses_svg(&many, (9.0, 9.0), "Template poses").unwrap();
        assert!(svg.contains("40 template poses"));
        let bad = vec![PoseOutline {
            label: "x".into(),
            outline: vec![[f64::NAN, 0.0, 1.0]],
            leds: Vec::new(),
        }];
        assert!(poses_svg(&bad, (9.0, 9.0), "t").is_err());
    }
}
