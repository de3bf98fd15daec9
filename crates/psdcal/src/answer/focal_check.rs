//! `psdcal focal-check`: the focal length measured from known geometry (the
//! paper's Eq. 44; docs/model.md §8.9) against a calibration's.
//!
//! The measured corners `m_k` of a rectangle with sides `W` (corner 1→2 and
//! 3→4) and `H` (2→3 and 4→1), parallel to the sensor at distance `S`, are
//! corrected to ideal points `p_k` through the calibration. A pinhole images
//! a plane parallel to the sensor as a similar figure scaled by `f/S`, so each
//! side gives `f_k = |p_{k+1} − p_k| · S / L_k` (`L_k` its length in the
//! scene), and the check is their mean `f̄`. With `u_k` the unit vector of
//! side `k`, `∂f̄/∂p_j = (S/4)(u_{j−1}/L_{j−1} − u_j/L_j)`; the corners'
//! noise (σ per coordinate of the measured point, through
//! `∂p/∂m`) and the distance's (`σ_S f̄ / S`) give the check's σ.
//! The verdict compares `f̄ − f` with `√(σ_check² + σ_f²)`.

use std::path::PathBuf;

use nalgebra::Vector2;
use psdcal_io::Corners;
use serde_json::json;

use crate::answer::loaded_sensor::LoadedSensor;
use crate::base::error::{Error, Result};

/// What to check.
#[derive(Debug, Clone, PartialEq)]
pub struct FocalCheckRequest {
    /// calibration.json.
    pub calibration: PathBuf,
    /// The corners file.
    pub points: PathBuf,
    /// Distance of the rectangle's plane from the sensor, mm.
    pub distance_mm: f64,
    /// Its standard deviation, mm (0: exact).
    pub distance_sigma_mm: f64,
    /// Sides `(W, H)` in the scene, mm (a square: equal).
    pub size_mm: (f64, f64),
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
}

/// The check's result.
#[derive(Debug, Clone, PartialEq)]
pub struct FocalCheck {
    /// `f_k` of each side, mm.
    pub sides: Vec<f64>,
    /// Their mean, mm.
    pub f_check: f64,
    /// Its σ from the corners' and the distance's noise, mm (`None`: the
    /// corners' noise is not given and the distance is exact).
    pub sigma_check: Option<f64>,
    /// The calibration's `f`, mm.
    pub f_calibration: f64,
    /// Its σ, mm (`None` when the calibration has no covariance for `f`).
    pub sigma_calibration: Option<f64>,
    /// `(f̄ − f) / √(σ_check² + σ_f²)`, when some σ is known.
    pub z: Option<f64>,
    /// The summary for people.
    pub text: String,
    /// The summary as JSON.
    pub json: serde_json::Value,
}

/// Runs the check.
pub fn focal_check(request: &FocalCheckRequest) -> Result<FocalCheck> {
    let (s, (w, h)) = (request.distance_mm, request.size_mm);
    if !(s.is_finite() && s > 0.0 && w.is_finite() && w > 0.0 && h.is_finite() && h > 0.0) {
        return Err(Error::Options(
            "--distance and --size must be positive lengths in mm".into(),
        ));
    }
    if !(request.distance_sigma_mm.is_finite() && request.distance_sigma_mm >= 0.0) {
        return Err(Error::Options("--distance-sigma must be ≥ 0 mm".into()));
    }
    let loaded = LoadedSensor::read_with(&request.calibration, request.limits)?;
    let corners = Corners::read_with(&request.points, request.limits)?;
    let chain = loaded.sensor.chain();
    let mut ideal = Vec::with_capacity(4);
    for c in &corners.corners {
        loaded.sensor.check_valid_region(&c.measured).map_err(|e| {
            Error::Input(format!(
                "{}: line {}: corner '{}' at ({}, {}) mm: {e}",
                corners.source, c.line_no, c.id, c.measured.x, c.measured.y
            ))
        })?;
        ideal.push(chain.ideal(&c.measured));
    }
    let lengths = [w, h, w, h];
    let mut sides = Vec::with_capacity(4);
    let mut units: Vec<Vector2<f64>> = Vec::with_capacity(4);
    for k in 0..4 {
        let d = ideal[(k + 1) % 4] - ideal[k];
        if d.norm() == 0.0 {
            return Err(Error::Input(format!(
                "{}: corners '{}' and '{}' coincide after correction; give the four corners in order around the rectangle",
                corners.source,
                corners.corners[k].id,
                corners.corners[(k + 1) % 4].id
            )));
        }
        sides.push(d.norm() * s / lengths[k]);
        units.push(d.normalize() / lengths[k]);
    }
    let f_check = sides.iter().sum::<f64>() / 4.0;
    let noise = corners.corners.iter().all(|c| c.sigma_mm.is_some());
    let mut var = (request.distance_sigma_mm * f_check / s).powi(2);
    if noise {
        for (j, c) in corners.corners.iter().enumerate() {
            let g = (units[(j + 3) % 4] - units[j]) * (s / 4.0);
            let jac = chain.ideal_point_jacobian(&c.measured);
            let sigma = c.sigma_mm.unwrap_or(0.0);
            var += (jac.transpose() * g).norm_squared() * sigma * sigma;
        }
    }
    let sigma_check = (noise || request.distance_sigma_mm > 0.0).then(|| var.sqrt());
    let f_calibration = loaded.sensor.model.intrinsics.f;
    let sigma_calibration = loaded.sensor.covariance.std("f");
    let combined = sigma_check
        .unwrap_or(0.0)
        .hypot(sigma_calibration.unwrap_or(0.0));
    let z = (combined > 0.0).then(|| (f_check - f_calibration) / combined);
    let mut out = FocalCheck {
        sides,
        f_check,
        sigma_check,
        f_calibration,
        sigma_calibration,
        z,
        text: String::new(),
        json: serde_json::Value::Null,
    };
    out.text = text(&out);
    out.json = json!({
        "f_sides_mm": out.sides,
        "f_check_mm": out.f_check,
        "sigma_check_mm": out.sigma_check,
        "f_calibration_mm": out.f_calibration,
        "sigma_f_calibration_mm": out.sigma_calibration,
        "difference_mm": out.f_check - out.f_calibration,
        "z": out.z,
        "consistent": out.z.map(|z| z.abs() <= 3.0),
    });
    Ok(out)
}

fn text(c: &FocalCheck) -> String {
    let pm = |s: Option<f64>| s.map(|s| format!(" ± {s:.4}")).unwrap_or_default();
    let sides: Vec<String> = c.sides.iter().map(|f| format!("{f:.4}")).collect();
    let verdict = match c.z {
        Some(z) if z.abs() <= 3.0 => format!("consistent ({z:+.2} σ)"),
        Some(z) => format!("NOT consistent ({z:+.2} σ): check the distance, the sizes and the corners' order, or recalibrate"),
        None => format!(
            "differs by {:+.2} %; no σ known (give sigma_mm in the corners file or --distance-sigma)",
            100.0 * (c.f_check / c.f_calibration - 1.0)
        ),
    };
    format!(
        "f from the sides: {} mm\nf check {:.4}{} mm against the calibration's f {:.4}{} mm: {verdict}",
        sides.join(", "),
        c.f_check,
        pm(c.sigma_check),
        c.f_calibration,
        pm(c.sigma_calibration)
    )
}
