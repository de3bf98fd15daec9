//! The relative pose of two sensors from rays to the same points, without a
//! guess: the essential matrix by the eight-point method on unit rays inside
//! RANSAC, then its decomposition.
//!
//! With `j_from_i = (R, t)` (`X_j = R X_i + t`) and unit rays `x_i ∥ X_i`,
//! `x_j ∥ X_j`, the epipolar constraint is `x_jᵀ E x_i = 0`, `E = [t]× R`.
//! Rays (not pixels) keep wide angles well conditioned. Each pair gives one
//! row `kron(x_j, x_i)` of `A e = 0` (`e` = `E` row-major); `e` is the right
//! singular vector of the smallest singular value, projected onto the
//! essential manifold (singular values `(1, 1, 0)`). A pair's error is the
//! sine of the angle between `x_j` and the epipolar plane `E x_i`:
//! `|x_jᵀ E x_i| / ‖E x_i‖`, symmetrised with `‖Eᵀ x_j‖`.
//!
//! Decomposition: `E = U diag(1,1,0) Vᵀ` (`det U = det V = 1`),
//! `R ∈ {U W Vᵀ, U Wᵀ Vᵀ}`, `t = ±u₃`; the one placing the most points in
//! front of both sensors is kept. `‖t‖ = 1`: the scale comes later.

use nalgebra::{DMatrix, Matrix3, Vector3};
use psdcal_model::Pose;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A relative pose from shared rays.
#[derive(Debug, Clone)]
pub struct RelativePose {
    /// `j_from_i`, with `‖t‖ = 1`.
    pub j_from_i: Pose,
    /// Which ray pairs agree with it.
    pub inliers: Vec<bool>,
}

/// The essential matrix of least algebraic error through ray pairs
/// `(x_i, x_j)` (at least 8), projected onto the essential manifold.
pub fn eight_point(pairs: &[(Vector3<f64>, Vector3<f64>)]) -> Option<Matrix3<f64>> {
    if pairs.len() < 8 {
        return None;
    }
    // AᵀA (9 × 9) accumulated, its smallest eigenvector.
    let mut ata = DMatrix::<f64>::zeros(9, 9);
    let mut row = [0.0; 9];
    for (xi, xj) in pairs {
        for a in 0..3 {
            for b in 0..3 {
                row[3 * a + b] = xj[a] * xi[b];
            }
        }
        for a in 0..9 {
            for b in 0..9 {
                ata[(a, b)] += row[a] * row[b];
            }
        }
    }
    let eig = ata.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let e = eig.eigenvectors.column(k);
    let m = Matrix3::from_row_slice(e.as_slice());
    let svd = m.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    Some(u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 0.0)) * v_t)
}

/// The symmetric epipolar error of a ray pair (module documentation).
pub fn epipolar_error(e: &Matrix3<f64>, xi: &Vector3<f64>, xj: &Vector3<f64>) -> f64 {
    let ex = e * xi;
    let etx = e.transpose() * xj;
    let alg = xj.dot(&ex).abs();
    let n1 = ex.norm();
    let n2 = etx.norm();
    if n1 == 0.0 || n2 == 0.0 {
        return f64::INFINITY;
    }
    0.5 * (alg / n1 + alg / n2)
}

/// Pairs a RANSAC hypothesis is scored on, evenly spread over all of them:
/// the search costs the same however long the wand was waved.
const SCORED: usize = 2000;

/// How many times the best hypothesis' median error a pair may stray and
/// still agree.
const MEDIAN_FACTOR: f64 = 4.0;

/// The median of `v` (reordered).
fn median_of(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Least-median RANSAC over eight-pair samples (each hypothesis scored by
/// its median epipolar error over up to 2 000 pairs, so no threshold
/// has to be guessed), then the eight-point fit to every inlier and its
/// decomposition. A pair agrees when its error is below the larger of
/// `threshold` (rad) and 4 × the fit's median error: a lab
/// model's systematic error (a few mrad) moves every ray a little, a wrong
/// sighting moves one far.
pub fn relative_pose(
    pairs: &[(Vector3<f64>, Vector3<f64>)],
    threshold: f64,
    iterations: usize,
    rng: &mut ChaCha8Rng,
) -> Option<RelativePose> {
    let n = pairs.len();
    if n < 8 {
        return None;
    }
    let scored: Vec<_> = pairs.iter().step_by(n.div_ceil(SCORED)).collect();
    let mut errors = Vec::with_capacity(scored.len());
    let mut best: Option<(f64, Matrix3<f64>)> = None;
    let mut sample = Vec::with_capacity(8);
    for _ in 0..iterations {
        sample.clear();
        while sample.len() < 8 {
            let k = rng.random_range(0..n);
            if !sample.contains(&k) {
                sample.push(k);
            }
        }
        let chosen: Vec<_> = sample.iter().map(|&k| pairs[k]).collect();
        let Some(e) = eight_point(&chosen) else {
            continue;
        };
        errors.clear();
        errors.extend(scored.iter().map(|(xi, xj)| epipolar_error(&e, xi, xj)));
        let m = median_of(&mut errors);
        if m.is_finite() && best.as_ref().is_none_or(|(b, _)| m < *b) {
            best = Some((m, e));
        }
    }
    let (_, mut e) = best?;
    // Refit on the inliers twice (the set settles).
    let mut inliers = vec![false; n];
    let mut all = vec![0.0; n];
    let mut mark = |e: &Matrix3<f64>, inliers: &mut [bool]| {
        for (a, (xi, xj)) in all.iter_mut().zip(pairs) {
            *a = epipolar_error(e, xi, xj);
        }
        let mut sorted = all.clone();
        let bound = threshold.max(MEDIAN_FACTOR * median_of(&mut sorted));
        for (flag, a) in inliers.iter_mut().zip(&all) {
            *flag = *a < bound;
        }
    };
    for _ in 0..2 {
        mark(&e, &mut inliers);
        let chosen: Vec<_> = pairs
            .iter()
            .zip(&inliers)
            .filter(|(_, f)| **f)
            .map(|(p, _)| *p)
            .collect();
        e = eight_point(&chosen)?;
    }
    mark(&e, &mut inliers);
    let j_from_i = decompose(&e, pairs, &inliers)?;
    Some(RelativePose { j_from_i, inliers })
}

/// The decomposition of `E` that puts the most inlier points in front of
/// both sensors (module documentation).
pub fn decompose(
    e: &Matrix3<f64>,
    pairs: &[(Vector3<f64>, Vector3<f64>)],
    inliers: &[bool],
) -> Option<Pose> {
    let svd = e.svd(true, true);
    let (mut u, mut v_t) = (svd.u?, svd.v_t?);
    if u.determinant() < 0.0 {
        u = -u;
    }
    if v_t.determinant() < 0.0 {
        v_t = -v_t;
    }
    let w = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let t0: Vector3<f64> = u.column(2).into();
    let mut best: Option<(usize, Pose)> = None;
    for r in [u * w * v_t, u * w.transpose() * v_t] {
        for t in [t0, -t0] {
            let count = pairs
                .iter()
                .zip(inliers)
                .filter(|(_, f)| **f)
                .filter(|((xi, xj), _)| in_front(&r, &t, xi, xj))
                .count();
            if best.as_ref().is_none_or(|(c, _)| count > *c) {
                best = Some((count, Pose::from_rotation(&r, t)));
            }
        }
    }
    best.map(|(_, p)| p)
}

/// Whether the point seen along `xi` from sensor i and `xj` from sensor j
/// (`X_j = R X_i + t`) lies in front of both (positive depths of the
/// closest approach of the two rays).
pub fn in_front(r: &Matrix3<f64>, t: &Vector3<f64>, xi: &Vector3<f64>, xj: &Vector3<f64>) -> bool {
    match depths(r, t, xi, xj) {
        Some((si, sj)) => si > 0.0 && sj > 0.0,
        None => false,
    }
}

/// Depths `(s_i, s_j)` along `xi` (frame i) and `xj` (frame j) of the
/// closest approach of the two rays, `X_i ≈ s_i x_i`, `X_j ≈ s_j x_j`.
pub fn depths(
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    xi: &Vector3<f64>,
    xj: &Vector3<f64>,
) -> Option<(f64, f64)> {
    // In frame i: sensor j's centre c = −Rᵀt, its ray direction d = Rᵀ xj.
    let c = -(r.transpose() * t);
    let d = r.transpose() * xj;
    // Minimise ‖s_i xi − (c + s_j d)‖².
    let a11 = xi.dot(xi);
    let a12 = -xi.dot(&d);
    let a22 = d.dot(&d);
    let b1 = xi.dot(&c);
    let b2 = -d.dot(&c);
    let det = a11 * a22 - a12 * a12;
    if det.abs() < 1e-12 * a11 * a22 {
        return None;
    }
    let si = (b1 * a22 - a12 * b2) / det;
    let sj = (a11 * b2 - a12 * b1) / det;
    Some((si, sj))
}
