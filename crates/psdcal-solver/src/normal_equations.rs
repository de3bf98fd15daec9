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
//!
//! Residual rows (`d`, one or two) and the global size `p` are runtime
//! values; blocks are poses (six parameters).

use nalgebra::{DMatrix, DVector, Matrix6, Vector6};

/// Accumulated normal equations of one evaluation: `p` global parameters and
/// `n` blocks of six (runtime `p`: two coefficients or hundreds).
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
    /// Whether terms came through [`Self::add_columns`]: each `W_i` then
    /// has few non-zero rows, and [`Self::solve`] skips the others.
    pub sparse_rows: bool,
}

/// One residual's contribution: `d` rows (`r.len()`), its Jacobian with
/// respect to the `p` global parameters (`a`, d × p, column-major) and, when
/// it belongs to a block, with respect to that block (`b`, d × 6).
#[derive(Debug, Clone, Copy)]
pub struct ResidualTerm<'a> {
    /// The residual.
    pub r: &'a [f64],
    /// `∂r/∂a`, column-major (`a[d·j + row]`).
    pub a: &'a [f64],
    /// The block and `∂r/∂b_i` (column-major), when the residual has one.
    pub block: Option<(usize, &'a [f64])>,
}

/// Most global parameters whose two-row Jacobians [`NormalEquations::add`]
/// copies into contiguous rows; larger blocks (a PSD map's hundreds of
/// coefficients) use the interleaved loop.
pub const SPLIT_COLUMNS: usize = 48;

impl NormalEquations {
    /// Adds one residual with weight `weight` (robust reweighting). Only the
    /// upper triangle of `U` is accumulated ([`Self::finish`] mirrors it).
    /// This is the hot loop of every fit: columns are walked as `d`-row
    /// chunks, each product summed over the rows in one expression.
    pub fn add(&mut self, weight: f64, term: &ResidualTerm<'_>) {
        let d = term.r.len();
        if d == 2 {
            // Calibration's usual sizes, unrolled at compile time (the
            // preliminary correction's 2, the default fit's 5, with gains 8).
            return match self.g_a.len() {
                1 => self.add_pair_fixed::<1>(weight, term),
                2 => self.add_pair_fixed::<2>(weight, term),
                3 => self.add_pair_fixed::<3>(weight, term),
                4 => self.add_pair_fixed::<4>(weight, term),
                5 => self.add_pair_fixed::<5>(weight, term),
                6 => self.add_pair_fixed::<6>(weight, term),
                7 => self.add_pair_fixed::<7>(weight, term),
                8 => self.add_pair_fixed::<8>(weight, term),
                _ => self.add_pair(weight, term),
            };
        }
        let p = self.g_a.len();
        let (a, r) = (&term.a[..d * p], term.r);
        // Σ_rows x[row]·y[row] for two d-row columns.
        let dot = |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(x, y)| x * y).sum() };
        let u = self.u.as_mut_slice();
        let g_a = self.g_a.as_mut_slice();
        for (j, aj) in a.chunks_exact(d).enumerate() {
            g_a[j] += weight * dot(aj, r);
            // Column j of the column-major U, rows 0..=j (upper triangle).
            let column = &mut u[p * j..p * j + j + 1];
            for (slot, ak) in column.iter_mut().zip(a.chunks_exact(d)) {
                *slot += weight * dot(aj, ak);
            }
        }
        self.add_block(weight, term, a, None);
    }

    /// [`Self::add`] for a two-row residual (an image point), the common
    /// case, with the rows unrolled. For up to [`SPLIT_COLUMNS`] parameters
    /// the Jacobian's two rows are first copied apart (on the stack), so
    /// that the inner loops read contiguous slices and vectorise; every entry
    /// is the same expression as in the interleaved loop, so the sums are the
    /// same to the bit.
    fn add_pair(&mut self, weight: f64, term: &ResidualTerm<'_>) {
        let p = self.g_a.len();
        let (r0, r1) = (term.r[0], term.r[1]);
        let a = &term.a[..2 * p];
        let (mut rows0, mut rows1) = ([0.0; SPLIT_COLUMNS], [0.0; SPLIT_COLUMNS]);
        let split = p <= SPLIT_COLUMNS;
        if split {
            for (j, aj) in a.chunks_exact(2).enumerate() {
                rows0[j] = aj[0];
                rows1[j] = aj[1];
            }
        }
        let (a0, a1) = (
            &rows0[..p.min(SPLIT_COLUMNS)],
            &rows1[..p.min(SPLIT_COLUMNS)],
        );
        let u = self.u.as_mut_slice();
        let g_a = self.g_a.as_mut_slice();
        for (j, aj) in a.chunks_exact(2).enumerate() {
            let (x0, x1) = (weight * aj[0], weight * aj[1]);
            g_a[j] += x0 * r0 + x1 * r1;
            let column = &mut u[p * j..p * j + j + 1];
            if split {
                for ((slot, y0), y1) in column.iter_mut().zip(&a0[..=j]).zip(&a1[..=j]) {
                    *slot += x0 * y0 + x1 * y1;
                }
            } else {
                for (slot, ak) in column.iter_mut().zip(a.chunks_exact(2)) {
                    *slot += x0 * ak[0] + x1 * ak[1];
                }
            }
        }
        if let Some((i, b)) = term.block {
            let b: [f64; 12] = b[..12].try_into().expect("a 2 × 6 block Jacobian");
            self.add_pose_pair(i, weight, (r0, r1), &b);
            let w_i = self.w[i].as_mut_slice();
            for c in 0..6 {
                let (y0, y1) = (weight * b[2 * c], weight * b[2 * c + 1]);
                let column = &mut w_i[c * p..c * p + p];
                if split {
                    for ((slot, x0), x1) in column.iter_mut().zip(a0).zip(a1) {
                        *slot += x0 * y0 + x1 * y1;
                    }
                } else {
                    for (slot, aj) in column.iter_mut().zip(a.chunks_exact(2)) {
                        *slot += aj[0] * y0 + aj[1] * y1;
                    }
                }
            }
        }
    }

    /// [`Self::add_pair`] for `P` global parameters known at compile time:
    /// the same expression for every entry, in the same order (the sums are
    /// the same to the bit), with the loops' bounds constant.
    fn add_pair_fixed<const P: usize>(&mut self, weight: f64, term: &ResidualTerm<'_>) {
        let (r0, r1) = (term.r[0], term.r[1]);
        let a = &term.a[..2 * P];
        let (mut a0, mut a1) = ([0.0; P], [0.0; P]);
        for j in 0..P {
            a0[j] = a[2 * j];
            a1[j] = a[2 * j + 1];
        }
        let u = &mut self.u.as_mut_slice()[..P * P];
        let g_a = &mut self.g_a.as_mut_slice()[..P];
        for j in 0..P {
            let (x0, x1) = (weight * a0[j], weight * a1[j]);
            g_a[j] += x0 * r0 + x1 * r1;
            let column = &mut u[P * j..P * j + j + 1];
            for (k, slot) in column.iter_mut().enumerate() {
                *slot += x0 * a0[k] + x1 * a1[k];
            }
        }
        if let Some((i, b)) = term.block {
            let b: [f64; 12] = b[..12].try_into().expect("a 2 × 6 block Jacobian");
            self.add_pose_pair(i, weight, (r0, r1), &b);
            let w_i = &mut self.w[i].as_mut_slice()[..6 * P];
            for c in 0..6 {
                let (y0, y1) = (weight * b[2 * c], weight * b[2 * c + 1]);
                let column = &mut w_i[c * P..c * P + P];
                for j in 0..P {
                    column[j] += a0[j] * y0 + a1[j] * y1;
                }
            }
        }
    }

    /// The pose block's share of a two-row residual `r` with `∂r/∂b_i = b`
    /// (column-major): `g_i += w bᵀ r`, `V_i += w bᵀ b`.
    fn add_pose_pair(&mut self, i: usize, weight: f64, (r0, r1): (f64, f64), b: &[f64; 12]) {
        let v_i = self.v[i].as_mut_slice();
        let g_i = &mut self.g_b[i];
        for c in 0..6 {
            let (y0, y1) = (weight * b[2 * c], weight * b[2 * c + 1]);
            g_i[c] += y0 * r0 + y1 * r1;
            for k in 0..6 {
                v_i[6 * c + k] += y0 * b[2 * k] + y1 * b[2 * k + 1];
            }
        }
    }

    /// A `d`-row term's share of its block (any `d`): `g_i += w Bᵀ r`,
    /// `V_i += w BᵀB`, `W_i += w AᵀB`, with `a`'s column `j` the global
    /// column `columns[j]` (or `j`).
    fn add_block(
        &mut self,
        weight: f64,
        term: &ResidualTerm<'_>,
        a: &[f64],
        columns: Option<&[usize]>,
    ) {
        let Some((i, b)) = term.block else {
            return;
        };
        let (d, p, r) = (term.r.len(), self.g_a.len(), term.r);
        let dot = |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(x, y)| x * y).sum() };
        let b = &b[..6 * d];
        let w_i = self.w[i].as_mut_slice();
        let v_i = self.v[i].as_mut_slice();
        let g_i = &mut self.g_b[i];
        for (c, bc) in b.chunks_exact(d).enumerate() {
            g_i[c] += weight * dot(bc, r);
            for (slot, bk) in v_i[6 * c..6 * c + 6].iter_mut().zip(b.chunks_exact(d)) {
                *slot += weight * dot(bc, bk);
            }
            // W_i is p × 6, column-major: entry (j, c) at c·p + j.
            for (j, aj) in a.chunks_exact(d).enumerate() {
                let column = columns.map_or(j, |cs| cs[j]);
                w_i[c * p + column] += weight * dot(aj, bc);
            }
        }
    }

    /// [`Self::add`] for a term whose `a` (d × k, column-major) holds the
    /// global columns `columns` only (the others are zero): the same sums
    /// over the non-zero entries, `O(d k²)` instead of `O(d p²)`.
    pub fn add_columns(&mut self, weight: f64, term: &ResidualTerm<'_>, columns: &[usize]) {
        self.sparse_rows = true;
        let d = term.r.len();
        if d == 2 && columns.len() <= SPLIT_COLUMNS {
            return self.add_columns_pair(weight, term, columns);
        }
        let p = self.g_a.len();
        let a = &term.a[..d * columns.len()];
        let r = term.r;
        let dot = |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(x, y)| x * y).sum() };
        let u = self.u.as_mut_slice();
        for (j, aj) in a.chunks_exact(d).enumerate() {
            let cj = columns[j];
            self.g_a[cj] += weight * dot(aj, r);
            for (k, ak) in a.chunks_exact(d).enumerate() {
                let ck = columns[k];
                // Upper triangle only (row ≤ column), as `add` fills it.
                if ck <= cj {
                    u[p * cj + ck] += weight * dot(aj, ak);
                }
            }
        }
        self.add_block(weight, term, a, Some(columns));
    }

    /// [`Self::add_columns`] for a two-row residual, its rows copied apart.
    fn add_columns_pair(&mut self, weight: f64, term: &ResidualTerm<'_>, columns: &[usize]) {
        let p = self.g_a.len();
        let k = columns.len();
        let (r0, r1) = (term.r[0], term.r[1]);
        let (mut a0, mut a1) = ([0.0; SPLIT_COLUMNS], [0.0; SPLIT_COLUMNS]);
        for (j, aj) in term.a[..2 * k].chunks_exact(2).enumerate() {
            a0[j] = aj[0];
            a1[j] = aj[1];
        }
        let u = self.u.as_mut_slice();
        for j in 0..k {
            let cj = columns[j];
            let (x0, x1) = (weight * a0[j], weight * a1[j]);
            self.g_a[cj] += x0 * r0 + x1 * r1;
            let column = &mut u[p * cj..p * cj + p];
            for m in 0..k {
                let cm = columns[m];
                if cm <= cj {
                    column[cm] += x0 * a0[m] + x1 * a1[m];
                }
            }
        }
        if let Some((i, b)) = term.block {
            let b: [f64; 12] = b[..12].try_into().expect("a 2 × 6 block Jacobian");
            self.add_pose_pair(i, weight, (r0, r1), &b);
            let w_i = self.w[i].as_mut_slice();
            for c in 0..6 {
                let (y0, y1) = (weight * b[2 * c], weight * b[2 * c + 1]);
                let column = &mut w_i[c * p..c * p + p];
                for j in 0..k {
                    column[columns[j]] += a0[j] * y0 + a1[j] * y1;
                }
            }
        }
    }

    /// Mirrors the upper triangle of `U` (accumulated by [`Self::add`]).
    pub fn finish(&mut self) {
        let p = self.u.nrows();
        for j in 0..p {
            for k in (j + 1)..p {
                self.u[(k, j)] = self.u[(j, k)];
            }
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
            sparse_rows: false,
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
        let mut factors = Vec::with_capacity(if self.sparse_rows { self.v.len() } else { 0 });
        for i in 0..self.v.len() {
            let mut vi = self.v[i];
            for k in 0..6 {
                vi[(k, k)] *= 1.0 + lambda;
                vi[(k, k)] += 1e-12 * lambda.max(1e-12) * (1.0 + vi[(k, k)]);
            }
            let chol = vi.cholesky()?;
            let inv = chol.inverse();
            if p > 0 && self.sparse_rows {
                factors.push(chol.l().try_inverse()?);
            } else if p > 0 {
                let wv = &self.w[i] * inv;
                s -= &wv * self.w[i].transpose();
                rhs += &wv * self.g_b[i];
            }
            v_inv.push(inv);
        }
        if p > 0 && self.sparse_rows {
            subtract_by_products(&mut s, &mut rhs, &self.w, &factors, &self.g_b);
        }
        let da = if p > 0 {
            solve_scaled(&s, &rhs)?
        } else {
            DVector::zeros(0)
        };
        let db = (0..self.v.len())
            .map(|i| {
                // W_iᵀ δa, column by column of the column-major W_i.
                let w = self.w[i].as_slice();
                let wt_da = Vector6::from_fn(|c, _| {
                    w[c * p..c * p + p]
                        .iter()
                        .zip(da.iter())
                        .map(|(x, y)| x * y)
                        .sum()
                });
                v_inv[i] * (-self.g_b[i] - wt_da)
            })
            .collect();
        Some(Step { da, db })
    }

    /// The decrease of the cost the linear model predicts for `step`:
    /// `‖r‖² − ‖r + Jδ‖² = −2 gᵀδ − δᵀ JᵀJ δ` from the blocks of the normal
    /// equations (`g = Jᵀr`).
    pub fn predicted_decrease(&self, step: &Step) -> f64 {
        let da = &step.da;
        let mut g_dot = self.g_a.dot(da);
        let mut quad = (&self.u * da).dot(da);
        for (i, db) in step.db.iter().enumerate() {
            g_dot += self.g_b[i].dot(db);
            quad += db.dot(&(self.v[i] * db));
            if !da.is_empty() {
                quad += 2.0
                    * (self.w[i].transpose() * da)
                        .iter()
                        .zip(db.iter())
                        .map(|(a, b)| a * b)
                        .sum::<f64>();
            }
        }
        -2.0 * g_dot - quad
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
    ///
    /// The products are written out (upper triangle, then mirrored: `S` is
    /// exactly symmetric): nalgebra hands products of matrices wider than
    /// five to matrixmultiply, whose first call detects the CPU's features,
    /// a dozen `cpuid` instructions that cost 13 µs each under a hypervisor
    /// (measured here) — more than the whole product for the sizes of
    /// calibration.
    ///
    /// With [`Self::sparse_rows`], only each `W_i`'s non-zero rows are
    /// visited (a network's frame touches the sensors that saw it).
    pub fn schur_complement(&self) -> Option<DMatrix<f64>> {
        let p = self.u.nrows();
        let mut s = self.u.clone();
        if self.sparse_rows {
            let factors = self
                .v
                .iter()
                .map(|v| v.cholesky()?.l().try_inverse())
                .collect::<Option<Vec<_>>>()?;
            let zeros = vec![Vector6::zeros(); self.v.len()];
            subtract_by_products(&mut s, &mut DVector::zeros(p), &self.w, &factors, &zeros);
            return Some(s);
        }
        let mut x = vec![0.0; 6 * p];
        for (w, v) in self.w.iter().zip(&self.v) {
            let inv = v.cholesky()?.inverse();
            // X = W V⁻¹ (p × 6, column-major like W).
            for c in 0..6 {
                for j in 0..p {
                    x[c * p + j] = (0..6).map(|l| w[(j, l)] * inv[(l, c)]).sum();
                }
            }
            // S −= X Wᵀ, upper triangle.
            for k in 0..p {
                for j in 0..=k {
                    let xw: f64 = (0..6).map(|c| x[c * p + j] * w[(k, c)]).sum();
                    s[(j, k)] -= xw;
                }
            }
        }
        for k in 0..p {
            for j in 0..k {
                s[(k, j)] = s[(j, k)];
            }
        }
        Some(s)
    }
}

/// Frames side by side in one product of [`subtract_by_products`].
const CHUNK: usize = 64;

/// `S −= Σ W_i V_i⁻¹ W_iᵀ`, `rhs += Σ W_i V_i⁻¹ g_i` given `L_i⁻¹`
/// (`V_i = L_i L_iᵀ`): with `X_i = W_i L_i⁻ᵀ` (p × 6), `W_i V_i⁻¹ W_iᵀ =
/// X_i X_iᵀ` and `W_i V_i⁻¹ g_i = X_i (L_i⁻¹ g_i)`; [`CHUNK`] of the `X_i`
/// side by side make one matrix product (matrixmultiply's kernels: many
/// frames, each touching most of the global block, as a network's do).
/// `S` is mirrored from its upper triangle afterwards (exactly symmetric).
/// Sums in a fixed order: the result does not depend on the machine's
/// threads.
fn subtract_by_products(
    s: &mut DMatrix<f64>,
    rhs: &mut DVector<f64>,
    w: &[DMatrix<f64>],
    l_inv: &[Matrix6<f64>],
    g: &[Vector6<f64>],
) {
    let p = s.nrows();
    let mut x = DMatrix::<f64>::zeros(p, 6 * CHUNK.min(w.len()));
    for start in (0..w.len()).step_by(CHUNK) {
        let end = (start + CHUNK).min(w.len());
        for i in start..end {
            let wi = w[i].as_slice();
            let li = &l_inv[i];
            let lg = li * g[i];
            let first = 6 * (i - start);
            for c in 0..6 {
                // Column c of X_i: Σ_l W_i[:, l] L⁻¹[c, l] (L⁻¹ lower: l ≤ c).
                let column = &mut x.as_mut_slice()[(first + c) * p..(first + c + 1) * p];
                column.fill(0.0);
                for l in 0..=c {
                    let f = li[(c, l)];
                    for (out, v) in column.iter_mut().zip(&wi[l * p..l * p + p]) {
                        *out += f * v;
                    }
                }
                for (r, v) in rhs.iter_mut().zip(column.iter()) {
                    *r += v * lg[c];
                }
            }
        }
        let used = x.columns(0, 6 * (end - start));
        s.gemm(-1.0, &used, &used.transpose(), 1.0);
    }
    for k in 0..p {
        for j in 0..k {
            s[(k, j)] = s[(j, k)];
        }
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

#[cfg(test)]
mod tests {
    //! The blocks against the dense `JᵀWJ` and `JᵀWr` of the same residuals,
    //! assembled row by row with no block structure, and the Schur step
    //! against a dense solve of the damped system.

    use super::*;

    /// A reproducible pseudo-random value in [−1, 1) (no RNG dependency).
    fn value(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    struct Term {
        r: Vec<f64>,
        a: Vec<f64>,
        block: Option<(usize, Vec<f64>)>,
        weight: f64,
    }

    /// `count` residuals of `d` rows over `p` globals and `n` blocks; every
    /// third residual has no block.
    fn terms(p: usize, n: usize, d: usize, count: usize, seed: &mut u64) -> Vec<Term> {
        (0..count)
            .map(|t| Term {
                r: (0..d).map(|_| value(seed)).collect(),
                a: (0..d * p).map(|_| value(seed)).collect(),
                block: (t % 3 != 2).then(|| (t % n, (0..6 * d).map(|_| value(seed)).collect())),
                weight: 0.5 + value(seed).abs(),
            })
            .collect()
    }

    /// The dense Jacobian (rows: residual rows; columns: p globals, then 6
    /// per block), residuals and weights.
    fn dense(
        p: usize,
        n: usize,
        d: usize,
        terms: &[Term],
    ) -> (DMatrix<f64>, DVector<f64>, DVector<f64>) {
        let rows = terms.len() * d;
        let mut j = DMatrix::zeros(rows, p + 6 * n);
        let mut r = DVector::zeros(rows);
        let mut w = DVector::zeros(rows);
        for (t, term) in terms.iter().enumerate() {
            for row in 0..d {
                let i = t * d + row;
                r[i] = term.r[row];
                w[i] = term.weight;
                for k in 0..p {
                    j[(i, k)] = term.a[d * k + row];
                }
                if let Some((b, jb)) = &term.block {
                    for c in 0..6 {
                        j[(i, p + 6 * b + c)] = jb[d * c + row];
                    }
                }
            }
        }
        (j, r, w)
    }

    fn accumulate(p: usize, n: usize, terms: &[Term]) -> NormalEquations {
        let mut ne = NormalEquations::zeros(p, n);
        for t in terms {
            ne.add(
                t.weight,
                &ResidualTerm {
                    r: &t.r,
                    a: &t.a,
                    block: t.block.as_ref().map(|(i, b)| (*i, b.as_slice())),
                },
            );
        }
        ne.finish();
        ne
    }

    #[test]
    fn blocks_equal_the_dense_normal_equations() {
        let mut seed = 11;
        for (p, n, d) in [
            (5, 4, 2),
            (1, 3, 1),
            (0, 2, 2),
            (12, 2, 2),
            (3, 1, 1),
            (1, 2, 2),
            (2, 3, 2),
            (8, 2, 2),
            (9, 2, 2),
        ] {
            let terms = terms(p, n, d, 40, &mut seed);
            let ne = accumulate(p, n, &terms);
            let (j, r, w) = dense(p, n, d, &terms);
            let jw = DMatrix::from_fn(j.nrows(), j.ncols(), |i, k| j[(i, k)] * w[i]);
            let h = jw.transpose() * &j;
            let g = jw.transpose() * &r;
            let tol = 1e-12 * h.amax().max(1.0);
            for a in 0..p {
                assert!((ne.g_a[a] - g[a]).abs() <= tol);
                for b in 0..p {
                    assert!(
                        (ne.u[(a, b)] - h[(a, b)]).abs() <= tol,
                        "U({a},{b}) p={p} d={d}"
                    );
                }
            }
            for i in 0..n {
                for c in 0..6 {
                    assert!((ne.g_b[i][c] - g[p + 6 * i + c]).abs() <= tol);
                    for k in 0..6 {
                        let dense = h[(p + 6 * i + c, p + 6 * i + k)];
                        assert!((ne.v[i][(c, k)] - dense).abs() <= tol, "V_{i}({c},{k})");
                    }
                    for a in 0..p {
                        let dense = h[(a, p + 6 * i + c)];
                        assert!((ne.w[i][(a, c)] - dense).abs() <= tol, "W_{i}({a},{c})");
                    }
                }
            }
        }
    }

    #[test]
    fn schur_complement_equals_the_products_and_is_symmetric() {
        let mut seed = 17;
        // n prime to 3: `terms` leaves every third residual without a block.
        for (p, n) in [(3, 4), (5, 5), (8, 4), (19, 7)] {
            let terms = terms(p, n, 2, 12 * n, &mut seed);
            let ne = accumulate(p, n, &terms);
            let s = ne.schur_complement().expect("positive definite blocks");
            let mut expected = ne.u.clone();
            for i in 0..n {
                let inv = ne.v[i].try_inverse().expect("invertible");
                expected -= &ne.w[i] * inv * ne.w[i].transpose();
            }
            let tol = 1e-12 * expected.amax();
            for j in 0..p {
                for k in 0..p {
                    assert!(
                        (s[(j, k)] - expected[(j, k)]).abs() <= tol,
                        "S({j},{k}) p={p}"
                    );
                    assert_eq!(s[(j, k)], s[(k, j)]);
                }
            }
        }
    }

    #[test]
    fn schur_step_equals_the_dense_damped_solve() {
        let mut seed = 5;
        let (p, n, d) = (4, 3, 2);
        let terms = terms(p, n, d, 60, &mut seed);
        let ne = accumulate(p, n, &terms);
        let (j, r, w) = dense(p, n, d, &terms);
        let jw = DMatrix::from_fn(j.nrows(), j.ncols(), |i, k| j[(i, k)] * w[i]);
        let mut h = jw.transpose() * &j;
        let g = jw.transpose() * &r;
        let lambda = 0.3;
        for k in 0..h.nrows() {
            let dk = h[(k, k)];
            h[(k, k)] = dk * (1.0 + lambda) + 1e-12 * lambda * (1.0 + dk);
        }
        let x = h.clone().lu().solve(&(-&g)).expect("dense system solves");
        let step = ne.solve(lambda).expect("positive definite");
        let scale = x.amax();
        for k in 0..p {
            assert!((step.da[k] - x[k]).abs() <= 1e-10 * scale, "δa[{k}]");
        }
        for i in 0..n {
            for c in 0..6 {
                assert!((step.db[i][c] - x[p + 6 * i + c]).abs() <= 1e-10 * scale);
            }
        }
    }
}
