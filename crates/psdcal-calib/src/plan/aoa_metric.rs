//! The angle-of-arrival uncertainty a parameter covariance gives over the
//! active area (docs/model.md §8.6).
//!
//! At a measured point `m` the model gives the normalised ray `u = (a, b)`
//! (`d = (a, b, 1)/n`, `n = √(1 + a² + b²)`). A parameter error `δθ` moves it
//! by `δu = G δθ`, `G = ∂u/∂θ` (2 × p), and the ray turns by the angle
//! `|δd| = √(δuᵀ Q δu)` to first order, with `Q = (I − u uᵀ/n²)/n²`. So the
//! expected squared angle is `σ²(m) = tr(C H_m)` with `H_m = Gᵀ Q G` for a
//! parameter covariance `C`. The grid is the centres of `g × g` equal cells
//! over the active area; the RMS over it is `√(tr(C H̄))`, `H̄` the mean of
//! the `H_m`.
//!
//! When the model owns the channel gains, a point is measured from
//! amplitudes, `m = P(V / g)`, and an error `δg` in the gains moves it by
//! `∂m/∂g δg` before the chain: `G`'s gain columns are
//! `(∂u/∂m)(∂m/∂g)`, at the amplitudes the signal chain gives at `m`
//! ([`crate::plan::information::nominal_amplitudes`]).

use nalgebra::{DMatrix, Matrix2, Vector2};
use psdcal_model::{Model, PsdGeometry};

use crate::plan::information::nominal_amplitudes;
use crate::CalibError;

/// `H_m` at each point of a grid (module documentation).
#[derive(Debug, Clone)]
pub struct AoaMetric {
    /// The grid's measured points, mm.
    pub points: Vec<Vector2<f64>>,
    /// `H_m` per point (p × p).
    pub weights: Vec<DMatrix<f64>>,
    /// `H̄`, their mean.
    pub mean: DMatrix<f64>,
}

/// The centres of `cells × cells` equal cells over the active area.
pub fn cell_centres(geometry: &PsdGeometry, cells: usize) -> Vec<Vector2<f64>> {
    let c = |k: usize, side: f64| side * ((k as f64 + 0.5) / cells as f64 - 0.5);
    (0..cells)
        .flat_map(|j| (0..cells).map(move |i| (i, j)))
        .map(|(i, j)| Vector2::new(c(i, geometry.lx), c(j, geometry.ly)))
        .collect()
}

impl AoaMetric {
    /// `H_m` of `model` for the freed parameters `free` at `points`.
    pub fn new(
        model: &Model,
        free: &[String],
        points: Vec<Vector2<f64>>,
    ) -> Result<Self, CalibError> {
        let columns = free
            .iter()
            .map(|name| {
                model.index(name).ok_or_else(|| CalibError::InvalidInput {
                    reason: format!("the model has no parameter '{name}'"),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if points.is_empty() {
            return Err(CalibError::InvalidInput {
                reason: "no grid points for the angle-of-arrival map".into(),
            });
        }
        let p = columns.len();
        let mut jac = model.jacobian_buffer();
        let mut weights = Vec::with_capacity(points.len());
        let mut mean = DMatrix::zeros(p, p);
        for m in &points {
            let u = model.ray_with_jacobians(m, &mut jac);
            let n2 = 1.0 + u.norm_squared();
            let q = (Matrix2::identity() - u * u.transpose() / n2) / n2;
            let mut g = DMatrix::zeros(2, p);
            for (slot, c) in columns.iter().enumerate() {
                g[(0, slot)] = jac.wrt_params[2 * c];
                g[(1, slot)] = jac.wrt_params[2 * c + 1];
            }
            if let (Some(amps), Some(cols)) = (nominal_amplitudes(model, m), model.gain_columns()) {
                let (_, dm_dg) = model
                    .measured_from_amplitudes_with_jacobian(&amps)
                    .map_err(|e| CalibError::InvalidInput {
                        reason: format!(
                            "no impact point at the grid point ({}, {}) mm: {e}",
                            m.x, m.y
                        ),
                    })?;
                let du_dg = jac.wrt_point * dm_dg;
                for (n, c) in cols.iter().enumerate() {
                    if let Some(slot) = columns.iter().position(|k| k == c) {
                        g[(0, slot)] = du_dg[(0, n)];
                        g[(1, slot)] = du_dg[(1, n)];
                    }
                }
            }
            let q = DMatrix::from_column_slice(2, 2, q.as_slice());
            let h = g.transpose() * q * &g;
            mean += &h;
            weights.push(h);
        }
        mean /= points.len() as f64;
        Ok(Self {
            points,
            weights,
            mean,
        })
    }

    /// `σ(m)` (rad) at every grid point for the covariance `c`.
    pub fn sigma_map(&self, c: &DMatrix<f64>) -> Vec<f64> {
        self.weights
            .iter()
            .map(|h| trace_product(c, h).max(0.0).sqrt())
            .collect()
    }

    /// The mean of `σ²(m)` over the grid, `tr(C H̄)` (rad²).
    pub fn mean_square(&self, c: &DMatrix<f64>) -> f64 {
        trace_product(c, &self.mean)
    }

    /// The largest `σ²(m)` over the grid (rad²).
    pub fn max_square(&self, c: &DMatrix<f64>) -> f64 {
        self.weights
            .iter()
            .map(|h| trace_product(c, h))
            .fold(0.0, f64::max)
    }
}

/// `tr(A B)` for symmetric `B`: `Σ A_ij B_ij`.
fn trace_product(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    a.iter().zip(b.iter()).map(|(x, y)| x * y).sum()
}
