//! The checks a calibration read from a file passes before it answers,
//! beyond its file's own rules (psdcal-io: finite numbers, a plausible f and
//! skew, `std` agreeing with a positive semi-definite covariance): it is
//! held to what a fresh calibration guarantees (docs/formats.md,
//! "calibration.json: checks on reading").
//!
//! - **Valid region.** Recomputed from the parameters (docs/model.md §8.2),
//!   never taken from the file: a hand-edited coefficient cannot keep an
//!   old region. The region must reach at least
//!   `MIN_REGION_FRACTION · min(Lx, Ly) / 2` from the optical centre on every
//!   ray: a correction that folds closer than that cannot have been fitted
//!   to points on the active area; the error names the distortion
//!   coefficient whose term `|k r^n|` is largest at that reach on the ray
//!   that folds first.
//! - **Covariance.** The calibration's angle σ (docs/model.md §5) at the
//!   optical centre, the active area's centre and its four corners (those
//!   inside the region) must be finite and at most `MAX_ANGLE_SIGMA_DEG`: a
//!   calibration that knows the direction of arrival to no better than ±90°
//!   knows nothing, and a larger σ is a scaled value (σ × 1e150), not a
//!   measurement.

use std::path::Path;

use nalgebra::Vector2;
use psdcal_io::{Calibration, IoError, Location};
use psdcal_locate::{sigmas_and_correlation, CalibratedSensor, LocateOptions, Measurement};

/// The smallest reach of the valid region, as a fraction of the active
/// area's smaller half side.
pub const MIN_REGION_FRACTION: f64 = 0.05;
/// The largest calibration angle σ accepted, degrees.
pub const MAX_ANGLE_SIGMA_DEG: f64 = 90.0;

/// Refuses a loaded sensor that a fresh calibration could not have given
/// (module documentation); `file` names it in the error.
pub fn check_loaded(
    calibration: &Calibration,
    sensor: &CalibratedSensor,
    file: &Path,
) -> Result<(), IoError> {
    let invalid = |message: String| IoError::Invalid {
        at: Location::file(&file.display().to_string()),
        message,
    };
    check_region(calibration, sensor).map_err(invalid)?;
    check_angle_sigma(sensor).map_err(invalid)
}

/// The region's reach (module documentation).
fn check_region(calibration: &Calibration, sensor: &CalibratedSensor) -> Result<(), String> {
    let region = &sensor.valid_region;
    let geometry = region.geometry();
    let needed = MIN_REGION_FRACTION * geometry.lx.min(geometry.ly) / 2.0;
    let radii = region.radii();
    let Some((ray, reach)) = radii
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return Ok(());
    };
    if reach >= needed {
        return Ok(());
    }
    // The culprit is the coefficient whose term is largest where the region
    // should at least reach.
    let theta = std::f64::consts::TAU * ray as f64 / radii.len() as f64;
    let at = region.centre() + needed * Vector2::new(theta.cos(), theta.sin());
    Err(format!(
        "{}: the distortion correction folds {} mm from the optical centre, and the valid \
         region must reach at least {} mm (5 % of the active area's half side); expected the \
         coefficients of a real lens and PSD (was the value edited or in the wrong unit?)",
        largest_term(calibration, &region.centre(), &at),
        psdcal_io::number_text(reach),
        psdcal_io::number_text(needed)
    ))
}

/// `distortion.NAME = VALUE`: the coefficient whose term (`k1 r²`, `k2 r⁴`,
/// `k3 r⁶`, `2 p r`, `l1 s²`, `l2 s⁴`) is largest at the measured point `at` (lens terms about the optical centre `c`, PSD terms
/// about the electrical centre).
fn largest_term(calibration: &Calibration, c: &Vector2<f64>, at: &Vector2<f64>) -> String {
    let d = &calibration.distortion;
    let r = (at - c).norm();
    let s = at.norm();
    let terms = [
        ("k1", d.k1, r.powi(2)),
        ("k2", d.k2, r.powi(4)),
        ("k3", d.k3, r.powi(6)),
        ("p1", d.p1, 2.0 * r),
        ("p2", d.p2, 2.0 * r),
        ("l1", d.l1, s.powi(2)),
        ("l2", d.l2, s.powi(4)),
    ];
    let (name, value, _) = terms
        .iter()
        .copied()
        .max_by(|a, b| (a.1 * a.2).abs().total_cmp(&(b.1 * b.2).abs()))
        .unwrap_or(("k1", d.k1, 0.0));
    if terms.iter().all(|t| t.1 == 0.0) {
        return "the model (no distortion coefficient is set)".to_string();
    }
    format!("distortion.{name} = {}", psdcal_io::shown_number(value))
}

/// The calibration's angle σ at a few points (module documentation).
fn check_angle_sigma(sensor: &CalibratedSensor) -> Result<(), String> {
    if sensor.covariance.is_empty() {
        return Ok(());
    }
    let (hx, hy) = (sensor.geometry.lx / 2.0, sensor.geometry.ly / 2.0);
    let points = [
        sensor.valid_region.centre(),
        Vector2::zeros(),
        Vector2::new(hx, hy),
        Vector2::new(-hx, hy),
        Vector2::new(-hx, -hy),
        Vector2::new(hx, -hy),
    ];
    let options = LocateOptions::default();
    for p in points {
        let Ok(estimate) = sensor.aoa(&Measurement::Point(p), &options) else {
            continue;
        };
        let covariance = estimate.alpha_covariance_calibration();
        let (sx, sy, _) = sigmas_and_correlation(&covariance);
        let finite = covariance.iter().all(|v| v.is_finite());
        let worst = if finite {
            sx.max(sy).to_degrees()
        } else {
            f64::INFINITY
        };
        if worst.is_nan() || worst > MAX_ANGLE_SIGMA_DEG {
            return Err(format!(
                "covariance: the angle sigma it gives at ({}, {}) mm is {} degrees; expected at \
                 most {MAX_ANGLE_SIGMA_DEG} (std and covariance as a calibration gives them: \
                 was a value scaled by mistake?)",
                psdcal_io::number_text(p.x),
                psdcal_io::number_text(p.y),
                psdcal_io::shown_number(worst)
            ));
        }
    }
    Ok(())
}
