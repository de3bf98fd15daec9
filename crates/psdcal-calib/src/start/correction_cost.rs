//! The form every cost of the preliminary correction takes ([`crate::preliminary`]):
//! a scale-free least-squares cost in the two dimensionless parameters
//! `u = (k1 R², k2 R⁴)` of `p = c + d (1 + u1 ρ + u2 ρ²)`, `d = m − c`,
//! `ρ = ‖d‖²/R²`, with a forward-difference Jacobian unless the cost has an
//! analytic one (line straightness, [`crate::straightness`]).

use nalgebra::{DMatrix, DVector};

use crate::CalibError;

/// A scale-free least-squares cost in the two dimensionless parameters
/// `u = (k1 R², k2 R⁴)`.
pub(crate) trait TwoParameterCost {
    /// The residual vector (fixed length for a given problem).
    fn residuals(&self, u: [f64; 2]) -> Result<DVector<f64>, CalibError>;

    /// Its Jacobian (n × 2) at `u`, where the residuals are `r`: forward
    /// differences (two more evaluations; a rough correction does not need
    /// the last digits) unless overridden.
    fn jacobian(&self, u: [f64; 2], r: &DVector<f64>) -> Result<DMatrix<f64>, CalibError> {
        const H: f64 = 1e-7;
        let mut cols = Vec::with_capacity(2);
        for k in 0..2 {
            let mut up = u;
            up[k] += H;
            cols.push((self.residuals(up)? - r) / H);
        }
        Ok(DMatrix::from_columns(&cols))
    }

    /// Residual evaluations one [`Self::jacobian`] costs.
    fn jacobian_evaluations(&self) -> usize {
        2
    }
}
