//! Image coverage on the sensor (the paper's Figure 8).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{
    chart, chart_legend, color, finite, legend, to_png, to_svg, Figure, Frame, PointSet, MAX_LEGEND,
};

struct Coverage<'a> {
    images: &'a [PointSet],
    lx: f64,
    ly: f64,
    frame: &'a Frame,
}

impl Figure for Coverage<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        self.frame.check("coverage")?;
        finite(
            "coverage",
            self.images
                .iter()
                .flat_map(|s| s.points.iter().flat_map(|p| [p.0, p.1])),
        )?;
        let labelled = self.images.len() <= MAX_LEGEND && !self.images.is_empty();
        let mut chart = if labelled {
            chart_legend(root, self.frame)?
        } else {
            chart(root, self.frame)?
        };
        let (hx, hy) = (0.5 * self.lx, 0.5 * self.ly);
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)],
                BLACK.stroke_width(2),
            )))
            .map_err(draw_err)?;
        for (k, set) in self.images.iter().enumerate() {
            let c = color(k);
            chart
                .draw_series(set.points.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(draw_err)?;
        }
        if labelled {
            let entries: Vec<_> = (self.images.iter().enumerate())
                .map(|(k, set)| (set.label.as_str(), color(k)))
                .collect();
            legend(root, &chart, &entries)?;
        }
        Ok(())
    }
}

/// The measured points of each image on the sensor's `lx × ly` mm active
/// area (outlined): one circle per point, one colour per image, the image
/// labels in the legend (up to 12 images).
pub fn coverage_svg(
    images: &[PointSet],
    lx: f64,
    ly: f64,
    frame: &Frame,
) -> Result<String, ReportError> {
    to_svg(&Coverage {
        images,
        lx,
        ly,
        frame,
    })
}

/// [`coverage_svg`] as a PNG file.
pub fn coverage_png(
    images: &[PointSet],
    lx: f64,
    ly: f64,
    frame: &Frame,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(
        &Coverage {
            images,
            lx,
            ly,
            frame,
        },
        path,
    )
}
