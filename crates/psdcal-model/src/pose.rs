//! Rigid poses as a Rodrigues vector plus a translation (docs/model.md §3, (P3)).
//!
//! A [`Pose`] named `sensor_from_template` maps template-frame points to the
//! sensor frame: `P_c = R(rvec) P_t + t`, millimetres. The rotation is
//! `R = I + a K + b K²` with `K = [rvec]×`, `θ = ‖rvec‖`, `a = sin θ / θ`,
//! `b = (1 − cos θ)/θ²`. Its derivative with respect to `rvec_i` is
//!
//! ```text
//! ∂R/∂v_i = a [e_i]× + b ([e_i]× K + K [e_i]×) + v_i (c K + d K²),
//! c = a'(θ)/θ = (θ cos θ − sin θ)/θ³,   d = b'(θ)/θ = (θ sin θ − 2(1 − cos θ))/θ⁴,
//! ```
//!
//! with `a, b, c, d` taken from their Taylor series below θ = 0.1, so the
//! derivative is exact to rounding at every angle including zero.
//! Pose parameter vectors are ordered `(rx, ry, rz, tx, ty, tz)`.

use nalgebra::{Matrix3, Rotation3, SMatrix, UnitQuaternion, Vector3};

/// Number of pose parameters: Rodrigues vector (3) and translation (3).
pub const N_POSE: usize = 6;

/// A rotation matrix with its derivatives with respect to the Rodrigues
/// vector: computed once per pose and shared by every point seen in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotationJacobian {
    /// `R(rvec)`.
    pub r: Matrix3<f64>,
    /// `∂R/∂rvec_i`, i = 0, 1, 2.
    pub dr: [Matrix3<f64>; 3],
}

/// A rigid transformation `P_dst = R(rvec) P_src + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rodrigues vector (axis × angle), radians.
    pub rvec: Vector3<f64>,
    /// Translation, mm.
    pub t: Vector3<f64>,
}

/// The coefficients `a, b, c, d` of the module documentation.
fn rodrigues_coefficients(theta: f64) -> [f64; 4] {
    if theta < 0.1 {
        rodrigues_series(theta)
    } else {
        rodrigues_closed_form(theta)
    }
}

/// Taylor series of `a, b, c, d`, truncated after the θ⁶ or θ⁸ term (error
/// below 1e-17 for θ < 0.1).
fn rodrigues_series(theta: f64) -> [f64; 4] {
    let t2 = theta * theta;
    let a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0)));
    let b = 0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0)));
    let c = -1.0 / 3.0 + t2 / 30.0 - t2 * t2 / 840.0 + t2 * t2 * t2 / 45360.0;
    let d = -1.0 / 12.0 + t2 / 180.0 - t2 * t2 / 6720.0 + t2 * t2 * t2 / 453600.0;
    [a, b, c, d]
}

/// Closed forms of `a, b, c, d`, with `1 − cos θ = 2 sin²(θ/2)` to avoid
/// one cancellation; the remaining one costs about ε/θ² in `c` and `d`, hence
/// the series below θ = 0.1.
fn rodrigues_closed_form(theta: f64) -> [f64; 4] {
    let (s, co) = theta.sin_cos();
    let half = (0.5 * theta).sin();
    let one_minus_cos = 2.0 * half * half;
    let t2 = theta * theta;
    [
        s / theta,
        one_minus_cos / t2,
        (theta * co - s) / (t2 * theta),
        (theta * s - 2.0 * one_minus_cos) / (t2 * t2),
    ]
}

/// The cross-product matrix `[v]×`.
pub fn skew_matrix(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

impl Pose {
    /// The identity pose.
    pub fn identity() -> Self {
        Self {
            rvec: Vector3::zeros(),
            t: Vector3::zeros(),
        }
    }

    /// A pose from a Rodrigues vector (rad) and a translation (mm).
    pub fn new(rvec: Vector3<f64>, t: Vector3<f64>) -> Self {
        Self { rvec, t }
    }

    /// A pose from a rotation matrix (assumed orthonormal, det +1) and a
    /// translation. The logarithm goes through a unit quaternion, so angles
    /// near π are handled.
    pub fn from_rotation(rotation: &Matrix3<f64>, t: Vector3<f64>) -> Self {
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rotation));
        Self {
            rvec: q.scaled_axis(),
            t,
        }
    }

    /// The parameter vector `(rx, ry, rz, tx, ty, tz)`.
    pub fn to_array(&self) -> [f64; N_POSE] {
        [
            self.rvec.x,
            self.rvec.y,
            self.rvec.z,
            self.t.x,
            self.t.y,
            self.t.z,
        ]
    }

    /// The pose of a parameter vector `(rx, ry, rz, tx, ty, tz)`.
    pub fn from_array(p: &[f64; N_POSE]) -> Self {
        Self {
            rvec: Vector3::new(p[0], p[1], p[2]),
            t: Vector3::new(p[3], p[4], p[5]),
        }
    }

    /// The pose whose parameters `(rvec, t)` are this one's plus `delta`
    /// (a solver's step on the pose block, in [`Self::to_array`]'s order).
    pub fn stepped(&self, delta: &[f64]) -> Self {
        let a = self.to_array();
        Self::from_array(&std::array::from_fn(|k| a[k] + delta[k]))
    }

    /// The rotation matrix `R(rvec)`.
    pub fn rotation(&self) -> Matrix3<f64> {
        let [a, b, _, _] = rodrigues_coefficients(self.rvec.norm());
        let k = skew_matrix(&self.rvec);
        Matrix3::identity() + k * a + k * k * b
    }

    /// The rotation matrix and its derivatives `∂R/∂rvec_i`, i = 0, 1, 2.
    pub fn rotation_with_derivatives(&self) -> (Matrix3<f64>, [Matrix3<f64>; 3]) {
        let v = self.rvec;
        let [a, b, c, d] = rodrigues_coefficients(v.norm());
        let k = skew_matrix(&v);
        let k2 = k * k;
        let r = Matrix3::identity() + k * a + k2 * b;
        let common = k * c + k2 * d;
        let deriv = [0, 1, 2].map(|i| {
            let e = skew_matrix(&Vector3::ith(i, 1.0));
            e * a + (e * k + k * e) * b + common * v[i]
        });
        (r, deriv)
    }

    /// For `self` = `sensor_from_world`: the sensor's optical centre in the
    /// world, `c = −Rᵀ t`, and `∂c/∂(rvec, t)` (3 × 6): `∂c/∂rvec_k =
    /// −(∂R/∂rvec_k)ᵀ t`, `∂c/∂t = −Rᵀ`.
    pub fn centre_with_jacobian(&self) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
        let (r, dr) = self.rotation_with_derivatives();
        let t = self.t;
        let mut j = SMatrix::<f64, 3, 6>::zeros();
        for (k, d) in dr.iter().enumerate() {
            j.set_column(k, &(-(d.transpose() * t)));
        }
        j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r.transpose()));
        (-(r.transpose() * t), j)
    }

    /// The rotation and its derivatives, for reuse over many points.
    pub fn rotation_jacobian(&self) -> RotationJacobian {
        let (r, dr) = self.rotation_with_derivatives();
        RotationJacobian { r, dr }
    }

    /// Applies the pose to a point: `R p + t`.
    pub fn transform(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation() * p + self.t
    }

    /// `R p + t`, its Jacobian with respect to the pose parameters (3×6) and
    /// with respect to `p` (3×3, which is `R`).
    pub fn transform_with_jacobians(
        &self,
        p: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, N_POSE>, Matrix3<f64>) {
        self.transform_with_jacobians_using(&self.rotation_jacobian(), p)
    }

    /// [`Self::transform_with_jacobians`] with the rotation Jacobian of this
    /// pose precomputed by [`Self::rotation_jacobian`].
    pub fn transform_with_jacobians_using(
        &self,
        rotation: &RotationJacobian,
        p: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, N_POSE>, Matrix3<f64>) {
        let (r, dr) = (rotation.r, &rotation.dr);
        let mut j = SMatrix::<f64, 3, N_POSE>::zeros();
        for (i, dri) in dr.iter().enumerate() {
            j.set_column(i, &(dri * p));
        }
        j.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&Matrix3::identity());
        (r * p + self.t, j, r)
    }

    /// The inverse pose: `P_src = Rᵀ (P_dst − t)`.
    pub fn inverse(&self) -> Self {
        let r = self.rotation();
        Self {
            rvec: -self.rvec,
            t: -(r.transpose() * self.t),
        }
    }

    /// Composition `self ∘ other` (apply `other` first): for
    /// `a_from_b.compose(&b_from_c)` the result is `a_from_c`.
    pub fn compose(&self, other: &Self) -> Self {
        let r = self.rotation() * other.rotation();
        Self::from_rotation(&r, self.rotation() * other.t + self.t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the two evaluations meet they must agree to the accuracy of the
    /// closed form there (its cancellation costs about ε/θ² ≈ 3e-14 in `c`, `d`).
    #[test]
    fn a_step_adds_to_rvec_then_t() {
        let pose = Pose::new(
            Vector3::new(0.1, -0.2, 0.3),
            Vector3::new(10.0, 20.0, 500.0),
        );
        let d = [1e-3, 2e-3, -3e-3, 0.5, -0.25, 2.0];
        let stepped = pose.stepped(&d);
        assert_eq!(stepped.rvec, Vector3::new(0.101, -0.198, 0.297));
        assert_eq!(stepped.t, Vector3::new(10.5, 19.75, 502.0));
    }

    #[test]
    fn series_and_closed_form_agree_at_the_switch() {
        for theta in [0.08, 0.1, 0.12] {
            let s = rodrigues_series(theta);
            let c = rodrigues_closed_form(theta);
            for k in 0..4 {
                let rel = (s[k] - c[k]).abs() / c[k].abs();
                assert!(
                    rel < 1e-12,
                    "θ = {theta}, coefficient {k}: {} vs {} (rel {rel:.2e})",
                    s[k],
                    c[k]
                );
            }
        }
    }

    #[test]
    fn rotation_is_exact_for_quarter_turn_about_z() {
        let pose = Pose::new(
            Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
            Vector3::zeros(),
        );
        let p = pose.transform(&Vector3::new(1.0, 0.0, 0.0));
        assert!((p - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn inverse_and_compose_round_trip() {
        let a = Pose::new(
            Vector3::new(0.3, -0.2, 2.9),
            Vector3::new(10.0, -5.0, 900.0),
        );
        let b = Pose::new(
            Vector3::new(-1.0, 0.4, 0.1),
            Vector3::new(-30.0, 60.0, 20.0),
        );
        let p = Vector3::new(12.0, -7.0, 3.0);
        assert!((a.inverse().transform(&a.transform(&p)) - p).norm() < 1e-12);
        assert!((a.compose(&b).transform(&p) - a.transform(&b.transform(&p))).norm() < 1e-12);
        // Logarithm near π goes through a quaternion and stays exact.
        let near_pi = Pose::new(
            Vector3::new(0.0, std::f64::consts::PI - 1e-5, 0.0),
            Vector3::zeros(),
        );
        let back = Pose::from_rotation(&near_pi.rotation(), Vector3::zeros());
        assert!((back.rotation() - near_pi.rotation()).norm() < 1e-12);
    }
}
