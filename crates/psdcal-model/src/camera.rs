//! The pinhole (docs/model.md §3, the paper's (P4)–(P6)) with one focal length and
//! optional skew.
//!
//! A sensor-frame point `P_c = (Xc, Yc, Zc)`, `Zc > 0`, has the ideal image
//! point
//!
//! ```text
//! x = f · Xc/Zc + γ · Yc/Zc + cx
//! y = f · Yc/Zc + cy
//! ```
//!
//! and, conversely, an ideal point `(x, y)` has the *normalised ray*
//! `(a, b, 1)` with `b = (y − cy)/f`, `a = (x − cx − γ b)/f`, i.e. the
//! direction `(x − cx − γ(y − cy)/f, y − cy, f)` of docs/model.md §4.6.

use nalgebra::{Matrix2, Matrix2x3, SMatrix, Unit, Vector2, Vector3};

use crate::params::{Param, SensorModel, N_PARAMS};
use crate::stages::pinhole::PinholeIntrinsics;
use crate::stages::Pinhole;
use crate::ModelError;

/// An ideal point with its Jacobians with respect to the sensor-frame point
/// (2×3) and to the model parameters (2×11).
pub type PinholeWithJacobians = (Vector2<f64>, Matrix2x3<f64>, SMatrix<f64, 2, N_PARAMS>);

/// Smallest depth accepted as "in front of the sensor", mm.
pub const MIN_DEPTH_MM: f64 = 1e-9;

impl SensorModel {
    /// Ideal image point of a sensor-frame point.
    pub fn pinhole_project(&self, p_c: &Vector3<f64>) -> Result<Vector2<f64>, ModelError> {
        if p_c.z.is_nan() || p_c.z <= MIN_DEPTH_MM {
            return Err(ModelError::BehindSensor { zc: p_c.z });
        }
        let k = &self.intrinsics;
        let (a, b) = (p_c.x / p_c.z, p_c.y / p_c.z);
        Ok(Vector2::new(k.f * a + k.skew * b + k.cx, k.f * b + k.cy))
    }

    /// Ideal image point, its Jacobian with respect to the sensor-frame point
    /// (2×3) and to the model parameters (2×11).
    pub fn pinhole_project_with_jacobians(
        &self,
        p_c: &Vector3<f64>,
    ) -> Result<PinholeWithJacobians, ModelError> {
        let ideal = self.pinhole_project(p_c)?;
        let k = &self.intrinsics;
        let inv_z = 1.0 / p_c.z;
        let (a, b) = (p_c.x * inv_z, p_c.y * inv_z);
        // ∂(x, y)/∂(a, b) · ∂(a, b)/∂P_c
        let dab = Matrix2x3::new(inv_z, 0.0, -a * inv_z, 0.0, inv_z, -b * inv_z);
        let dxy_dab = Matrix2::new(k.f, k.skew, 0.0, k.f);
        let mut wrt_model = SMatrix::<f64, 2, N_PARAMS>::zeros();
        wrt_model.set_column(Param::F.index(), &Vector2::new(a, b));
        wrt_model.set_column(Param::Cx.index(), &Vector2::new(1.0, 0.0));
        wrt_model.set_column(Param::Cy.index(), &Vector2::new(0.0, 1.0));
        wrt_model.set_column(Param::Skew.index(), &Vector2::new(b, 0.0));
        Ok((ideal, dxy_dab * dab, wrt_model))
    }

    /// The pinhole stage's intrinsics of this model.
    pub fn pinhole_intrinsics(&self) -> PinholeIntrinsics {
        let k = &self.intrinsics;
        PinholeIntrinsics {
            f: k.f,
            c: Vector2::new(k.cx, k.cy),
            skew: k.skew,
        }
    }

    /// Normalised ray coordinates `(a, b)` of an ideal point (ray `(a, b, 1)`):
    /// the pinhole stage ([`crate::stages::Pinhole`]).
    pub fn normalize(&self, ideal: &Vector2<f64>) -> Vector2<f64> {
        Pinhole::eval(&self.pinhole_intrinsics(), ideal, None)
    }

    /// Normalised ray coordinates with their Jacobians with respect to the
    /// ideal point (2×2) and, holding the ideal point fixed, to the model
    /// parameters (2×11).
    pub fn normalize_with_jacobians(
        &self,
        ideal: &Vector2<f64>,
    ) -> (Vector2<f64>, Matrix2<f64>, SMatrix<f64, 2, N_PARAMS>) {
        let (mut wrt_point, mut block) = (Matrix2::zeros(), [0.0; 8]);
        let ab = Pinhole::eval(
            &self.pinhole_intrinsics(),
            ideal,
            Some((&mut wrt_point, &mut block)),
        );
        let mut wrt_model = SMatrix::<f64, 2, N_PARAMS>::zeros();
        for (k, p) in [Param::F, Param::Cx, Param::Cy, Param::Skew]
            .iter()
            .enumerate()
        {
            wrt_model.set_column(p.index(), &Vector2::new(block[2 * k], block[2 * k + 1]));
        }
        (ab, wrt_point, wrt_model)
    }

    /// Unit direction, in the sensor frame, of the ray through an ideal point.
    pub fn ray_direction(&self, ideal: &Vector2<f64>) -> Unit<Vector3<f64>> {
        let ab = self.normalize(ideal);
        Unit::new_normalize(Vector3::new(ab.x, ab.y, 1.0))
    }
}
