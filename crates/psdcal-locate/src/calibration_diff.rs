//! The difference between two calibrations of one sensor, in angles of
//! arrival, over its active area (docs/model.md §8.8; mrcal's
//! projection-diff, for angles): did the sensor change?
//!
//! On an `N × N` grid of measured points `m` over the active area (edges
//! included, row-major with `y` outer), each calibration gives the angles
//! `α_A(m)`, `α_B(m)` (docs/model.md §5.1) and their covariances from its
//! parameters' covariance, `Σ_A(m)`, `Σ_B(m)` (the calibrations' part only:
//! the same measured point goes through both). With independent
//! calibrations (independent data):
//!
//! ```text
//! Δ(m) = α_B(m) − α_A(m),      |Δ| = √(Δx² + Δy²)
//! Σ(m) = Σ_A(m) + Σ_B(m)
//! σ(m) = √(uᵀ Σ u),  u = Δ/|Δ|   (σ of the difference along it; √((Σxx+Σyy)/2) when Δ = 0)
//! z(m) = |Δ| / σ                 (0 when Δ = 0)
//! ```
//!
//! A grid point that either calibration cannot answer (outside its valid
//! region) keeps its status and no numbers. The summary: the largest `|Δ|`
//! and where, the RMS of `|Δ|` over the answered points, and the largest
//! `z` and where. `z` above 3 somewhere means the calibrations differ by
//! more than their uncertainty explains (with a few estimated parameters
//! the map's values are strongly correlated, so the largest `z` of pure
//! noise stays near the parameters' own χ, mostly below 3).

use nalgebra::{Matrix2, Vector2};

use crate::calibrated_sensor::{CalibratedSensor, LocateOptions, Measurement};
use crate::error::LocateError;
use crate::maps::MAX_GRID;

/// One grid point's answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffValues {
    /// Calibration A's angles `(αx, αy)`, rad.
    pub alpha_a: Vector2<f64>,
    /// Calibration B's angles, rad.
    pub alpha_b: Vector2<f64>,
    /// `Σ_A + Σ_B`, rad².
    pub covariance: Matrix2<f64>,
}

impl DiffValues {
    /// `Δ = α_B − α_A`, rad.
    pub fn delta(&self) -> Vector2<f64> {
        self.alpha_b - self.alpha_a
    }

    /// `σ` of the difference along `Δ`, rad.
    pub fn sigma_along(&self) -> f64 {
        let d = self.delta();
        let n = d.norm();
        let c = &self.covariance;
        if n > 0.0 {
            let u = d / n;
            (u.transpose() * c * u)[(0, 0)].max(0.0).sqrt()
        } else {
            (0.5 * (c[(0, 0)] + c[(1, 1)])).max(0.0).sqrt()
        }
    }

    /// `|Δ| / σ` (0 when `Δ = 0`; `None` when `σ = 0` and `Δ ≠ 0`).
    pub fn z(&self) -> Option<f64> {
        let n = self.delta().norm();
        let s = self.sigma_along();
        if n == 0.0 {
            Some(0.0)
        } else {
            (s > 0.0).then(|| n / s)
        }
    }
}

/// One grid point.
#[derive(Debug, Clone, PartialEq)]
pub struct DiffPoint {
    /// The measured point, mm.
    pub measured: Vector2<f64>,
    /// Its values, or the status code of the calibration that could not
    /// answer.
    pub values: Result<DiffValues, &'static str>,
}

/// The difference over the grid and its summary.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationDiff {
    /// Grid points per side.
    pub grid: usize,
    /// The points, row-major with `y` outer.
    pub points: Vec<DiffPoint>,
    /// Points answered by both.
    pub answered: usize,
    /// Largest `|Δ|`, rad, and where (mm).
    pub max_delta: (f64, Vector2<f64>),
    /// RMS of `|Δ|`, rad.
    pub rms_delta: f64,
    /// Largest `z` and where (`None` without any finite z).
    pub max_z: Option<(f64, Vector2<f64>)>,
}

/// The difference `B − A` on a `grid × grid` grid (module docs). The two
/// sensors must have the same active area.
pub fn diff_calibrations(
    a: &CalibratedSensor,
    b: &CalibratedSensor,
    grid: usize,
) -> Result<CalibrationDiff, LocateError> {
    if !(2..=MAX_GRID).contains(&grid) {
        return Err(LocateError::InvalidInput {
            what: "grid",
            reason: format!("{grid} points per side; expected 2 to {MAX_GRID}"),
        });
    }
    if a.geometry != b.geometry {
        return Err(LocateError::InvalidInput {
            what: "active areas",
            reason: format!(
                "{} × {} mm and {} × {} mm: two calibrations of one sensor have one active area",
                a.geometry.lx, a.geometry.ly, b.geometry.lx, b.geometry.ly
            ),
        });
    }
    let (lx, ly) = (a.geometry.lx, a.geometry.ly);
    let options = LocateOptions::default();
    let mut diff = CalibrationDiff {
        grid,
        points: Vec::with_capacity(grid * grid),
        answered: 0,
        max_delta: (0.0, Vector2::zeros()),
        rms_delta: 0.0,
        max_z: None,
    };
    let mut sum = 0.0;
    for j in 0..grid {
        for i in 0..grid {
            let t = |k: usize| k as f64 / (grid - 1) as f64 - 0.5;
            let m = Vector2::new(lx * t(i), ly * t(j));
            let answer = |s: &CalibratedSensor| s.aoa(&Measurement::Point(m), &options);
            let values = match (answer(a), answer(b)) {
                (Ok(ea), Ok(eb)) => Ok(DiffValues {
                    alpha_a: ea.aoa.alpha,
                    alpha_b: eb.aoa.alpha,
                    covariance: ea.alpha_covariance_calibration()
                        + eb.alpha_covariance_calibration(),
                }),
                (Err(e), _) | (_, Err(e)) => Err(e.status()),
            };
            if let Ok(v) = &values {
                diff.answered += 1;
                let n = v.delta().norm();
                sum += n * n;
                if n > diff.max_delta.0 {
                    diff.max_delta = (n, m);
                }
                if let Some(z) = v.z() {
                    if diff.max_z.is_none_or(|(best, _)| z > best) {
                        diff.max_z = Some((z, m));
                    }
                }
            }
            diff.points.push(DiffPoint {
                measured: m,
                values,
            });
        }
    }
    diff.rms_delta = (sum / diff.answered.max(1) as f64).sqrt();
    Ok(diff)
}
