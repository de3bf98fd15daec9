//! What a finished fit says about itself (docs/model.md §4.6–4.7): the fit
//! statistics ([`mod@fit_statistics`]: the paper's residual, RMS errors, worst points),
//! the tests of the residuals for a smooth field the model does not contain
//! ([`residual_structure`]), and the diagnostics with stable codes built on
//! them, the covariance and the global search ([`diagnostics`]), and which
//! term of the model not fitted would explain a structure
//! ([`candidate_terms`]).

pub mod candidate_terms;
pub mod diagnostics;
pub mod fit_statistics;
pub mod residual_structure;
