//! The aspect stage (docs/model.md §3.3): the y axis's own scale. A PSD's
//! two axes are read by different electrode pairs through different
//! amplifiers, and their effective lengths differ; a camera's pixels may be
//! non-square. With the aspect `a` the pinhole becomes
//!
//! ```text
//! x = f X/Z + γ Y/Z + cx,   y = fy Y/Z + cy,   fy = f (1 + a)
//! ```
//!
//! written as a stage on the measured side of the lens, so that the lens's
//! radial terms act on square coordinates (as in a camera's normalised
//! ones): it takes a point `(x, y)` to
//!
//! ```text
//! x' = x,   y' = cy + (y − cy)/(1 + a)
//! ∂(x', y')/∂(x, y) = diag(1, 1/(1 + a))
//! ∂y'/∂a = −(y − cy)/(1 + a)²,   ∂y'/∂cy = 1 − 1/(1 + a),   ∂y'/∂cx = 0
//! ```
//!
//! The scale is about the optical centre, so `cy` keeps its meaning (mm on
//! the sensor, shared with the lens and the pinhole). Parameters `a`
//! (dimensionless, `1 + a > 0`; 0: square), `cx`, `cy` (mm; `cx` is named
//! for the shared centre and does not enter the map).

use nalgebra::{Matrix2, Vector2};

use crate::stage::{check_finite, set_column, ParameterInfo, Stage, StageJacobian};
use crate::{Model, ModelError};

/// The y scale of its own: `y' = cy + (y − cy)/(1 + a)`.
#[derive(Debug, Clone)]
pub struct Aspect {
    parameters: Vec<ParameterInfo>,
}

impl Aspect {
    /// The stage's kind in calibration.json.
    pub const KIND: &'static str = "aspect";
    /// The aspect's parameter name.
    pub const NAME: &'static str = "a";

    /// The stage (parameters `a`, `cx`, `cy`).
    pub fn new() -> Self {
        Self {
            parameters: vec![
                ParameterInfo::new(Self::NAME, "1", 0.0, 1e-2),
                ParameterInfo::new("cx", "mm", 0.0, 1.0),
                ParameterInfo::new("cy", "mm", 0.0, 1.0),
            ],
        }
    }

    /// The map with its optional Jacobians (`wrt_params` in block order
    /// `a, cx, cy`).
    #[inline]
    pub fn eval(
        a: f64,
        cy: f64,
        input: &Vector2<f64>,
        jacobian: Option<(&mut Matrix2<f64>, &mut [f64])>,
    ) -> Vector2<f64> {
        let s = 1.0 / (1.0 + a);
        let dy = input.y - cy;
        if let Some((wrt_input, wrt_params)) = jacobian {
            *wrt_input = Matrix2::new(1.0, 0.0, 0.0, s);
            set_column(wrt_params, 0, Vector2::new(0.0, -dy * s * s));
            set_column(wrt_params, 1, Vector2::zeros());
            set_column(wrt_params, 2, Vector2::new(0.0, 1.0 - s));
        }
        Vector2::new(input.x, cy + dy * s)
    }
}

/// `chain` with an aspect stage of value `a` just before its lens stage
/// (first when it has none); `chain` with `a` set when it has one already.
pub fn with_aspect(chain: &Model, a: f64) -> Result<Model, ModelError> {
    let mut with = match chain.index(Aspect::NAME) {
        Some(_) => chain.clone(),
        None => {
            let at = chain
                .stage_kinds()
                .iter()
                .position(|k| *k == "lens")
                .unwrap_or(0);
            chain.with_stage(at, Box::new(Aspect::new()))?
        }
    };
    with.set(Aspect::NAME, a)?;
    Ok(with)
}

impl Default for Aspect {
    fn default() -> Self {
        Self::new()
    }
}

impl Stage for Aspect {
    fn kind(&self) -> &str {
        Self::KIND
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
        Self::eval(
            params[0],
            params[2],
            input,
            jacobian.map(|j| (j.wrt_input, j.wrt_params)),
        )
    }

    fn validate(&self, params: &[f64]) -> Result<(), ModelError> {
        check_finite(&self.parameters, params)?;
        if params[0] <= -1.0 {
            return Err(ModelError::InvalidStageParameter {
                name: Self::NAME.into(),
                value: params[0],
                reason: "the y scale 1 + a must be positive",
            });
        }
        Ok(())
    }

    fn example_parameters(&self) -> Vec<Vec<f64>> {
        vec![
            vec![0.0, 0.0, 0.0],
            vec![2e-3, 0.5, -0.7],
            vec![-0.5, -0.3, 0.4],
        ]
    }

    fn clone_box(&self) -> Box<dyn Stage> {
        Box::new(self.clone())
    }
}
