//! One penalised least-squares solve of a map's coefficients
//! (docs/model.md §8.3):
//!
//! ```text
//! M = AᵀWA + λP,   λ = κ tr(AᵀWA)/tr(P)   (0 without a penalty)
//! a_x = M⁻¹ AᵀW d_x,   a_y = M⁻¹ AᵀW d_y
//! ```
//!
//! by Cholesky; `M` counts as singular when a pivot falls below 1e-12 of
//! the largest diagonal entry (the scan does not determine the model).

use nalgebra::{DMatrix, DVector, Vector2};
use psdcal_model::stages::PsdMap;

use crate::error::PsdMapError;
use crate::normal::NormalEquations;
use crate::penalty::PENALTY_KAPPA;

/// Relative pivot below which `M` is singular.
const SINGULAR_PIVOT: f64 = 1e-12;

/// The coefficients of one solve and `M⁻¹`.
#[derive(Debug, Clone)]
pub struct Solution {
    /// x coefficients.
    pub ax: DVector<f64>,
    /// y coefficients.
    pub ay: DVector<f64>,
    /// `M⁻¹`.
    pub inverse: DMatrix<f64>,
}

impl Solution {
    /// The stage's block `(a_x, a_y)`.
    pub fn block(&self) -> Vec<f64> {
        self.ax.iter().chain(self.ay.iter()).copied().collect()
    }
}

/// Solves the penalised normal equations (`penalty`: `P`, zero for none).
pub fn solve(
    eq: &NormalEquations,
    penalty: &DMatrix<f64>,
    label: &str,
) -> Result<Solution, PsdMapError> {
    let trace_p = penalty.trace();
    let lambda = if trace_p > 0.0 {
        PENALTY_KAPPA * eq.ata.trace() / trace_p
    } else {
        0.0
    };
    let m = &eq.ata + penalty * lambda;
    let largest = m.diagonal().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let singular = || PsdMapError::Singular {
        model: label.to_string(),
    };
    if !(largest.is_finite() && largest > 0.0) {
        return Err(singular());
    }
    let chol = m.clone().cholesky().ok_or_else(singular)?;
    let l = chol.l_dirty();
    let smallest = (0..l.nrows())
        .map(|i| l[(i, i)] * l[(i, i)])
        .fold(f64::INFINITY, f64::min);
    if smallest < SINGULAR_PIVOT * largest {
        return Err(singular());
    }
    Ok(Solution {
        ax: chol.solve(&eq.atx),
        ay: chol.solve(&eq.aty),
        inverse: chol.inverse(),
    })
}

/// Residuals `d_i − map(m_i)` (the stage position minus the corrected point).
pub fn residuals(
    map: &PsdMap,
    block: &[f64],
    measured: &[Vector2<f64>],
    displacement: &[Vector2<f64>],
) -> Vec<Vector2<f64>> {
    measured
        .iter()
        .zip(displacement)
        .map(|(m, d)| d - map.displacement(block, m))
        .collect()
}
