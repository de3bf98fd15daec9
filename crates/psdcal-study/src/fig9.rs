//! The paper's Figure 9: how large the angle-of-arrival and position errors
//! are across the sensor when the parameters are off by what the Monte Carlo
//! study found (docs/model.md §5).
//!
//! For each condition of Tables 9–10 the parameters are set to
//! `θ = θ_ideal + Δθ` with `Δθ = |mean − ideal| + 2·std` for `Cx, Cy, f, k1,
//! k2` (every offset positive, so their effects add). Over a 41 × 41 grid of
//! measured points on the active area, the ray of the true model and the ray
//! of the perturbed one are compared: the AoA error is the angle between
//! them, and the position error is their distance on a plane parallel to the
//! sensor at `S = 5 m` (`P = S·(a, b, 1)` for a normalised ray `(a, b)`). The
//! full model is used, not the small-angle sensitivity (P40)–(P42).

use nalgebra::Vector2;
use psdcal_model::{Param, PsdGeometry, SensorModel};
use serde::Serialize;

use crate::study::{Quantity, TableResult};

/// Distance of the plane of Figure 9, mm.
pub const FIG9_DISTANCE_MM: f64 = 5000.0;
/// Grid points per side.
pub const FIG9_GRID: usize = 41;

/// One map of Figure 9.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorMap {
    /// The lens (1 or 2).
    pub lens: u8,
    /// The condition (column of Table 9 or 10).
    pub condition: String,
    /// The parameter offsets used, `(name, Δ)`.
    pub offsets: Vec<(String, f64)>,
    /// `(x_mm, y_mm, aoa_error_deg, position_error_mm)` per grid point
    /// (points outside the perturbed model's valid region are left out).
    pub grid: Vec<[f64; 4]>,
    /// Largest AoA error, degrees.
    pub max_aoa_deg: f64,
    /// Largest position error at 5 m, mm.
    pub max_position_mm: f64,
    /// Mean AoA error, degrees.
    pub mean_aoa_deg: f64,
}

/// The maps of Figure 9 from the results of Tables 9 and 10 (either may be
/// missing).
pub fn figure9(tables: &[TableResult], geometry: &PsdGeometry) -> Vec<ErrorMap> {
    let mut maps = Vec::new();
    for table in tables
        .iter()
        .filter(|t| t.spec.id == "table9" || t.spec.id == "table10")
    {
        for column in &table.columns {
            let c = &column.condition;
            let mut truth = c.lens.model();
            if c.psd_distortion {
                truth.distortion.l1 = SensorModel::PAPER_L1;
            }
            let mut perturbed = truth;
            let mut offsets = Vec::new();
            for (q, p) in [
                (Quantity::Cx, Param::Cx),
                (Quantity::Cy, Param::Cy),
                (Quantity::F, Param::F),
                (Quantity::K1, Param::K1),
                (Quantity::K2, Param::K2),
            ] {
                let row = table.rows.iter().position(|r| *r == q);
                let (Some(row), Some(ideal)) = (row, c.ideal(q)) else {
                    continue;
                };
                let Some(s) = column.stats[row] else { continue };
                let delta = (s.mean - ideal).abs() + 2.0 * s.std;
                // k1's ideal here is k1 + l1 (what the fit estimates); offset k1.
                perturbed.set(p, truth.get(p) + delta);
                offsets.push((p.name().to_string(), delta));
            }
            maps.push(error_map(
                c.lens.number(),
                &c.label,
                &truth,
                &perturbed,
                geometry,
                offsets,
            ));
        }
    }
    maps
}

/// The AoA and position error map between two models over the sensor.
pub fn error_map(
    lens: u8,
    condition: &str,
    truth: &SensorModel,
    perturbed: &SensorModel,
    geometry: &PsdGeometry,
    offsets: Vec<(String, f64)>,
) -> ErrorMap {
    let n = FIG9_GRID;
    let mut grid = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let m = Vector2::new(
                geometry.lx * (i as f64 / (n - 1) as f64 - 0.5),
                geometry.ly * (j as f64 / (n - 1) as f64 - 0.5),
            );
            let a = truth.normalize(&truth.undistort(&m));
            let b = perturbed.normalize(&perturbed.undistort(&m));
            if !(a.iter().chain(b.iter()).all(|v| v.is_finite())) {
                continue;
            }
            let (ra, rb) = (
                truth.ray_direction(&truth.undistort(&m)),
                perturbed.ray_direction(&perturbed.undistort(&m)),
            );
            let angle = ra.cross(&rb).norm().atan2(ra.dot(&rb)).to_degrees();
            let position = ((a - b) * FIG9_DISTANCE_MM).norm();
            grid.push([m.x, m.y, angle, position]);
        }
    }
    let max_aoa_deg = grid.iter().map(|g| g[2]).fold(0.0, f64::max);
    let max_position_mm = grid.iter().map(|g| g[3]).fold(0.0, f64::max);
    let mean_aoa_deg = grid.iter().map(|g| g[2]).sum::<f64>() / grid.len().max(1) as f64;
    ErrorMap {
        lens,
        condition: condition.into(),
        offsets,
        grid,
        max_aoa_deg,
        max_position_mm,
        mean_aoa_deg,
    }
}
