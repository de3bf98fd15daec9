//! Small 3-D geometry of the start: the least-squares meeting point of
//! rays, the rigid fit of two point sets (Kabsch). (A sensor's optical
//! centre in the world with its Jacobian is psdcal-model's
//! `Pose::centre_with_jacobian`.)
//!
//! - Rays `c_k + s d_k` (unit `d_k`) meet at the `X` minimising
//!   `Σ ‖(I − d_k d_kᵀ)(X − c_k)‖²`: `(Σ P_k) X = Σ P_k c_k`, `P_k = I − d_k d_kᵀ`.
//! - Kabsch: `R, t` minimising `Σ ‖R a_k + t − b_k‖²`: with centroids `ā, b̄`
//!   and `H = Σ (a_k − ā)(b_k − b̄)ᵀ = U Σ Vᵀ`, `R = V diag(1, 1, det(V Uᵀ)) Uᵀ`,
//!   `t = b̄ − R ā`. For collinear points the rotation about their line is
//!   arbitrary (the minimal rotation is returned).

use nalgebra::{Matrix3, Vector3};
use psdcal_model::Pose;

/// The least-squares meeting point of rays (origins, unit directions), or
/// `None` when they are (nearly) parallel or fewer than two.
pub fn meet_rays(rays: &[(Vector3<f64>, Vector3<f64>)]) -> Option<Vector3<f64>> {
    if rays.len() < 2 {
        return None;
    }
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for (c, d) in rays {
        let p = Matrix3::identity() - d * d.transpose();
        a += p;
        b += p * c;
    }
    let eig = a.symmetric_eigen();
    let min = eig.eigenvalues.min();
    if min < 1e-8 * rays.len() as f64 {
        return None;
    }
    a.cholesky().map(|c| c.solve(&b))
}

/// `b_from_a` (rigid) fitted to point pairs `(a_k, b_k)` (module
/// documentation); `None` for fewer than two pairs.
pub fn kabsch(pairs: &[(Vector3<f64>, Vector3<f64>)]) -> Option<Pose> {
    if pairs.len() < 2 {
        return None;
    }
    let n = pairs.len() as f64;
    let ca = pairs.iter().map(|p| p.0).sum::<Vector3<f64>>() / n;
    let cb = pairs.iter().map(|p| p.1).sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (a, b) in pairs {
        h += (a - ca) * (b - cb).transpose();
    }
    let r = if pairs.len() == 2 || h.rank(1e-9 * h.norm().max(1e-300)) < 2 {
        let (a, b) = (pairs[0].0 - pairs[1].0, pairs[0].1 - pairs[1].1);
        rotation_between(&a, &b)?
    } else {
        let svd = h.svd(true, true);
        let (u, v_t) = (svd.u?, svd.v_t?);
        let v = v_t.transpose();
        let d = (v * u.transpose()).determinant().signum();
        v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose()
    };
    Some(Pose::from_rotation(&r, cb - r * ca))
}

/// The smallest rotation taking the direction of `a` to that of `b`.
pub fn rotation_between(a: &Vector3<f64>, b: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let (a, b) = (a.try_normalize(1e-300)?, b.try_normalize(1e-300)?);
    let axis = a.cross(&b);
    let s = axis.norm();
    let c = a.dot(&b);
    if s < 1e-12 {
        if c > 0.0 {
            return Some(Matrix3::identity());
        }
        // Half a turn about any axis perpendicular to a.
        let other = if a.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let k = a.cross(&other).normalize();
        return Some(2.0 * k * k.transpose() - Matrix3::identity());
    }
    let angle = s.atan2(c);
    Some(Pose::new(axis / s * angle, Vector3::zeros()).rotation())
}
