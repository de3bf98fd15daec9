//! A Gaussian prior on some of the model's parameters as one more residual
//! group of the refinement (docs/model.md §8.3: a PSD map refined with its
//! scan as the prior).
//!
//! With the prior mean `μ` and covariance `Σ` of the parameters `m` (say a
//! map's coefficients fitted to its scan), the prior residuals are
//!
//! ```text
//! r_p = s · L (m − μ),    LᵀL = Σ⁻¹,    ∂r_p/∂m = s L
//! ```
//!
//! with `Σ = C Cᵀ` (Cholesky, `C` lower triangular) and `L = C⁻¹` (lower
//! triangular too). `s` puts them on the data's scale: the refinement's
//! data cost `Σ ‖r‖²` has a variance `s²` per coordinate (the cost units:
//! mm² on the template plane, 1 for whitened residuals), so
//! `cost / s² = Σ ‖r‖² / s² + (m − μ)ᵀ Σ⁻¹ (m − μ)` is the negative log
//! posterior (up to constants) and its information `JᵀJ / s²` the joint
//! information of the data and the prior. The calibration sets `s² =
//! cost / dof` of the fit with `m` held at `μ` ([`mod@crate::calibrate`]).
//!
//! The prior's own randomness (`μ − m* ~ N(0, Σ)`) enters the estimate's
//! covariance through the gradient `s² Σ⁻¹ (m − μ)`: its variance is
//! `s⁴ Σ⁻¹` ([`Prior::meat`], used by [`mod@crate::covariance`]).

use nalgebra::{DMatrix, DVector};
use psdcal_model::{Model, ParameterCovariance};

use crate::CalibError;

/// A Gaussian prior on named parameters (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Prior {
    names: Vec<String>,
    mean: DVector<f64>,
    /// `L = C⁻¹`, lower triangular, `LᵀL = Σ⁻¹`.
    whitening: DMatrix<f64>,
    scale: f64,
}

impl Prior {
    /// The prior `N(mean, covariance)` over `covariance`'s names, its
    /// residuals scaled by `scale` (> 0); a covariance that is not positive
    /// definite is refused.
    pub fn new(
        covariance: &ParameterCovariance,
        mean: &[f64],
        scale: f64,
    ) -> Result<Self, CalibError> {
        let n = covariance.len();
        if mean.len() != n {
            return Err(CalibError::InvalidInput {
                reason: format!("a prior of {n} parameters given {} values", mean.len()),
            });
        }
        if !(scale.is_finite() && scale > 0.0) || mean.iter().any(|v| !v.is_finite()) {
            return Err(CalibError::InvalidInput {
                reason: format!("a prior needs finite values and a positive scale (got {scale})"),
            });
        }
        let c = covariance
            .matrix()
            .clone()
            .cholesky()
            .ok_or_else(|| CalibError::InvalidInput {
                reason: format!(
                    "the prior covariance of {} … is not positive definite",
                    covariance.names().first().map_or("", String::as_str)
                ),
            })?
            .l();
        let whitening = c
            .solve_lower_triangular(&DMatrix::identity(n, n))
            .ok_or_else(|| CalibError::Numerical {
                stage: "prior",
                reason: "the prior covariance's factor is singular".into(),
            })?;
        Ok(Self {
            names: covariance.names().to_vec(),
            mean: DVector::from_column_slice(mean),
            whitening,
            scale,
        })
    }

    /// The parameters' names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The prior mean.
    pub fn mean(&self) -> &DVector<f64> {
        &self.mean
    }

    /// The residuals' scale `s`.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Number of prior residuals (one per parameter).
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether the prior has no parameter.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// `∂r_p/∂m = s L` (rows the residuals, columns the parameters in
    /// [`Self::names`] order).
    pub fn jacobian(&self) -> DMatrix<f64> {
        &self.whitening * self.scale
    }

    /// `r_p = s L (m − μ)` of the parameter values `m` (in names order).
    pub fn residuals(&self, values: &DVector<f64>) -> DVector<f64> {
        &self.whitening * (values - &self.mean) * self.scale
    }

    /// The values of the prior's parameters in `model` (an unknown name is
    /// an error).
    pub fn values(&self, model: &Model) -> Result<DVector<f64>, CalibError> {
        let mut v = DVector::zeros(self.len());
        for (slot, name) in v.iter_mut().zip(&self.names) {
            *slot = model.get(name).ok_or_else(|| CalibError::InvalidInput {
                reason: format!("the prior's parameter '{name}' is not in the model"),
            })?;
        }
        Ok(v)
    }

    /// The model columns of the prior's parameters.
    pub fn columns(&self, model: &Model) -> Result<Vec<usize>, CalibError> {
        self.names
            .iter()
            .map(|name| {
                model.index(name).ok_or_else(|| CalibError::InvalidInput {
                    reason: format!("the prior's parameter '{name}' is not in the model"),
                })
            })
            .collect()
    }

    /// The prior's information in cost units, `s² Σ⁻¹ = (sL)ᵀ(sL)`.
    pub fn information(&self) -> DMatrix<f64> {
        let j = self.jacobian();
        j.transpose() * j
    }

    /// The variance of the prior's gradient, `s⁴ Σ⁻¹`: what its randomness
    /// adds to the middle of the estimate's sandwich covariance.
    pub fn meat(&self) -> DMatrix<f64> {
        self.information() * self.scale.powi(2)
    }
}
