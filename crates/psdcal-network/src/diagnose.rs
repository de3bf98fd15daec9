//! What a user can act on after a network calibration:
//!
//! - **wand-length residuals**: each used frame's wand LEDs triangulated by
//!   the calibrated sensors alone (rays through the refined models, the
//!   least-squares meeting point), their distances against wand.csv's —
//!   an error the rigid wand of the adjustment cannot hide;
//! - **coverage**: the fraction of an 8 × 8 grid over each sensor's active
//!   area holding kept sightings, and which ninths of the area hold none;
//! - **weak links**: a sensor whose strongest link shares fewer than
//!   `3 ×` the start's minimum sightings, or whose position σ is over three
//!   times the network's median;
//! - **dropped frames**, and the **advice**: a pose σ falls as `1/√frames`,
//!   so reaching σ_target from σ_now takes `(σ_now/σ_target)²` times the
//!   frames waved so far.

use nalgebra::Vector3;
use psdcal_model::Severity;
use serde::Serialize;

use crate::adjust::Adjusted;
use crate::data::{Led, NetworkData};
use crate::estimate::{Gauge, SensorEstimate};
use crate::geometry::meet_rays;

/// Cells per side of the coverage grid.
pub const COVERAGE_GRID: usize = 8;

/// One diagnostic: stable code, severity, message.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetworkDiagnostic {
    /// Stable identifier.
    pub code: &'static str,
    /// How much it matters.
    pub severity: Severity,
    /// What to do.
    pub message: String,
}

/// A sensor's coverage of its active area.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Coverage {
    /// Fraction of the grid's cells with a kept sighting.
    pub fraction: f64,
    /// Kept sightings per cell, row-major from (−x, −y).
    pub cells: Vec<usize>,
    /// Ninths of the area without sightings (`"upper left"`, …; sensor `+y`
    /// up).
    pub empty_regions: Vec<String>,
}

/// Everything diagnosed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetworkDiagnostics {
    /// RMS wand-length residual, mm.
    pub wand_length_rms_mm: f64,
    /// Worst frames: (frame index, largest |residual| mm).
    pub worst_frames: Vec<(usize, f64)>,
    /// Every used frame's largest |wand-length residual|, mm.
    pub frame_residuals: Vec<(usize, f64)>,
    /// Per sensor.
    pub coverage: Vec<Coverage>,
    /// The findings.
    pub items: Vec<NetworkDiagnostic>,
    /// Frames to wave in all for the worst position σ to halve.
    pub frames_to_halve_sigma: usize,
}

/// The diagnostics of an adjusted network (module documentation).
pub fn diagnose(
    data: &NetworkData,
    a: &Adjusted,
    sensors: &[SensorEstimate],
    shared: &[Vec<usize>],
    gauge: Gauge,
) -> NetworkDiagnostics {
    let (rms, frame_residuals) = wand_lengths(data, a);
    let mut worst = frame_residuals.clone();
    worst.sort_by(|x, y| y.1.total_cmp(&x.1));
    worst.truncate(5);
    let coverage: Vec<Coverage> = (0..data.sensors.len())
        .map(|s| coverage(data, a, s))
        .collect();
    let mut items = Vec::new();
    let id = |s: usize| data.sensors[s].id.as_str();
    items.push(NetworkDiagnostic {
        code: "gauge",
        severity: Severity::Info,
        message: gauge.describe(id(0)),
    });
    let sigmas: Vec<f64> = sensors
        .iter()
        .map(|e| e.position_covariance.trace().max(0.0).sqrt())
        .collect();
    let mut sorted: Vec<f64> = sigmas.iter().copied().filter(|v| *v > 0.0).collect();
    let median = if sorted.is_empty() {
        0.0
    } else {
        crate::start::median(&mut sorted)
    };
    for s in 0..data.sensors.len() {
        let best = shared[s].iter().copied().max().unwrap_or(0);
        if best < 90 || (median > 0.0 && sigmas[s] > 3.0 * median) {
            items.push(NetworkDiagnostic {
                code: "weakly_connected",
                severity: Severity::Warning,
                message: format!(
                    "sensor '{}' is weakly tied to the network ({} sightings shared with its \
                     best partner, position σ {:.2} mm against a median {:.2} mm): wave where \
                     it and its neighbours see the wand together",
                    id(s),
                    best,
                    sigmas[s],
                    median
                ),
            });
        }
        let c = &coverage[s];
        if c.fraction < 0.5 || !c.empty_regions.is_empty() {
            items.push(NetworkDiagnostic {
                code: "coverage_missing",
                severity: if c.fraction < 0.3 {
                    Severity::Warning
                } else {
                    Severity::Info
                },
                message: format!(
                    "sensor '{}' saw the wand on {:.0} % of its active area{}: wave where its \
                     view reaches there",
                    id(s),
                    100.0 * c.fraction,
                    if c.empty_regions.is_empty() {
                        String::new()
                    } else {
                        format!(", nothing in its {}", c.empty_regions.join(", "))
                    }
                ),
            });
        }
    }
    let outliers = a
        .dropped
        .iter()
        .filter(|d| d.1 == crate::adjust::DropReason::Outlier)
        .count();
    let total = data.frames.len().max(1);
    if outliers > 0 {
        let names: Vec<&str> = a
            .dropped
            .iter()
            .filter(|d| d.1 == crate::adjust::DropReason::Outlier)
            .take(5)
            .map(|d| data.frames[d.0].as_str())
            .collect();
        items.push(NetworkDiagnostic {
            code: "frames_dropped",
            severity: if outliers * 10 > total {
                Severity::Warning
            } else {
                Severity::Info
            },
            message: format!(
                "{outliers} frame(s) dropped for a sighting beyond {} σ (a wrong or reflected \
                 LED), e.g. {}",
                crate::adjust::AdjustOptions::default().outlier_sigma,
                names.join(", ")
            ),
        });
    }
    let worst_sigma = sigmas.iter().copied().fold(0.0, f64::max);
    let frames = a.frames.len();
    let frames_to_halve_sigma = 4 * frames;
    if let Some(s) = sigmas.iter().position(|v| *v == worst_sigma) {
        items.push(NetworkDiagnostic {
            code: "advice",
            severity: Severity::Info,
            message: format!(
                "the least certain sensor is '{}' (position σ {:.3} mm from {} frames); σ falls \
                 as 1/√frames: about {} frames in all halve it",
                id(s),
                worst_sigma,
                frames,
                frames_to_halve_sigma
            ),
        });
    }
    NetworkDiagnostics {
        wand_length_rms_mm: rms,
        worst_frames: worst,
        frame_residuals,
        coverage,
        items,
        frames_to_halve_sigma,
    }
}

/// The RMS wand-length residual and each frame's largest (module
/// documentation).
fn wand_lengths(data: &NetworkData, a: &Adjusted) -> (f64, Vec<(usize, f64)>) {
    let centres: Vec<_> = a.state.sensors.iter().map(|p| p.inverse()).collect();
    let (mut ss, mut n) = (0.0, 0usize);
    let mut per_frame = Vec::new();
    for (b, obs) in a.by_block.iter().enumerate() {
        let mut points: Vec<Option<Vector3<f64>>> = vec![None; data.wand.len()];
        for (l, slot) in points.iter_mut().enumerate() {
            let rays: Vec<_> = obs
                .iter()
                .map(|&k| &data.observations[k])
                .filter(|o| o.led == Led::Wand(l))
                .map(|o| {
                    let ab = a.state.models[o.sensor].ray(&o.measured);
                    let w = &centres[o.sensor];
                    (
                        w.t,
                        w.rotation() * Vector3::new(ab.x, ab.y, 1.0).normalize(),
                    )
                })
                .collect();
            *slot = meet_rays(&rays);
        }
        let mut worst: Option<f64> = None;
        for i in 0..points.len() {
            for j in i + 1..points.len() {
                if let (Some(p), Some(q)) = (points[i], points[j]) {
                    let e = (p - q).norm() - (data.wand[i] - data.wand[j]).norm();
                    ss += e * e;
                    n += 1;
                    worst = Some(worst.map_or(e.abs(), |w: f64| w.max(e.abs())));
                }
            }
        }
        if let Some(w) = worst {
            per_frame.push((a.frames[b], w));
        }
    }
    ((ss / n.max(1) as f64).sqrt(), per_frame)
}

/// A sensor's coverage (module documentation).
fn coverage(data: &NetworkData, a: &Adjusted, s: usize) -> Coverage {
    let g = data.sensors[s].geometry;
    let n = COVERAGE_GRID;
    let mut cells = vec![0usize; n * n];
    let mut ninths = [0usize; 9];
    for &k in a.by_block.iter().flatten().chain(&a.statics) {
        let o = &data.observations[k];
        if o.sensor != s {
            continue;
        }
        let u = (o.measured.x / g.lx + 0.5).clamp(0.0, 0.999_999);
        let v = (o.measured.y / g.ly + 0.5).clamp(0.0, 0.999_999);
        cells[(v * n as f64) as usize * n + (u * n as f64) as usize] += 1;
        ninths[(v * 3.0) as usize * 3 + (u * 3.0) as usize] += 1;
    }
    let names = [
        "lower left",
        "lower middle",
        "lower right",
        "middle left",
        "centre",
        "middle right",
        "upper left",
        "upper middle",
        "upper right",
    ];
    Coverage {
        fraction: cells.iter().filter(|c| **c > 0).count() as f64 / (n * n) as f64,
        cells,
        empty_regions: ninths
            .iter()
            .zip(names)
            .filter(|(c, _)| **c == 0)
            .map(|(_, name)| name.to_string())
            .collect(),
    }
}
