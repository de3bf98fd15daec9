//! Monte Carlo histograms of a parameter against its truth.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{draw_err, ReportError};
use crate::plot::{build_chart, color, finite, pad, to_png, to_svg, Figure, Frame};

/// The counts of `values` in `bins` equal bins over `[lo, hi]` (the last
/// bin closed).
pub fn bin_counts(values: &[f64], bins: usize, lo: f64, hi: f64) -> Vec<usize> {
    let bins = bins.max(1);
    let mut counts = vec![0; bins];
    let width = (hi - lo) / bins as f64;
    for &v in values {
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            continue;
        }
        let k = if width > 0.0 {
            (((v - lo) / width) as usize).min(bins - 1)
        } else {
            0
        };
        counts[k] += 1;
    }
    counts
}

struct Histogram<'a> {
    values: &'a [f64],
    truth: Option<f64>,
    bins: usize,
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    /// Width and height, pixels.
    size: (u32, u32),
}

/// The size of a histogram against the truth: compact, so that its text
/// stays readable when three share a row or at a phone's width.
const TRUTH_SIZE: (u32, u32) = (400, 300);
/// The size of a counts histogram.
const COUNTS_SIZE: (u32, u32) = (640, 560);

impl Histogram<'_> {
    fn range(&self) -> (f64, f64) {
        let (lo, hi) = self
            .values
            .iter()
            .chain(self.truth.as_ref())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if hi > lo {
            (lo, hi)
        } else {
            pad((lo, hi))
        }
    }
}

impl Figure for Histogram<'_> {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        if self.values.is_empty() {
            return Err(ReportError::InvalidData {
                what: "histogram",
                reason: "no values".into(),
            });
        }
        finite("histogram", self.values.iter().copied().chain(self.truth))?;
        let (lo, hi) = self.range();
        let counts = bin_counts(self.values, self.bins, lo, hi);
        let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64;
        let frame = Frame::new(
            self.title,
            self.x_label,
            self.y_label,
            pad((lo, hi)),
            (0.0, 1.1 * top),
        );
        let mut chart = build_chart(root, &frame, false, true, false)?;
        let width = (hi - lo) / counts.len() as f64;
        let fill = color(0).mix(0.75).filled();
        chart
            .draw_series(
                counts
                    .iter()
                    .enumerate()
                    .filter(|(_, n)| **n > 0)
                    .map(|(k, n)| {
                        let x0 = lo + k as f64 * width;
                        Rectangle::new([(x0, 0.0), (x0 + width, *n as f64)], fill)
                    }),
            )
            .map_err(draw_err)?;
        if let Some(t) = self.truth {
            let red = color(3);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(t, 0.0), (t, 1.1 * top)],
                    red.stroke_width(2),
                )))
                .map_err(draw_err)?;
        }
        Ok(())
    }
}

/// A histogram of `values` in `bins` equal bins (one `<rect>` per non-empty
/// bin) with the true value as a red vertical line when given (one line:
/// no legend; the caption says what it is).
pub fn histogram_svg(
    values: &[f64],
    truth: Option<f64>,
    bins: usize,
    title: &str,
    x_label: &str,
) -> Result<String, ReportError> {
    to_svg(&Histogram {
        values,
        truth,
        bins,
        title,
        x_label,
        y_label: "trials",
        size: TRUTH_SIZE,
    })
}

/// [`histogram_svg`] as a PNG file.
pub fn histogram_png(
    values: &[f64],
    truth: Option<f64>,
    bins: usize,
    title: &str,
    x_label: &str,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(
        &Histogram {
            values,
            truth,
            bins,
            title,
            x_label,
            y_label: "trials",
            size: TRUTH_SIZE,
        },
        path,
    )
}

/// A histogram of `values` in `bins` equal bins with a labelled count axis
/// (integer ticks) and no truth line.
pub fn counts_histogram_svg(
    values: &[f64],
    bins: usize,
    title: &str,
    x_label: &str,
    y_label: &str,
) -> Result<String, ReportError> {
    to_svg(&Histogram {
        values,
        truth: None,
        bins,
        title,
        x_label,
        y_label,
        size: COUNTS_SIZE,
    })
}

/// [`counts_histogram_svg`] as a PNG file.
pub fn counts_histogram_png(
    values: &[f64],
    bins: usize,
    title: &str,
    x_label: &str,
    y_label: &str,
    path: &Path,
) -> Result<(), ReportError> {
    to_png(
        &Histogram {
            values,
            truth: None,
            bins,
            title,
            x_label,
            y_label,
            size: COUNTS_SIZE,
        },
        path,
    )
}
