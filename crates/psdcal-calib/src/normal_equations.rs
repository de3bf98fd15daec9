//! The block structure of calibration's normal equations and its solution by
//! the Schur complement.
//!
//! The unknowns are `p` sensor parameters `a` (the freed intrinsics and
//! distortion coefficients) and one pose `b_i` (6 parameters) per image. A
//! residual of image `i` depends on `a` and `b_i` only, so with
//! `A = ∂r/∂a` and `B = ∂r/∂b_i`, `JᵀJ` has the arrow shape
//!
//! ```text
//! [ U    W_1  …  W_n ]      U   = Σ AᵀA        (p × p)
//! [ W_1ᵀ V_1         ]      V_i = Σ_i BᵀB      (6 × 6)
//! [  ⋮        ⋱      ]      W_i = Σ_i AᵀB      (p × 6)
//! [ W_nᵀ          V_n]
//! ```
//!
//! and `(JᵀJ + damping) δ = −Jᵀr` is solved by eliminating the poses:
//! `S = U − Σ W_i V_i⁻¹ W_iᵀ`, `S δa = −g_a + Σ W_i V_i⁻¹ g_i`,
//! `δb_i = V_i⁻¹(−g_i − W_iᵀ δa)`. The work is `O(n (p² · 6 + 6³) + p³)`:
//! linear in the number of images. `S` is solved after Jacobi scaling (unit
//! diagonal), because the columns span many orders of magnitude (`f` in mm
//! next to `k3` in mm⁻⁶).
//!
//! The same blocks give the covariance of the estimate (undamped):
//! `Cov(a) = S⁻¹`, `Cov(b_i) = V_i⁻¹ + V_i⁻¹ W_iᵀ S⁻¹ W_i V_i⁻¹`, both times σ².

use nalgebra::{DMatrix, DVector, Matrix6, SMatrix, Vector2, Vector6};
use psdcal_model::N_PARAMS;

/// Columns of the global block: the 11 sensor parameters, then the relative
/// channel gains `g_x2, g_y1, g_y2`.
pub const N_GLOBAL: usize = N_PARAMS + 3;

/// Accumulated normal equations of one evaluation.
#[derive(Debug, Clone)]
pub struct NormalEquations {
    /// `U = Σ AᵀA` over every residual (p × p).
    pub u: DMatrix<f64>,
    /// `g_a = Σ Aᵀ r` (p).
    pub g_a: DVector<f64>,
    /// Per image: `V_i = Σ BᵀB`.
    pub v: Vec<Matrix6<f64>>,
    /// Per image: `W_i = Σ AᵀB` (p × 6).
    pub w: Vec<DMatrix<f64>>,
    /// Per image: `g_i = Σ Bᵀ r`.
    pub g_b: Vec<Vector6<f64>>,
}

/// Normal equations accumulated over all 11 sensor parameters with
/// fixed-size blocks (no allocation per point); [`FullNormalEquations::select`]
/// then keeps the freed ones.
#[derive(Debug, Clone)]
pub struct FullNormalEquations {
    u: SMatrix<f64, N_GLOBAL, N_GLOBAL>,
    g_a: SMatrix<f64, N_GLOBAL, 1>,
    v: Vec<Matrix6<f64>>,
    w: Vec<SMatrix<f64, N_GLOBAL, 6>>,
    g_b: Vec<Vector6<f64>>,
}

impl FullNormalEquations {
    /// Zeroed blocks for `n` images.
    pub fn zeros(n: usize) -> Self {
        Self {
            u: SMatrix::zeros(),
            g_a: SMatrix::zeros(),
            v: vec![Matrix6::zeros(); n],
            w: vec![SMatrix::zeros(); n],
            g_b: vec![Vector6::zeros(); n],
        }
    }

    /// Adds one weighted 2-vector residual `r` of image `i` with its Jacobians
    /// `a = ∂r/∂(model, gains)` (all [`N_GLOBAL`] columns) and `b = ∂r/∂pose_i`.
    pub fn add(
        &mut self,
        i: usize,
        weight: f64,
        r: &Vector2<f64>,
        a: &SMatrix<f64, 2, N_GLOBAL>,
        b: &SMatrix<f64, 2, 6>,
    ) {
        let at = a.transpose() * weight;
        self.u += at * a;
        self.g_a += at * r;
        let bt = b.transpose() * weight;
        self.v[i] += bt * b;
        self.g_b[i] += bt * r;
        self.w[i] += at * b;
    }

    /// The normal equations of the freed global columns only (indices into
    /// the [`N_GLOBAL`] columns).
    pub fn select(&self, free: &[usize]) -> NormalEquations {
        let p = free.len();
        NormalEquations {
            u: DMatrix::from_fn(p, p, |i, j| self.u[(free[i], free[j])]),
            g_a: DVector::from_fn(p, |i, _| self.g_a[free[i]]),
            v: self.v.clone(),
            w: self
                .w
                .iter()
                .map(|w| DMatrix::from_fn(p, 6, |i, j| w[(free[i], j)]))
                .collect(),
            g_b: self.g_b.clone(),
        }
    }
}

/// A solved step: sensor-parameter part and one 6-vector per image.
#[derive(Debug, Clone)]
pub struct Step {
    /// `δa`.
    pub da: DVector<f64>,
    /// `δb_i` per image.
    pub db: Vec<Vector6<f64>>,
}

impl NormalEquations {
    /// Zeroed blocks for `p` sensor parameters and `n` images.
    pub fn zeros(p: usize, n: usize) -> Self {
        Self {
            u: DMatrix::zeros(p, p),
            g_a: DVector::zeros(p),
            v: vec![Matrix6::zeros(); n],
            w: vec![DMatrix::zeros(p, 6); n],
            g_b: vec![Vector6::zeros(); n],
        }
    }

    /// Solves `(JᵀJ + λ D) δ = −Jᵀr` with Marquardt damping: the diagonal of
    /// every block is multiplied by `1 + λ` (with a small floor so that a
    /// parameter without information cannot make the system singular).
    /// Returns `None` when the damped system is not positive definite.
    pub fn solve(&self, lambda: f64) -> Option<Step> {
        let p = self.u.nrows();
        let mut s = self.u.clone();
        damp(&mut s, lambda);
        let mut rhs = -&self.g_a;
        let mut v_inv = Vec::with_capacity(self.v.len());
        for i in 0..self.v.len() {
            let mut vi = self.v[i];
            for k in 0..6 {
                vi[(k, k)] *= 1.0 + lambda;
                vi[(k, k)] += 1e-12 * lambda.max(1e-12) * (1.0 + vi[(k, k)]);
            }
            let inv = vi.cholesky()?.inverse();
            if p > 0 {
                let wv = &self.w[i] * inv;
                s -= &wv * self.w[i].transpose();
                rhs += &wv * self.g_b[i];
            }
            v_inv.push(inv);
        }
        let da = if p > 0 {
            solve_scaled(&s, &rhs)?
        } else {
            DVector::zeros(0)
        };
        let db = (0..self.v.len())
            .map(|i| {
                let wt_da: Vector6<f64> = if p > 0 {
                    Vector6::from_iterator((self.w[i].transpose() * &da).iter().copied())
                } else {
                    Vector6::zeros()
                };
                v_inv[i] * (-self.g_b[i] - wt_da)
            })
            .collect();
        Some(Step { da, db })
    }

    /// The undamped covariance factors: `S⁻¹` (p × p) and, per image, the
    /// 6 × 6 marginal `V_i⁻¹ + V_i⁻¹ W_iᵀ S⁻¹ W_i V_i⁻¹` (both to be scaled by
    /// σ²). `None` when the information matrix is singular.
    pub fn inverse_blocks(&self) -> Option<(DMatrix<f64>, Vec<Matrix6<f64>>)> {
        let p = self.u.nrows();
        let mut s = self.u.clone();
        let mut v_inv = Vec::with_capacity(self.v.len());
        for i in 0..self.v.len() {
            let inv = self.v[i].cholesky()?.inverse();
            if p > 0 {
                s -= &self.w[i] * inv * self.w[i].transpose();
            }
            v_inv.push(inv);
        }
        let s_inv = if p > 0 {
            inverse_scaled(&s)?
        } else {
            DMatrix::zeros(0, 0)
        };
        let poses = (0..self.v.len())
            .map(|i| {
                if p == 0 {
                    return v_inv[i];
                }
                let m = &self.w[i].transpose() * &s_inv * &self.w[i];
                let m6 = Matrix6::from_iterator(m.iter().copied());
                v_inv[i] + v_inv[i] * m6 * v_inv[i]
            })
            .collect();
        Some((s_inv, poses))
    }

    /// `S = U − Σ W_i V_i⁻¹ W_iᵀ`, the information about the sensor
    /// parameters once the poses are eliminated (undamped).
    pub fn schur_complement(&self) -> Option<DMatrix<f64>> {
        let mut s = self.u.clone();
        for i in 0..self.v.len() {
            let inv = self.v[i].cholesky()?.inverse();
            s -= &self.w[i] * inv * self.w[i].transpose();
        }
        Some(s)
    }
}

fn damp(s: &mut DMatrix<f64>, lambda: f64) {
    for k in 0..s.nrows() {
        let d = s[(k, k)];
        s[(k, k)] = d * (1.0 + lambda) + 1e-12 * lambda.max(1e-12) * (1.0 + d);
    }
}

/// Solves `S x = rhs` for symmetric positive definite `S` after scaling it
/// to unit diagonal.
fn solve_scaled(s: &DMatrix<f64>, rhs: &DVector<f64>) -> Option<DVector<f64>> {
    let d = jacobi_scale(s)?;
    let scaled = DMatrix::from_fn(s.nrows(), s.ncols(), |i, j| s[(i, j)] * d[i] * d[j]);
    let rhs_scaled = rhs.component_mul(&d);
    let x = scaled.cholesky()?.solve(&rhs_scaled);
    Some(x.component_mul(&d))
}

/// Inverts symmetric positive definite `S` after scaling it to unit diagonal.
pub fn inverse_scaled(s: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let d = jacobi_scale(s)?;
    let scaled = DMatrix::from_fn(s.nrows(), s.ncols(), |i, j| s[(i, j)] * d[i] * d[j]);
    let inv = scaled.cholesky()?.inverse();
    Some(DMatrix::from_fn(s.nrows(), s.ncols(), |i, j| {
        inv[(i, j)] * d[i] * d[j]
    }))
}

fn jacobi_scale(s: &DMatrix<f64>) -> Option<DVector<f64>> {
    let d = DVector::from_iterator(s.nrows(), (0..s.nrows()).map(|k| s[(k, k)]));
    if d.iter().all(|v| *v > 0.0 && v.is_finite()) {
        Some(d.map(|v| 1.0 / v.sqrt()))
    } else {
        None
    }
}
