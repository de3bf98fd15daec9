//! The pinhole read backwards (docs/model.md §3, the paper's (P4)): an ideal point
//! `(x, y)` has the normalised ray `(a, b, 1)` in the sensor frame with
//!
//! ```text
//! b = (y − cy)/f,   a = (x − cx − γ b)/f
//! ∂(a, b)/∂(x, y) = [[1/f, −γ/f²], [0, 1/f]]
//! ∂b/∂f = −b/f,  ∂a/∂f = −a/f − γ (∂b/∂f)/f,  ∂a/∂cx = −1/f,
//! ∂(a, b)/∂cy = (γ/f², −1/f),  ∂a/∂γ = −b/f
//! ```
//!
//! Parameters `f` (mm), `cx, cy` (mm; shared with the lens), `skew` (`γ`, mm).

use nalgebra::{Matrix2, Vector2};

use crate::stage::{check_finite, set_column, ParameterInfo, Stage, StageJacobian};
use crate::ModelError;

/// Intrinsics of the pinhole stage, in block order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeIntrinsics {
    /// Focal length, mm.
    pub f: f64,
    /// Optical centre, mm.
    pub c: Vector2<f64>,
    /// Skew `γ`, mm.
    pub skew: f64,
}

/// The pinhole: ideal point → normalised ray.
#[derive(Debug, Clone)]
pub struct Pinhole {
    parameters: Vec<ParameterInfo>,
}

impl Pinhole {
    /// The stage (parameters `f, cx, cy, skew`).
    pub fn new() -> Self {
        Self {
            parameters: vec![
                ParameterInfo::new("f", "mm", 8.0, 1.0),
                ParameterInfo::new("cx", "mm", 0.0, 1.0),
                ParameterInfo::new("cy", "mm", 0.0, 1.0),
                ParameterInfo::new("skew", "mm", 0.0, 1e-2),
            ],
        }
    }

    /// The map with its optional Jacobians (`wrt_params` in block order).
    #[inline]
    pub fn eval(
        k: &PinholeIntrinsics,
        ideal: &Vector2<f64>,
        jacobian: Option<(&mut Matrix2<f64>, &mut [f64])>,
    ) -> Vector2<f64> {
        let inv_f = 1.0 / k.f;
        let b = (ideal.y - k.c.y) / k.f;
        let a = (ideal.x - k.c.x - k.skew * b) / k.f;
        if let Some((wrt_input, wrt_params)) = jacobian {
            *wrt_input = Matrix2::new(inv_f, -k.skew * inv_f * inv_f, 0.0, inv_f);
            let db_df = -b * inv_f;
            set_column(
                wrt_params,
                0,
                Vector2::new(-a * inv_f - k.skew * inv_f * db_df, db_df),
            );
            set_column(wrt_params, 1, Vector2::new(-inv_f, 0.0));
            set_column(wrt_params, 2, Vector2::new(k.skew * inv_f * inv_f, -inv_f));
            set_column(wrt_params, 3, Vector2::new(-b * inv_f, 0.0));
        }
        Vector2::new(a, b)
    }
}

impl Default for Pinhole {
    fn default() -> Self {
        Self::new()
    }
}

impl Stage for Pinhole {
    fn kind(&self) -> &str {
        "pinhole"
    }

    fn parameters(&self) -> &[ParameterInfo] {
        &self.parameters
    }

    fn apply(
        &self,
        params: &[f64],
        input: &Vector2<f64>,
        jacobian: Option<StageJacobian<'_>>,
    ) -> Vector2<f64> {
        let k = PinholeIntrinsics {
            f: params[0],
            c: Vector2::new(params[1], params[2]),
            skew: params[3],
        };
        Self::eval(&k, input, jacobian.map(|j| (j.wrt_input, j.wrt_params)))
    }

    fn validate(&self, params: &[f64]) -> Result<(), ModelError> {
        check_finite(&self.parameters, params)?;
        if params[0] <= 0.0 {
            return Err(ModelError::InvalidStageParameter {
                name: "f".into(),
                value: params[0],
                reason: "the focal length must be positive",
            });
        }
        Ok(())
    }

    fn example_parameters(&self) -> Vec<Vec<f64>> {
        vec![
            vec![8.0, 0.0, 0.0, 0.0],
            vec![25.0, 0.5, -0.7, 0.0],
            vec![8.0, -0.3, 0.4, 0.05],
        ]
    }

    fn clone_box(&self) -> Box<dyn Stage> {
        Box::new(self.clone())
    }
}
