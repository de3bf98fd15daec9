//! The full sensor map between the template plane and measured impact points
//! (docs/model.md §3–4, the paper's (P5) with distortion (P15)–(P16), and the
//! template-plane residual of (P29)).
//!
//! *Projection* (template → measured): `P_c = R P_t + t` with
//! `P_t = (X, Y, 0)`; the pinhole gives the ideal point `p`; the measured
//! point `m` solves `undistort(m) = p` (Newton, [`SensorModel::distort`]).
//! Its Jacobians follow from the implicit function theorem:
//! `∂m/∂θ = U_m⁻¹ (∂p/∂θ − ∂U/∂θ)`.
//!
//! *Back-projection* (measured → template plane): `p = undistort(m)`, the
//! normalised ray `n = (a, b, 1)`, and the ray parameter `s` at which
//! `P_t = Rᵀ(s n − t)` has zero `Z`: `s = (r3·t)/(r3·n)` with `r3` the third
//! column of `R`; then `(X, Y)` are the first two components of `P_t`.
//! `s` is the depth `Zc` of the point, and must be positive.
//! Jacobians: with `w = s n − t` and `q = r3·n`,
//! `∂P_t/∂n = Rᵀ(s I − (s/q) n r3ᵀ)`, `∂P_t/∂t = Rᵀ(n r3ᵀ/q − I)`,
//! `∂P_t/∂v_i = (∂R/∂v_i)ᵀ w + Rᵀ n ∂s/∂v_i` with
//! `∂s/∂v_i = −e3ᵀ(∂R/∂v_i)ᵀ w / q`.

use nalgebra::{Matrix2, Matrix3, SMatrix, Vector2, Vector3};

use crate::params::{SensorModel, N_PARAMS};
use crate::pose::{Pose, RotationJacobian, N_POSE};
use crate::ModelError;

/// Jacobians of a projected (measured or ideal) point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProjectionJacobians {
    /// With respect to the model parameters, [`crate::Param::ALL`] order (2×11).
    pub wrt_model: SMatrix<f64, 2, N_PARAMS>,
    /// With respect to the pose `(rvec, t)` (2×6).
    pub wrt_pose: SMatrix<f64, 2, N_POSE>,
    /// With respect to the template point `(X, Y)` (2×2).
    pub wrt_template: Matrix2<f64>,
}

/// Jacobians of a back-projected template-plane point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackProjectionJacobians {
    /// With respect to the model parameters (2×11).
    pub wrt_model: SMatrix<f64, 2, N_PARAMS>,
    /// With respect to the pose `(rvec, t)` (2×6).
    pub wrt_pose: SMatrix<f64, 2, N_POSE>,
    /// With respect to the measured point (2×2).
    pub wrt_measured: Matrix2<f64>,
}

/// Smallest `|r3·n|` (cosine-like obliquity of the ray to the plane) accepted.
const MIN_OBLIQUITY: f64 = 1e-12;

impl SensorModel {
    /// Ideal (undistorted) image point of a template point.
    pub fn project_ideal(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let p_t = Vector3::new(template_xy.x, template_xy.y, 0.0);
        self.pinhole_project(&sensor_from_template.transform(&p_t))
    }

    /// Ideal image point of a template point with its Jacobians.
    pub fn project_ideal_with_jacobians(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, ProjectionJacobians), ModelError> {
        self.project_ideal_with_jacobians_using(
            sensor_from_template,
            &sensor_from_template.rotation_jacobian(),
            template_xy,
        )
    }

    /// [`Self::project_ideal_with_jacobians`] with the pose's rotation
    /// Jacobian precomputed ([`Pose::rotation_jacobian`]).
    pub fn project_ideal_with_jacobians_using(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        template_xy: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, ProjectionJacobians), ModelError> {
        let p_t = Vector3::new(template_xy.x, template_xy.y, 0.0);
        let (p_c, dpc_dpose, rot) =
            sensor_from_template.transform_with_jacobians_using(rotation, &p_t);
        let (ideal, dp_dpc, wrt_model) = self.pinhole_project_with_jacobians(&p_c)?;
        Ok((
            ideal,
            ProjectionJacobians {
                wrt_model,
                wrt_pose: dp_dpc * dpc_dpose,
                wrt_template: dp_dpc * rot.fixed_view::<3, 2>(0, 0),
            },
        ))
    }

    /// Measured impact point of a template point seen in pose
    /// `sensor_from_template`.
    pub fn project(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        self.distort(&self.project_ideal(sensor_from_template, template_xy)?)
    }

    /// Measured impact point of a template point with its Jacobians.
    pub fn project_with_jacobians(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, ProjectionJacobians), ModelError> {
        self.project_with_jacobians_using(
            sensor_from_template,
            &sensor_from_template.rotation_jacobian(),
            template_xy,
        )
    }

    /// [`Self::project_with_jacobians`] with the pose's rotation Jacobian
    /// precomputed ([`Pose::rotation_jacobian`]).
    pub fn project_with_jacobians_using(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        template_xy: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, ProjectionJacobians), ModelError> {
        let (ideal, jp) =
            self.project_ideal_with_jacobians_using(sensor_from_template, rotation, template_xy)?;
        let measured = self.distort(&ideal)?;
        let ju = self.undistort_with_jacobians(&measured);
        let inv = ju
            .wrt_point
            .try_inverse()
            .ok_or(ModelError::SingularDistortion {
                x: measured.x,
                y: measured.y,
                det: ju.wrt_point.determinant(),
            })?;
        Ok((
            measured,
            ProjectionJacobians {
                wrt_model: inv * (jp.wrt_model - ju.wrt_model),
                wrt_pose: inv * jp.wrt_pose,
                wrt_template: inv * jp.wrt_template,
            },
        ))
    }

    /// The template-plane point `(X, Y)` whose ray passes through a measured
    /// impact point, for the template in pose `sensor_from_template`.
    pub fn back_project(
        &self,
        sensor_from_template: &Pose,
        measured: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let n = self.normalize(&self.undistort(measured));
        let rot = sensor_from_template.rotation();
        let (xy, _, _) = intersect_template_plane(&rot, &sensor_from_template.t, &n)?;
        Ok(xy)
    }

    /// Back-projection with its Jacobians.
    pub fn back_project_with_jacobians(
        &self,
        sensor_from_template: &Pose,
        measured: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, BackProjectionJacobians), ModelError> {
        self.back_project_with_jacobians_using(
            sensor_from_template,
            &sensor_from_template.rotation_jacobian(),
            measured,
        )
    }

    /// [`Self::back_project_with_jacobians`] with the pose's rotation
    /// Jacobian precomputed ([`Pose::rotation_jacobian`]).
    pub fn back_project_with_jacobians_using(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        measured: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, BackProjectionJacobians), ModelError> {
        let ju = self.undistort_with_jacobians(measured);
        let (ab, dn_dideal, dn_dmodel_direct) = self.normalize_with_jacobians(&ju.ideal);
        let (xy, dxy_dab, wrt_pose) =
            plane_intersection_with_jacobians(rotation, &sensor_from_template.t, &ab)?;
        let dn_dmodel = dn_dideal * ju.wrt_model + dn_dmodel_direct;
        Ok((
            xy,
            BackProjectionJacobians {
                wrt_model: dxy_dab * dn_dmodel,
                wrt_pose,
                wrt_measured: dxy_dab * dn_dideal * ju.wrt_point,
            },
        ))
    }
}

/// A template-plane point with `∂(X, Y)/∂(a, b)` and `∂(X, Y)/∂(rvec, t)`.
pub type PlaneIntersection = (Vector2<f64>, Matrix2<f64>, SMatrix<f64, 2, N_POSE>);

/// The template-plane point `(X, Y)` hit by the normalised ray `(a, b, 1)`
/// for the pose `(R, t)` (its rotation Jacobian precomputed), with
/// `∂(X, Y)/∂(a, b)` (2×2) and `∂(X, Y)/∂(rvec, t)` (2×6) (module
/// documentation).
pub fn plane_intersection_with_jacobians(
    rotation: &RotationJacobian,
    t: &Vector3<f64>,
    ab: &Vector2<f64>,
) -> Result<PlaneIntersection, ModelError> {
    let (rot, drot) = (rotation.r, rotation.dr);
    let (xy, s, q) = intersect_template_plane(&rot, t, ab)?;
    let n = Vector3::new(ab.x, ab.y, 1.0);
    let r3 = rot.column(2).into_owned();
    let rt = rot.transpose();
    let w = n * s - t;
    // ∂P_t/∂n restricted to (a, b), and rows X, Y.
    let dp_dn: Matrix3<f64> = rt * (Matrix3::identity() * s - n * r3.transpose() * (s / q));
    let dxy_dab: Matrix2<f64> = dp_dn.fixed_view::<2, 2>(0, 0).into_owned();
    let dp_dt: Matrix3<f64> = rt * (n * r3.transpose() / q - Matrix3::identity());
    let mut wrt_pose = SMatrix::<f64, 2, N_POSE>::zeros();
    for (i, dri) in drot.iter().enumerate() {
        let drt_w = dri.transpose() * w;
        let ds = -drt_w.z / q;
        let dp = drt_w + rt * n * ds;
        wrt_pose.set_column(i, &dp.fixed_rows::<2>(0));
    }
    wrt_pose
        .fixed_view_mut::<2, 3>(0, 3)
        .copy_from(&dp_dt.fixed_view::<2, 3>(0, 0));
    Ok((xy, dxy_dab, wrt_pose))
}

/// Intersects the ray `s (a, b, 1)` (sensor frame) with the template plane
/// `Z_t = 0` of pose `(rot, t)`; returns the template `(X, Y)`, the ray
/// parameter `s` (the depth) and `q = r3·n`.
pub(crate) fn intersect_template_plane(
    rot: &Matrix3<f64>,
    t: &Vector3<f64>,
    ab: &Vector2<f64>,
) -> Result<(Vector2<f64>, f64, f64), ModelError> {
    let n = Vector3::new(ab.x, ab.y, 1.0);
    let r3 = rot.column(2);
    let q = r3.dot(&n);
    let s = r3.dot(t) / q;
    let grazing = q.is_nan() || q.abs() <= MIN_OBLIQUITY * n.norm();
    if grazing || s.is_nan() || s <= 0.0 || !s.is_finite() {
        return Err(ModelError::RayMissesPlane { s });
    }
    let p_t = rot.transpose() * (n * s - t);
    Ok((Vector2::new(p_t.x, p_t.y), s, q))
}
