//! The 3 × 4 projection matrix of one image of surveyed, non-coplanar
//! points (docs/model.md §8.4): `λ (x, y, 1)ᵀ = P (X, Y, Z, 1)ᵀ`.
//!
//! - [`dlt_projection`]: the normalised DLT. Points and image points are
//!   translated to their centroids and scaled to mean distances √3 and √2
//!   (Hartley's normalisation, as (P36)–(P38) for the planar case); `P` is
//!   the null vector of the 2n × 12 system (SVD of the padded system, so
//!   the null vector is kept), which needs n ≥ 6 points off any one plane.
//! - [`decompose_projection`]: `P = K [R | t]` by RQ decomposition, `K`
//!   upper triangular with a positive diagonal and `K₃₃ = 1`, `det R = +1`.
//! - [`flatness`]: how far a cloud is from a plane (the ratio of its
//!   smallest to its largest principal spread), to refuse coplanar
//!   surveys before the DLT.
//! - `relative_reprojection`: a DLT's reprojection error relative to the
//!   spread of the image points (scale-free), the score of the start's
//!   preliminary radial correction.

use nalgebra::{DMatrix, Matrix3, Matrix3x4, Vector2, Vector3};
use psdcal_model::Pose;

/// Fewest points per image for the 3 × 4 DLT (11 unknowns, 2 rows a point).
pub const MIN_SURVEYED_POINTS: usize = 6;

/// The cloud's third principal spread over its first (0: coplanar).
pub fn flatness(points: &[Vector3<f64>]) -> f64 {
    let n = points.len().max(1) as f64;
    let mean = points.iter().fold(Vector3::zeros(), |s, p| s + p) / n;
    let scatter = points.iter().fold(Matrix3::zeros(), |s, p| {
        s + (p - mean) * (p - mean).transpose()
    });
    let mut ev: Vec<f64> = scatter.symmetric_eigenvalues().iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    if ev[2] <= 0.0 {
        return 0.0;
    }
    (ev[0].max(0.0) / ev[2]).sqrt()
}

/// The normalised DLT of one image's 3 × 4 projection matrix (module
/// documentation); `None` when the system has no clear null vector.
pub fn dlt_projection(points: &[Vector3<f64>], image: &[Vector2<f64>]) -> Option<Matrix3x4<f64>> {
    let n = points.len();
    if n < MIN_SURVEYED_POINTS || image.len() != n {
        return None;
    }
    let (t3, s3) = normalisation3(points);
    let (t2, s2) = normalisation2(image);
    // At least 12 rows; padded with zero rows so the SVD is of a tall matrix
    // and keeps every right singular vector.
    let rows = (2 * n).max(12);
    let mut a = DMatrix::<f64>::zeros(rows, 12);
    for (k, (p, q)) in points.iter().zip(image).enumerate() {
        let p = (p - t3) * s3;
        let q = (q - t2) * s2;
        let ph = [p.x, p.y, p.z, 1.0];
        for c in 0..4 {
            a[(2 * k, c)] = ph[c];
            a[(2 * k, 8 + c)] = -q.x * ph[c];
            a[(2 * k + 1, 4 + c)] = ph[c];
            a[(2 * k + 1, 8 + c)] = -q.y * ph[c];
        }
    }
    let svd = a.svd(false, true);
    let v_t = svd.v_t?;
    let (imin, _) = svd
        .singular_values
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    let h = v_t.row(imin);
    let pn = Matrix3x4::from_fn(|r, c| h[4 * r + c]);
    // Undo the normalisations: P = T2⁻¹ P̃ T3.
    let t2_inv = Matrix3::new(1.0 / s2, 0.0, t2.x, 0.0, 1.0 / s2, t2.y, 0.0, 0.0, 1.0);
    let mut t3m = nalgebra::Matrix4::<f64>::identity() * s3;
    t3m[(3, 3)] = 1.0;
    for r in 0..3 {
        t3m[(r, 3)] = -s3 * t3[r];
    }
    let p = t2_inv * pn * t3m;
    p.iter().all(|v| v.is_finite()).then_some(p)
}

fn normalisation3(points: &[Vector3<f64>]) -> (Vector3<f64>, f64) {
    let n = points.len() as f64;
    let c = points.iter().fold(Vector3::zeros(), |s, p| s + p) / n;
    let d = points.iter().map(|p| (p - c).norm()).sum::<f64>() / n;
    (c, 3f64.sqrt() / d.max(f64::MIN_POSITIVE))
}

fn normalisation2(points: &[Vector2<f64>]) -> (Vector2<f64>, f64) {
    let n = points.len() as f64;
    let c = points.iter().fold(Vector2::zeros(), |s, p| s + p) / n;
    let d = points.iter().map(|p| (p - c).norm()).sum::<f64>() / n;
    (c, 2f64.sqrt() / d.max(f64::MIN_POSITIVE))
}

/// `P = K [R | t]` with `K` upper triangular (positive diagonal, `K₃₃ = 1`)
/// and `R` a rotation, by RQ decomposition; `P`'s sign is chosen so that
/// `det P₁:₃ > 0`.
pub fn decompose_projection(p: &Matrix3x4<f64>) -> Option<(Matrix3<f64>, Pose)> {
    let mut m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
    let mut p4: Vector3<f64> = p.column(3).into_owned();
    if m.determinant() < 0.0 {
        m = -m;
        p4 = -p4;
    }
    // RQ through QR of the row-reversed transpose: with E the exchange
    // matrix, (E M)ᵀ = Q̃ R̃ gives M = (E R̃ᵀ E)(E Q̃ᵀ).
    let e = Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0);
    let qr = (e * m).transpose().qr();
    let (q, r) = (qr.q(), qr.r());
    let mut k = e * r.transpose() * e;
    let mut rot = e * q.transpose();
    for i in 0..3 {
        if k[(i, i)] < 0.0 {
            k.set_column(i, &(-k.column(i)));
            rot.set_row(i, &(-rot.row(i)));
        }
    }
    if rot.determinant() < 0.0 || k[(2, 2)] <= 0.0 {
        return None;
    }
    let t = k.try_inverse()? * p4;
    let k = k / k[(2, 2)];
    k.iter()
        .chain(t.iter())
        .all(|v| v.is_finite())
        .then(|| (k, Pose::from_rotation(&rot, t)))
}

/// The start of every image (module documentation): the intrinsics' median
/// over the images, each image's pose from its own DLT.
/// Σ ‖proj(P X) − q‖² over Σ ‖q − q̄‖².
pub(crate) fn relative_reprojection(
    p: &Matrix3x4<f64>,
    pts: &[Vector3<f64>],
    q: &[Vector2<f64>],
) -> f64 {
    let n = q.len() as f64;
    let mean = q.iter().fold(Vector2::zeros(), |s, v| s + v) / n;
    let spread: f64 = q.iter().map(|v| (v - mean).norm_squared()).sum();
    let err: f64 = pts
        .iter()
        .zip(q)
        .map(|(x, q)| {
            let h = p * x.push(1.0);
            if h.z.abs() < f64::MIN_POSITIVE {
                return f64::INFINITY;
            }
            (Vector2::new(h.x / h.z, h.y / h.z) - q).norm_squared()
        })
        .sum();
    err / spread.max(f64::MIN_POSITIVE)
}
