//! Two views of a calibration report beyond the fit's own plots:
//!
//! - **the template poses in 3-D**: each image's template outline (the
//!   convex hull of the LEDs on the template plane, `Z_t = 0`) and LEDs
//!   carried into the sensor frame by the image's pose, `P_s = R P_t + t`
//!   (CONVENTIONS.md), for psdcal-report's oblique view;
//! - **the PSD map** when the calibration carries one (docs/model.md §8.3):
//!   its displacement `d(m) = m' − m` (measured point → corrected point) as
//!   arrows on an 11 × 11 grid and `|d|` in µm as a heat map on a 21 × 21
//!   grid over the active area, only inside the map's domain (its scan's
//!   hull), and the map's own 1σ uncertainty `√(tr J_a C_m J_aᵀ)` in µm
//!   when the calibration stores its covariance; and, when the calibration
//!   stores its scan's summary (the stage's `scan`), the scan's residuals
//!   (stage position − corrected point, outliers left out) per cell of the
//!   map's frame: the mean residual as an arrow from the cell's centre, the
//!   scan's hull drawn, and the RMS residual as a heat map, with the fit's
//!   numbers in one line of the report's list (`map_text`).

use nalgebra::{Vector2, Vector3};
use psdcal_io::{Calibration, PsdMapScanRecord, PsdMapStageRecord, Template};
use psdcal_locate::CalibratedSensor;
use psdcal_model::stages::PsdMap;
use psdcal_model::ConvexHull;
use psdcal_report::{Arrow, Frame, HeatCell, Plot, PlotData, PoseOutline};

/// At most this many poses are drawn (evenly spaced in file order).
pub(crate) const MAX_POSES: usize = 60;
/// Grid points per side of the map's arrows.
const ARROW_GRID: usize = 11;
/// Grid points per side of the map's heat maps.
const HEAT_GRID: usize = 21;

/// The 3-D view of the template poses, or `None` without LEDs or images.
pub(crate) fn pose_plot(calibration: &Calibration, template: &Template) -> Option<Plot> {
    let leds: Vec<Vector2<f64>> = template
        .leds
        .iter()
        .map(|l| Vector2::new(l.x_mm, l.y_mm))
        .collect();
    let outline: Vec<Vector2<f64>> = match ConvexHull::of_points(&leds) {
        Ok(h) => h.vertices().to_vec(),
        Err(_) => leds.clone(),
    };
    let n = calibration.images.len();
    if leds.is_empty() || n == 0 {
        return None;
    }
    let shown: Vec<usize> = if n <= MAX_POSES {
        (0..n).collect()
    } else {
        (0..MAX_POSES)
            .map(|k| k * (n - 1) / (MAX_POSES - 1))
            .collect()
    };
    let poses: Vec<PoseOutline> = shown
        .iter()
        .map(|&i| {
            let image = &calibration.images[i];
            let pose = image.pose();
            let carry = |p: &Vector2<f64>| {
                let s = pose.transform(&Vector3::new(p.x, p.y, 0.0));
                [s.x, s.y, s.z]
            };
            PoseOutline {
                label: image.id.clone(),
                outline: outline.iter().map(carry).collect(),
                leds: leds.iter().map(carry).collect(),
            }
        })
        .collect();
    let geometry = calibration.geometry();
    let subset = if n > MAX_POSES {
        format!(" ({} of {n}, evenly spaced in file order)", poses.len())
    } else {
        String::new()
    };
    Some(Plot {
        name: "template_poses",
        caption: format!(
            "Where the template was: {} calibrated poses{subset} in the sensor frame, seen \
             obliquely (X, Y across the sensor, Z along the optical axis towards the \
             template); each outline joins the outermost LEDs, dots are the LEDs",
            poses.len()
        ),
        data: PlotData::Poses {
            poses,
            sensor: (geometry.lx, geometry.ly),
            title: "Template poses relative to the sensor".into(),
        },
    })
}

/// Grid points over the active area inside the map's domain.
fn grid(lx: f64, ly: f64, n: usize) -> impl Iterator<Item = Vector2<f64>> {
    (0..n * n).map(move |k| {
        Vector2::new(
            lx * (-0.5 + (k % n) as f64 / (n - 1) as f64),
            ly * (-0.5 + (k / n) as f64 / (n - 1) as f64),
        )
    })
}

/// The PSD map's plots (field, magnitude, its own uncertainty, and its
/// scan's residuals when `scan` is given), empty without a map.
pub(crate) fn map_plots(sensor: &CalibratedSensor, scan: Option<&PsdMapScanRecord>) -> Vec<Plot> {
    let Some(map) = &sensor.psd_map else {
        return Vec::new();
    };
    let (lx, ly) = (sensor.geometry.lx, sensor.geometry.ly);
    let arrows: Vec<Arrow> = grid(lx, ly, ARROW_GRID)
        .filter(|m| map.contains(m))
        .map(|m| {
            let d = map.correct(&m).point - m;
            Arrow {
                at: (m.x, m.y),
                delta: (d.x, d.y),
            }
        })
        .collect();
    let heat: Vec<HeatCell> = grid(lx, ly, HEAT_GRID)
        .filter(|m| map.contains(m))
        .map(|m| HeatCell {
            x: m.x,
            y: m.y,
            value: 1e3 * (map.correct(&m).point - m).norm(),
        })
        .collect();
    if arrows.is_empty() || heat.is_empty() {
        return Vec::new();
    }
    let step = (lx / (HEAT_GRID - 1) as f64, ly / (HEAT_GRID - 1) as f64);
    let largest = heat.iter().map(|c| c.value).fold(0.0, f64::max);
    let longest = arrows
        .iter()
        .map(|a| a.delta.0.hypot(a.delta.1))
        .fold(0.0, f64::max);
    let scale = crate::reports::calibration_plots::arrow_scale_for(longest, 1.1 * lx.max(ly));
    let mut plots = vec![
        Plot {
            name: "psd_map_field",
            caption: format!(
                "The PSD map (the sensor's own non-linearity, from a lensless scan): measured \
                 → corrected point, arrows scaled × {}, drawn where the scan reached",
                crate::reports::calibration_plots::scale_text(scale)
            ),
            data: PlotData::DistortionField {
                arrows,
                scale,
                boundary: Vec::new(),
                frame: Frame::sensor(
                    &format!(
                        "PSD map × {}",
                        crate::reports::calibration_plots::scale_text(scale)
                    ),
                    lx,
                    ly,
                ),
            },
        },
        Plot {
            name: "psd_map_magnitude",
            caption: format!(
                "Size of the PSD map's correction over the active area, largest {} µm \
                 (blank: outside the scan)",
                psdcal_report::num(largest)
            ),
            data: PlotData::HeatMap {
                cells: heat,
                step,
                frame: Frame::sensor("PSD map correction size", lx, ly),
                label: "correction (µm)".into(),
            },
        },
    ];
    if let Some(cells) = map_sigma(sensor, lx, ly) {
        let largest = cells.iter().map(|c| c.value).fold(0.0, f64::max);
        plots.push(Plot {
            name: "psd_map_uncertainty",
            caption: format!(
                "The PSD map's own uncertainty (1σ: its scan's fit, or, refined by the \
                 calibration, the scan and the calibration data together), largest {} µm",
                psdcal_report::num(largest)
            ),
            data: PlotData::HeatMap {
                cells,
                step,
                frame: Frame::sensor("PSD map uncertainty, 1σ", lx, ly),
                label: "1σ (µm)".into(),
            },
        });
    }
    if let Some(scan) = scan {
        plots.extend(scan_plots(&map.stage, scan, lx, ly));
    }
    plots
}

/// The scan's residuals per cell: mean residual arrows and RMS heat map.
fn scan_plots(stage: &PsdMap, scan: &PsdMapScanRecord, lx: f64, ly: f64) -> Vec<Plot> {
    let c = &scan.residual_cells;
    if c.x_mm.is_empty() {
        return Vec::new();
    }
    let arrows: Vec<Arrow> = (0..c.x_mm.len())
        .map(|i| Arrow {
            at: (c.x_mm[i], c.y_mm[i]),
            delta: (1e-3 * c.dx_um[i], 1e-3 * c.dy_um[i]),
        })
        .collect();
    let longest = arrows
        .iter()
        .map(|a| a.delta.0.hypot(a.delta.1))
        .fold(0.0, f64::max);
    let scale = crate::reports::calibration_plots::arrow_scale_for(longest, 1.1 * lx.max(ly));
    let boundary: Vec<Vec<(f64, f64)>> = stage
        .hull()
        .map(|h| {
            let v = h.vertices();
            vec![(0..=v.len())
                .map(|i| (v[i % v.len()].x, v[i % v.len()].y))
                .collect()]
        })
        .unwrap_or_default();
    let frame = stage.frame();
    let n = c.cells as f64;
    let step = (
        (frame.max.x - frame.min.x) / n,
        (frame.max.y - frame.min.y) / n,
    );
    let worst = c.rms_um.iter().copied().fold(0.0, f64::max);
    let noise = scan.fit.sigma_x_um.hypot(scan.fit.sigma_y_um);
    vec![
        Plot {
            name: "psd_map_scan_residuals",
            caption: format!(
                "The map's scan residuals (stage position − corrected point), mean per cell of a \
                 {0} × {0} grid, arrows scaled × {1}, largest {2} µm; black: the scan's hull \
                 (the map's valid region)",
                c.cells,
                crate::reports::calibration_plots::scale_text(scale),
                psdcal_report::num(1e3 * longest)
            ),
            data: PlotData::DistortionField {
                arrows,
                scale,
                boundary,
                frame: Frame::sensor(
                    &format!(
                        "PSD map scan residuals × {}",
                        crate::reports::calibration_plots::scale_text(scale)
                    ),
                    lx,
                    ly,
                ),
            },
        },
        Plot {
            name: "psd_map_scan_rms",
            caption: format!(
                "The map's scan residuals, RMS per cell, largest {} µm, against the scan noise \
                 √(σx² + σy²) = {} µm",
                psdcal_report::num(worst),
                psdcal_report::num(noise)
            ),
            data: PlotData::HeatMap {
                cells: (0..c.x_mm.len())
                    .map(|i| HeatCell {
                        x: c.x_mm[i],
                        y: c.y_mm[i],
                        value: c.rms_um[i],
                    })
                    .collect(),
                step,
                frame: Frame::sensor("PSD map scan residual RMS", lx, ly),
                label: "RMS residual (µm)".into(),
            },
        },
    ]
}

/// The map in one line of the report's list: its model and its scan's fit,
/// or that the calibration does not store them.
pub(crate) fn map_text(map: &PsdMapStageRecord) -> String {
    let how = if map.estimated {
        "refined by the calibration"
    } else {
        "held fixed"
    };
    match &map.scan {
        Some(s) => {
            let f = &s.fit;
            format!(
                "PSD map ({how}): {} from a scan of {} points ({} rejected as outliers); \
                 cross-validated RMS error {:.3} µm, residual RMS {:.3} µm, scan noise σx {:.3} \
                 µm, σy {:.3} µm, the map's own error {:.3} µm RMS",
                s.model,
                f.points,
                f.rejected_lines.len(),
                f.cv_rms_um,
                f.rms_um,
                f.sigma_x_um,
                f.sigma_y_um,
                f.map_sigma_um
            )
        }
        None => format!(
            "PSD map ({how}): this calibration does not store its scan's residuals (written \
             by an older psdcal); `psdcal psd-map --scan SCAN --report DIR` shows them"
        ),
    }
}

/// The map's 1σ at each heat-map point, `√(tr J_a C_m J_aᵀ)` µm, from the
/// sensor's covariance over the map's coefficients (`None` without it).
fn map_sigma(sensor: &CalibratedSensor, lx: f64, ly: f64) -> Option<Vec<HeatCell>> {
    let map = sensor.psd_map.as_ref()?;
    let names: Vec<String> = map
        .stage
        .parameters()
        .iter()
        .map(|p| p.name.clone())
        .collect();
    let cov = sensor.covariance.sub(&names).ok()?;
    let c = cov.matrix();
    let k = names.len();
    let cells: Vec<HeatCell> = grid(lx, ly, HEAT_GRID)
        .filter(|m| map.contains(m))
        .map(|m| {
            let j = map.correct(&m).wrt_block;
            // J is 2 × k column-major: entry (r, c) at j[2c + r].
            let mut var = 0.0;
            for r in 0..2 {
                for a in 0..k {
                    for b in 0..k {
                        var += j[2 * a + r] * c[(a, b)] * j[2 * b + r];
                    }
                }
            }
            HeatCell {
                x: m.x,
                y: m.y,
                value: 1e3 * var.max(0.0).sqrt(),
            }
        })
        .collect();
    (!cells.is_empty() && cells.iter().any(|c| c.value > 0.0)).then_some(cells)
}

use psdcal_model::Stage as _;
