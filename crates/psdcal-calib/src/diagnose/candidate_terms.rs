//! The candidate terms of the misfit test (docs/model.md §4.7): which of the
//! model's own parameters, not fitted, would explain the residual structure.
//!
//! A candidate is a group of the model's parameters held at their values in
//! the fit ([`CANDIDATE_TERMS`]: `k3`; `p1, p2`; the PSD's `l1`; `l2`;
//! `skew`; an aspect `a` or `fy` when the chain has one), none of them
//! freed. Freeing it would add to the image-plane residual
//! `r = m̂(θ) − m` the columns
//!
//! ```text
//! ∂m̂/∂θ_c = −(∂ray/∂m)⁻¹ · ∂ray/∂θ_c        at the prediction m̂
//! ```
//!
//! (the predicted point solves `ray(m̂; θ) = (X/Z, Y/Z)` of its pose, whose
//! right side does not depend on `θ`): exactly the Jacobian columns the fit
//! would have with the term freed. Each candidate is scored like the fields
//! ([`super::residual_structure`]): the Gauss–Newton decrease of adding its
//! columns to the freed parameters, the poses re-optimised, as an F-test
//! against the residual, and its share of what the cubic field explains.
//! A term already fitted is never a candidate, so it is never suggested.

use nalgebra::Vector2;
use psdcal_model::{ChainJacobian, Model};

/// The candidate groups, in the order they are reported (a group whose
/// names are not all in the model, or one of which is freed, is skipped).
pub const CANDIDATE_TERMS: &[&[&str]] = &[
    &["k3"],
    &["p1", "p2"],
    &["l1"],
    &["l2"],
    &["skew"],
    &["a"],
    &["fy"],
];

/// A candidate group: its names and its flat model columns.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CandidateTerm {
    pub names: &'static [&'static str],
    pub columns: Vec<usize>,
}

/// The candidates of `model` when the flat columns `freed` are fitted.
pub(crate) fn candidate_terms(model: &Model, freed: &[usize]) -> Vec<CandidateTerm> {
    CANDIDATE_TERMS
        .iter()
        .filter_map(|names| {
            let columns: Option<Vec<usize>> = names.iter().map(|n| model.index(n)).collect();
            let columns = columns?;
            if columns.iter().any(|c| freed.contains(c)) {
                return None;
            }
            Some(CandidateTerm { names, columns })
        })
        .collect()
}

/// A buffer computing the candidates' columns only.
pub(crate) fn term_buffer(model: &Model, terms: &[CandidateTerm]) -> ChainJacobian {
    let mut jac = model.jacobian_buffer();
    let columns: Vec<usize> = terms.iter().flat_map(|t| t.columns.clone()).collect();
    jac.restrict_to(&columns);
    jac
}

/// The candidates' columns `∂m̂/∂θ_c` at the prediction `m_hat` (module
/// documentation), column-major 2 × (their parameters), into `out`; zeros
/// where the ray's Jacobian is singular.
pub(crate) fn term_columns(
    model: &Model,
    m_hat: &Vector2<f64>,
    terms: &[CandidateTerm],
    jac: &mut ChainJacobian,
    out: &mut [f64],
) {
    model.ray_with_jacobians(m_hat, jac);
    let inverse = jac.wrt_point.try_inverse();
    let mut k = 0;
    for term in terms {
        for &c in &term.columns {
            let column = inverse.map_or(Vector2::zeros(), |inv| -(inv * jac.column(c)));
            let finite = column.x.is_finite() && column.y.is_finite();
            out[2 * k] = if finite { column.x } else { 0.0 };
            out[2 * k + 1] = if finite { column.y } else { 0.0 };
            k += 1;
        }
    }
}
