//! The model as a chain of stages (docs/model.md §8).
//!
//! The map from a measured impact point to the normalised ray is an ordered
//! chain `p₀ = m → p₁ = s₁(p₀; θ₁) → … → (a, b) = s_K(p_{K−1}; θ_K)`: the PSD's
//! own distortion (P14)–(P16), the lens (P7)–(P13), the pinhole (P4) read
//! backwards. Each stage is a 2-D map with a parameter block `θ_k` of any
//! size (two coefficients or hundreds), named, with units; it evaluates its
//! output and, when asked, `∂p_k/∂p_{k−1}` (2×2) and `∂p_k/∂θ_k` (2×n) in the
//! same pass, so the arithmetic exists once.
//!
//! Parameters are identified by name. Two stages that name the same parameter
//! share it: the lens's distortion centre and the pinhole's principal point
//! are both the optical centre `cx, cy` (docs/model.md §2–3).
//!
//! Conventions of the chain, checked by [`crate::Model`]: the first stage takes
//! the measured point (sensor frame, mm); the last stage is the pinhole and
//! returns the normalised ray `(a, b)`; its input is the *ideal point*.
//!
//! Adding a model is one file implementing [`Stage`] (with
//! [`Stage::example_parameters`]) plus one entry in the shared stage suite
//! (`tests/stages.rs`), which checks every stage's Jacobians against finite
//! differences and the chain's round trip.

use std::fmt;

use nalgebra::{Matrix2, Vector2};

use crate::ModelError;

/// A parameter of a stage: its name (shared across stages), unit and the
/// value it takes when nothing is known (usually 0).
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterInfo {
    /// Name in files, on the command line and in covariance rows.
    pub name: String,
    /// Unit, for reports (`mm`, `mm^-2`, `1`).
    pub unit: String,
    /// Neutral value (the stage is the identity, or the nominal model).
    pub neutral: f64,
    /// Scale of a typical value, for finite differences and conditioning.
    pub scale: f64,
}

impl ParameterInfo {
    /// A parameter description.
    pub fn new(name: impl Into<String>, unit: impl Into<String>, neutral: f64, scale: f64) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
            neutral,
            scale,
        }
    }
}

/// Where [`Stage::apply`] writes its Jacobians.
#[derive(Debug)]
pub struct StageJacobian<'a> {
    /// `∂output/∂input` (2×2).
    pub wrt_input: &'a mut Matrix2<f64>,
    /// `∂output/∂θ` (2×n), column-major: column `k` is
    /// `[wrt_params[2k], wrt_params[2k + 1]]`.
    pub wrt_params: &'a mut [f64],
}

/// One stage of the measured → ray chain.
pub trait Stage: Send + Sync + fmt::Debug {
    /// Stable identifier of the stage kind (`psd_radial`, `lens`, `pinhole`, …),
    /// as written in calibration.json.
    fn kind(&self) -> &str;

    /// The parameter block, in the order of `params` in [`Stage::apply`].
    fn parameters(&self) -> &[ParameterInfo];

    /// Evaluates the stage at `input` with parameters `params`
    /// (`params.len() == self.parameters().len()`); with `jacobian`, also
    /// writes `∂output/∂input` and `∂output/∂θ`.
    fn apply(
        &self,
        params: &[f64],
        input: &Vector2<f64>,
        jacobian: Option<StageJacobian<'_>>,
    ) -> Vector2<f64>;

    /// Checks a parameter block (finite values and the stage's own domain).
    fn validate(&self, params: &[f64]) -> Result<(), ModelError> {
        check_finite(self.parameters(), params)
    }

    /// Whether the stage is defined at `input` (its own domain: a map fitted
    /// to a scan is known only on the scan's hull, docs/model.md §8.3); a
    /// point whose input is outside is outside the model's valid region.
    /// Everywhere by default.
    fn contains_input(&self, _input: &Vector2<f64>) -> bool {
        true
    }

    /// Whether [`Stage::contains_input`] can be false somewhere.
    fn has_domain(&self) -> bool {
        false
    }

    /// The stage's domain as a convex polygon in its input coordinates, when
    /// it is one ([`Stage::contains_input`] is then exactly
    /// [`ConvexHull::contains`](crate::ConvexHull::contains)); `None`
    /// everywhere else.
    fn domain(&self) -> Option<&crate::hull::ConvexHull> {
        None
    }

    /// Example parameter blocks on which the shared suite checks the stage:
    /// realistic values and harder ones, each a valid model over the
    /// 9 mm × 9 mm active area.
    fn example_parameters(&self) -> Vec<Vec<f64>>;

    /// Structure of the stage that is not a parameter (a grid, an order),
    /// as JSON for calibration files; `null` for the fixed-form stages.
    fn configuration(&self) -> serde_json::Value {
        serde_json::Value::Null
    }

    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn Stage>;
}

impl Clone for Box<dyn Stage> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// Writes column `k` of a 2×n column-major Jacobian.
#[inline]
pub fn set_column(jac: &mut [f64], k: usize, column: Vector2<f64>) {
    jac[2 * k] = column.x;
    jac[2 * k + 1] = column.y;
}

/// `Ok` when every value of `params` is finite; otherwise the first
/// non-finite one, named by `parameters` (every stage's first check).
pub fn check_finite(parameters: &[ParameterInfo], params: &[f64]) -> Result<(), ModelError> {
    for (info, v) in parameters.iter().zip(params) {
        if !v.is_finite() {
            return Err(ModelError::InvalidStageParameter {
                name: info.name.clone(),
                value: *v,
                reason: "must be finite",
            });
        }
    }
    Ok(())
}
