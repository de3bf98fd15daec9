//! The calibration report's plots (psdcal-report draws them): the residual
//! fields of the data (per image, or averaged per cell over many images),
//! the model's distortion correction and a spiral through it, the valid
//! region's boundary (docs/model.md §8.2), and the arrow scales that make a
//! field of micrometres visible on a sensor of millimetres.

use nalgebra::Vector2;
use psdcal_model::psd::is_on_active_area;
use psdcal_model::{Model, SensorModel, ValidRegion};
use psdcal_report::{Arrow, ArrowSet, Frame, Plot, PlotData, PointSet};

use crate::calibration::residuals::ResidualTable;
use crate::dataset::data_set::DataSet;

/// The valid region's boundary where it folds inside the active area, as a
/// point set (docs/model.md §8.2).
pub(crate) fn region_boundary(region: &ValidRegion) -> PointSet {
    let area = region.geometry();
    PointSet {
        label: "valid region boundary (the correction folds beyond)".into(),
        points: region
            .boundary()
            .iter()
            .enumerate()
            .filter(|(i, p)| region.folds_on_ray(*i) && is_on_active_area(&area, p))
            .map(|(_, p)| (p.x, p.y))
            .collect(),
    }
}

/// The valid region's boundary where the correction folds, as polylines
/// for the distortion field: the runs of consecutive rays (docs/model.md
/// §8.2) whose boundary point is a fold inside `frame`'s ranges, a closed
/// loop when every ray is. Empty when the region holds the whole active area.
fn region_outline(region: &ValidRegion, frame: &Frame) -> Vec<Vec<(f64, f64)>> {
    if region.whole_active_area() {
        return Vec::new();
    }
    let points = region.boundary();
    let n = points.len();
    let within = |r: (f64, f64), v: f64| v >= r.0 && v <= r.1;
    let shown: Vec<bool> = (0..n)
        .map(|i| {
            let p = points[i];
            region.folds_on_ray(i) && within(frame.x_range, p.x) && within(frame.y_range, p.y)
        })
        .collect();
    let xy = |i: usize| (points[i].x, points[i].y);
    let Some(gap) = shown.iter().position(|s| !s) else {
        return vec![(0..=n).map(|i| xy(i % n)).collect()];
    };
    let mut lines = Vec::new();
    let mut line = Vec::new();
    for k in 1..=n {
        let i = (gap + k) % n;
        if shown[i] {
            line.push(xy(i));
        } else if !line.is_empty() {
            lines.push(std::mem::take(&mut line));
        }
    }
    lines
}

/// The valid region in one line, for the report's list.
pub(crate) fn region_text(region: &ValidRegion) -> String {
    let c = region.centre();
    match region.nearest_fold_mm() {
        _ if region.whole_active_area() => {
            "valid region: the whole active area (the correction is one-to-one there)".into()
        }
        Some(r) => format!(
            "valid region: NOT the whole active area — the distortion correction folds {r:.3} mm \
             from the optical centre ({:.3}, {:.3}) mm at the nearest; points beyond are \
             answered outside_valid_region (the boundary is drawn on the coverage and distortion-field plots)",
            c.x, c.y
        ),
        None => "valid region: not the whole active area (the optical centre is far off it)".into(),
    }
}

/// Coverage and residual plots of the data.
pub(crate) fn data_plots(
    plots: &mut Vec<Plot>,
    set: &DataSet,
    table: &ResidualTable,
    lx: f64,
    ly: f64,
) {
    let coverage: Vec<PointSet> = set
        .validated
        .images
        .iter()
        .map(|image| PointSet {
            label: image.id.clone(),
            points: image.points.iter().map(|(_, m)| (m.x, m.y)).collect(),
        })
        .collect();
    plots.push(Plot {
        name: "coverage",
        caption: format!(
            "{} measured points of {} images on the {lx} × {ly} mm active area (paper Figure 8)",
            set.validated.total_points(),
            set.validated.images.len()
        ),
        data: PlotData::Coverage {
            sets: coverage,
            lx,
            ly,
            frame: Frame::sensor("Coverage of the sensor by the images", lx, ly),
        },
    });
    let arrows = |sensor: bool| -> Vec<ArrowSet> {
        table
            .images
            .iter()
            .filter_map(|image| {
                let r = image.residuals.as_ref()?;
                Some(ArrowSet {
                    label: image.id.clone(),
                    arrows: r
                        .iter()
                        .filter_map(|p| {
                            let (at, e) = if sensor {
                                (p.measured, p.on_sensor?)
                            } else {
                                (p.template, p.on_template?)
                            };
                            Some(Arrow {
                                at: (at.x, at.y),
                                delta: (e.x, e.y),
                            })
                        })
                        .collect(),
                })
            })
            .collect()
    };
    let leds = set.template.leds.iter().map(|l| (l.x_mm, l.y_mm));
    for (name, sets, frame0, what) in [
        (
            "residuals_template",
            arrows(false),
            Frame::fit("Template-plane residuals", "X (mm)", "Y (mm)", leds),
            "template plane (back-projected point − LED)",
        ),
        (
            "residuals_sensor",
            arrows(true),
            Frame::sensor("Sensor residuals", lx, ly),
            "sensor (projected LED − measured point)",
        ),
    ] {
        let images = sets.len();
        let (sets, what) = if images > MAX_IMAGE_ARROWS {
            (
                vec![cell_means(&sets, &frame0, CELLS)],
                format!("{what}, mean per cell of a {CELLS} × {CELLS} grid over {images} images"),
            )
        } else {
            (sets, what.to_string())
        };
        let span = (frame0.x_range.1 - frame0.x_range.0).max(frame0.y_range.1 - frame0.y_range.0);
        let scale = arrow_scale(sets.iter().flat_map(|s| &s.arrows), span);
        let mut frame = frame0;
        frame.title = format!("{} × {}", frame.title, round_scale(scale));
        plots.push(Plot {
            name,
            caption: format!(
                "Residual vectors per image on the {what}, arrows scaled × {} (paper Figure 13)",
                round_scale(scale)
            ),
            data: PlotData::Residuals { sets, scale, frame },
        });
    }
    let sizes: Vec<f64> = table
        .images
        .iter()
        .filter_map(|im| im.residuals.as_ref())
        .flatten()
        .filter_map(|p| Some(1e3 * p.on_sensor?.norm()))
        .collect();
    let rms: Vec<f64> = table
        .images
        .iter()
        .filter_map(|im| im.rms().1.map(|r| 1e3 * r))
        .collect();
    if !rms.is_empty() {
        let worst = table
            .images
            .iter()
            .filter_map(|im| Some((im.rms().1?, im.id.as_str())))
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(String::new(), |(r, id)| {
                format!(
                    "; the largest, {} µm, is image {id}",
                    psdcal_report::num(1e3 * r)
                )
            });
        plots.push(Plot {
            name: "image_rms",
            caption: format!(
                "RMS sensor residual of each of the {} images, in file order{worst}",
                rms.len()
            ),
            data: PlotData::Bars {
                frame: psdcal_report::bar_frame(
                    "RMS residual per image",
                    "image (in file order)",
                    "RMS residual (µm)",
                    &rms,
                ),
                values: rms,
            },
        });
    }
    if !sizes.is_empty() {
        let bins = ((sizes.len() as f64).sqrt().round() as usize).clamp(5, 30);
        plots.push(Plot {
            name: "residual_histogram",
            caption: format!(
                "How large the {} sensor residuals are (projected LED − measured point)",
                sizes.len()
            ),
            data: PlotData::Histogram {
                values: sizes,
                bins,
                title: "Sensor residuals".into(),
                x_label: "residual (µm)".into(),
                y_label: "points".into(),
            },
        });
    }
}

/// Above this many images the residual plots show per-cell means.
const MAX_IMAGE_ARROWS: usize = 12;
/// Cells per side of the per-cell means.
const CELLS: usize = 10;

/// The mean residual of each cell of an `n × n` grid over the frame (at
/// the mean position of its points): one arrow per non-empty cell.
fn cell_means(sets: &[ArrowSet], frame: &Frame, n: usize) -> ArrowSet {
    let (x0, y0) = (frame.x_range.0, frame.y_range.0);
    let (w, h) = (
        (frame.x_range.1 - x0) / n as f64,
        (frame.y_range.1 - y0) / n as f64,
    );
    let mut sum = vec![(0.0, 0.0, 0.0, 0.0, 0usize); n * n];
    for a in sets.iter().flat_map(|s| &s.arrows) {
        let i = (((a.at.0 - x0) / w).floor().max(0.0) as usize).min(n - 1);
        let j = (((a.at.1 - y0) / h).floor().max(0.0) as usize).min(n - 1);
        let c = &mut sum[j * n + i];
        *c = (
            c.0 + a.at.0,
            c.1 + a.at.1,
            c.2 + a.delta.0,
            c.3 + a.delta.1,
            c.4 + 1,
        );
    }
    ArrowSet {
        label: "mean per cell".into(),
        arrows: sum
            .iter()
            .filter(|c| c.4 > 0)
            .map(|c| {
                let k = c.4 as f64;
                Arrow {
                    at: (c.0 / k, c.1 / k),
                    delta: (c.2 / k, c.3 / k),
                }
            })
            .collect(),
    }
}

/// The distortion field, the corrected spiral and the AoA sensitivity.
///
/// Only points inside the valid region are drawn (past a fold the
/// correction has no answer).
pub(crate) fn model_plots(
    plots: &mut Vec<Plot>,
    model: &SensorModel,
    region: &ValidRegion,
    lx: f64,
    ly: f64,
) {
    let n = 11;
    let chain = Model::standard(model);
    let field: Vec<Arrow> = (0..n * n)
        .filter_map(|k| {
            let m = Vector2::new(
                lx * (-0.45 + 0.9 * (k % n) as f64 / (n - 1) as f64),
                ly * (-0.45 + 0.9 * (k / n) as f64 / (n - 1) as f64),
            );
            let i = chain.ideal(&m);
            region.contains(&m).then_some(Arrow {
                at: (m.x, m.y),
                delta: (i.x - m.x, i.y - m.y),
            })
        })
        .collect();
    let scale = arrow_scale(field.iter(), lx.max(ly) * 1.1);
    let frame = Frame::sensor(
        &format!("Distortion correction × {}", round_scale(scale)),
        lx,
        ly,
    );
    let boundary = region_outline(region, &frame);
    plots.push(Plot {
        name: "distortion_field",
        caption: format!(
            "Correction of the calibrated model, measured → ideal point, arrows scaled × {} (paper Figure 16){}",
            round_scale(scale),
            if boundary.is_empty() {
                ""
            } else {
                "; black: the valid region's boundary, where the correction folds (no arrows beyond)"
            }
        ),
        data: PlotData::DistortionField {
            arrows: field,
            scale,
            boundary,
            frame,
        },
    });
    let (measured, corrected) = spiral(model, region, 0.45 * lx.min(ly));
    let frame = Frame::fit(
        "A measured spiral and its correction",
        "x (mm)",
        "y (mm)",
        measured.iter().chain(&corrected).copied(),
    );
    plots.push(Plot {
        name: "spiral",
        caption: "A spiral of measured points and the same points corrected by the model (paper Figure 16)".into(),
        data: PlotData::Spiral {
            measured,
            corrected,
            frame,
        },
    });
    let f = model.intrinsics.f;
    plots.push(Plot {
        name: "aoa_sensitivity",
        caption: format!(
            "Change of the angle of arrival per mm of error in x and in f, f = {f:.3} mm (paper Figure 6, P40–P41)"
        ),
        data: PlotData::Sensitivity {
            f,
            half_width: 0.5 * lx,
        },
    });
}

/// A scale that makes the longest arrow 8 % of `span`.
fn arrow_scale<'a>(arrows: impl Iterator<Item = &'a Arrow>, span: f64) -> f64 {
    let longest = arrows
        .map(|a| a.delta.0.hypot(a.delta.1))
        .filter(|l| l.is_finite())
        .fold(0.0, f64::max);
    arrow_scale_for(longest, span)
}

/// A scale that makes an arrow `longest` long 8 % of `span`, one
/// significant digit.
pub(crate) fn arrow_scale_for(longest: f64, span: f64) -> f64 {
    if longest > 0.0 && longest.is_finite() {
        let s = 0.08 * span / longest;
        // One significant digit, so the caption's factor is the exact one.
        let p = 10f64.powf(s.log10().floor());
        (s / p).floor().max(1.0) * p
    } else {
        1.0
    }
}

/// The text of an arrow scale.
pub(crate) fn scale_text(scale: f64) -> String {
    round_scale(scale)
}

fn round_scale(scale: f64) -> String {
    if scale >= 1.0 {
        format!("{scale:.0}")
    } else {
        format!("{scale}")
    }
}

/// Points on the sensor, mm.
type Points = Vec<(f64, f64)>;

/// A spiral of measured points of radius up to `radius` and its correction.
/// (only its part inside the valid region).
fn spiral(model: &SensorModel, region: &ValidRegion, radius: f64) -> (Points, Points) {
    let n = 120;
    let turns = 4.0;
    let chain = Model::standard(model);
    (0..n)
        .filter_map(|k| {
            let u = k as f64 / (n - 1) as f64;
            let t = u * turns * std::f64::consts::TAU;
            let m = Vector2::new(radius * u * t.cos(), radius * u * t.sin());
            let i = chain.ideal(&m);
            region.contains(&m).then_some(((m.x, m.y), (i.x, i.y)))
        })
        .unzip()
}
