//! Template plane ↔ measured point through a [`Model`] chain (docs/model.md §3–4,
//! the paper's (P5), (P15)–(P16) and the template-plane residual of (P29)),
//! with Jacobians with respect to the flat parameter vector, the pose and the
//! point.
//!
//! *Back-projection* (measured → template): the chain gives the ray `(a, b)`;
//! the ray is cut with the template plane `Z_t = 0` of the pose
//! ([`plane_intersection_with_jacobians`]): `∂XY/∂θ = ∂XY/∂(a,b) · ∂(a,b)/∂θ`.
//! The ray parameter `s` at which `P_t = Rᵀ(s n − t)`, `n = (a, b, 1)`, has
//! zero `Z` is `s = (r3·t)/(r3·n)` with `r3` the third column of `R`; then
//! `(X, Y)` are the first two components of `P_t`. `s` is the depth `Zc` of
//! the point, and must be positive. With `w = s n − t` and `q = r3·n`:
//! `∂P_t/∂n = Rᵀ(s I − (s/q) n r3ᵀ)`, `∂P_t/∂t = Rᵀ(n r3ᵀ/q − I)`,
//! `∂P_t/∂v_i = (∂R/∂v_i)ᵀ w + Rᵀ n ∂s/∂v_i` with
//! `∂s/∂v_i = −e3ᵀ(∂R/∂v_i)ᵀ w / q`.
//!
//! *Projection* (template → measured): `P_c = R P_t + t`, `(a, b) = (Xc, Yc)/Zc`,
//! the ideal point `x = f a + γ b + cx`, `y = f b + cy` (P4), and the measured
//! point `m` solving `ideal(m) = x` (Newton). By the implicit function theorem
//! on `ray(m; θ) = n(pose, P_t)`: with `R_m = ∂ray/∂m`,
//! `∂m/∂θ = −R_m⁻¹ ∂ray/∂θ`, `∂m/∂pose = R_m⁻¹ ∂n/∂pose`,
//! `∂m/∂P_t = R_m⁻¹ ∂n/∂P_t`.

use nalgebra::{Matrix2, Matrix2x3, Matrix3, SMatrix, Vector2, Vector3};

use crate::model::{ChainJacobian, Model};
use crate::pose::{Pose, RotationJacobian, N_POSE};
use crate::ModelError;

/// Smallest depth accepted as "in front of the sensor", mm.
pub const MIN_DEPTH_MM: f64 = 1e-9;

/// Smallest `|r3·n|` (cosine-like obliquity of the ray to the plane) accepted.
const MIN_OBLIQUITY: f64 = 1e-12;

/// Jacobians of a point computed through the chain with a pose. The flat
/// parameter columns live in the [`ChainJacobian`] passed along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseJacobians {
    /// With respect to the pose `(rvec, t)` (2×6).
    pub wrt_pose: SMatrix<f64, 2, N_POSE>,
    /// With respect to the input point (measured point for a back-projection,
    /// template `(X, Y)` for a projection) (2×2).
    pub wrt_point: Matrix2<f64>,
}

impl Model {
    /// The template-plane point whose ray passes through `measured`.
    pub fn back_project(
        &self,
        sensor_from_template: &Pose,
        measured: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let rotation = sensor_from_template.rotation();
        self.back_project_using(&rotation, &sensor_from_template.t, measured)
    }

    /// [`Self::back_project`] with the pose's rotation matrix `R` computed
    /// once (for many points of one image).
    pub fn back_project_using(
        &self,
        rotation: &Matrix3<f64>,
        t: &Vector3<f64>,
        measured: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        intersect_template_plane(rotation, t, &self.ray(measured)).map(|r| r.0)
    }

    /// Back-projection with its Jacobians: `jac.wrt_params` becomes
    /// `∂XY/∂θ` (2×P) and `jac.wrt_point` is left as `∂ray/∂m`.
    pub fn back_project_with_jacobians(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        measured: &Vector2<f64>,
        jac: &mut ChainJacobian,
    ) -> Result<(Vector2<f64>, PoseJacobians), ModelError> {
        let ab = self.ray_with_jacobians(measured, jac);
        let (xy, dxy_dab, wrt_pose) =
            plane_intersection_with_jacobians(rotation, &sensor_from_template.t, &ab)?;
        jac.left_multiply(&dxy_dab);
        Ok((
            xy,
            PoseJacobians {
                wrt_pose,
                wrt_point: dxy_dab * jac.wrt_point,
            },
        ))
    }

    /// The ideal (undistorted) point of template point `(X, Y)` in pose
    /// `sensor_from_template`: the pinhole alone.
    pub fn project_ideal(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let p_t = Vector3::new(template_xy.x, template_xy.y, 0.0);
        self.ideal_of_point(&sensor_from_template.transform(&p_t))
    }

    /// The ideal point of a sensor-frame point `P_c` in front of the sensor:
    /// `x = f Xc/Zc + γ Yc/Zc + cx`, `y = f Yc/Zc + cy` (P4).
    pub fn ideal_of_point(&self, p_c: &Vector3<f64>) -> Result<Vector2<f64>, ModelError> {
        Ok(self.ideal_of_ray(&normalised(p_c)?))
    }

    /// [`Self::project`] with the inverse of the distortion stopped at its
    /// tolerance ([`Self::measured_from_ideal_to_tolerance`]): the
    /// projection psdcal's simulators draw their data with.
    pub fn project_to_tolerance(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let ideal = self.project_ideal(sensor_from_template, template_xy)?;
        self.measured_from_ideal_to_tolerance(&ideal)
    }

    /// The measured point of template point `(X, Y)` in pose
    /// `sensor_from_template`.
    pub fn project(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        self.project_near(sensor_from_template, template_xy, None)
    }

    /// [`Self::project`] with the inversion of the distortion started at
    /// `near` when given (the measured point the prediction is compared
    /// with: [`Self::measured_from_ideal_near`]).
    pub fn project_near(
        &self,
        sensor_from_template: &Pose,
        template_xy: &Vector2<f64>,
        near: Option<&Vector2<f64>>,
    ) -> Result<Vector2<f64>, ModelError> {
        let p_c = sensor_from_template.transform(&Vector3::new(template_xy.x, template_xy.y, 0.0));
        let ab = normalised(&p_c)?;
        let ideal = self.ideal_of_ray(&ab);
        self.measured_from_ideal_near(&ideal, near.unwrap_or(&ideal))
    }

    /// Projection with its Jacobians: `jac.wrt_params` becomes `∂m/∂θ` (2×P).
    pub fn project_with_jacobians(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        template_xy: &Vector2<f64>,
        jac: &mut ChainJacobian,
    ) -> Result<(Vector2<f64>, PoseJacobians), ModelError> {
        self.project_with_jacobians_near(sensor_from_template, rotation, template_xy, None, jac)
    }

    /// [`Self::project_with_jacobians`] with the inversion started at
    /// `near` when given ([`Self::project_near`]).
    pub fn project_with_jacobians_near(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        template_xy: &Vector2<f64>,
        near: Option<&Vector2<f64>>,
        jac: &mut ChainJacobian,
    ) -> Result<(Vector2<f64>, PoseJacobians), ModelError> {
        let p_t = Vector3::new(template_xy.x, template_xy.y, 0.0);
        let (p_c, dpc_dpose, rot) =
            sensor_from_template.transform_with_jacobians_using(rotation, &p_t);
        let ab = normalised(&p_c)?;
        let ideal = self.ideal_of_ray(&ab);
        let measured = self.measured_from_ideal_near(&ideal, near.unwrap_or(&ideal))?;
        self.ray_with_jacobians(&measured, jac);
        let r_m = jac.wrt_point;
        let inv = r_m.try_inverse().ok_or(ModelError::SingularDistortion {
            x: measured.x,
            y: measured.y,
            det: r_m.determinant(),
        })?;
        jac.left_multiply(&(-inv));
        let inv_z = 1.0 / p_c.z;
        let dn_dpc = Matrix2x3::new(inv_z, 0.0, -ab.x * inv_z, 0.0, inv_z, -ab.y * inv_z);
        Ok((
            measured,
            PoseJacobians {
                wrt_pose: inv * dn_dpc * dpc_dpose,
                wrt_point: inv * dn_dpc * rot.fixed_view::<3, 2>(0, 0),
            },
        ))
    }
}

/// Jacobians of a 3-D point projected through the chain with a pose (a
/// surveyed, non-coplanar template, docs/model.md §8.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointJacobians {
    /// With respect to the pose `(rvec, t)` (2×6).
    pub wrt_pose: SMatrix<f64, 2, N_POSE>,
    /// With respect to the point `(X, Y, Z)` in the template (room) frame (2×3).
    pub wrt_point: Matrix2x3<f64>,
}

impl Model {
    /// The measured point of a 3-D template point `(X, Y, Z)` (a surveyed
    /// emitter) in pose `sensor_from_template`.
    pub fn project_point(
        &self,
        sensor_from_template: &Pose,
        point: &Vector3<f64>,
    ) -> Result<Vector2<f64>, ModelError> {
        let ab = normalised(&sensor_from_template.transform(point))?;
        self.measured_from_ideal(&self.ideal_of_ray(&ab))
    }

    /// [`Self::project_point`] with its Jacobians: `jac.wrt_params` becomes
    /// `∂m/∂θ` (2×P); the pose and point Jacobians as in
    /// [`Self::project_with_jacobians`], with the point's third column.
    pub fn project_point_with_jacobians(
        &self,
        sensor_from_template: &Pose,
        rotation: &RotationJacobian,
        point: &Vector3<f64>,
        jac: &mut ChainJacobian,
    ) -> Result<(Vector2<f64>, PointJacobians), ModelError> {
        let (p_c, dpc_dpose, rot) =
            sensor_from_template.transform_with_jacobians_using(rotation, point);
        let ab = normalised(&p_c)?;
        let measured = self.measured_from_ideal(&self.ideal_of_ray(&ab))?;
        self.ray_with_jacobians(&measured, jac);
        let r_m = jac.wrt_point;
        let inv = r_m.try_inverse().ok_or(ModelError::SingularDistortion {
            x: measured.x,
            y: measured.y,
            det: r_m.determinant(),
        })?;
        jac.left_multiply(&(-inv));
        let inv_z = 1.0 / p_c.z;
        let dn_dpc = Matrix2x3::new(inv_z, 0.0, -ab.x * inv_z, 0.0, inv_z, -ab.y * inv_z);
        let m = inv * dn_dpc;
        Ok((
            measured,
            PointJacobians {
                wrt_pose: m * dpc_dpose,
                wrt_point: m * rot,
            },
        ))
    }
}

/// `(Xc/Zc, Yc/Zc)` of a point in front of the sensor.
fn normalised(p_c: &Vector3<f64>) -> Result<Vector2<f64>, ModelError> {
    if p_c.z.is_nan() || p_c.z <= MIN_DEPTH_MM {
        return Err(ModelError::BehindSensor { zc: p_c.z });
    }
    Ok(Vector2::new(p_c.x / p_c.z, p_c.y / p_c.z))
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
