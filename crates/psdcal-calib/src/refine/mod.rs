//! Levenberg–Marquardt refinement of the model's freed parameters and every
//! pose (docs/model.md §4.6, the paper's (P29)): the cost of
//! [`crate::calibration_problem`] minimised by the one solver
//! ([`psdcal_solver::solver`]).
//!
//! The freed parameters are any of the model's, by name
//! ([`RefineOptions::free`], the gains, other stages' parameters); a
//! [`Prior`](crate::Prior) may join the cost ([`crate::prior`]).
//!
//! With a noise model other than uniform, each residual is whitened
//! ([`crate::weighting`]); because template-plane weights depend on the
//! parameters, they are recomputed at the solution and the refinement
//! repeated until the weighted cost settles (at most five passes).
//!
//! Stopping (the solver's): an *exact fit* when the RMS residual is below
//! 1e-10 (mm; a few hundred times the rounding floor of the back-projection),
//! a negligible step or cost change, saturated damping, or the iteration
//! budget. A run that ends on the budget still returns its last state.
//!
//! The folder: one refinement ([`refine`](fn@refine)), the linearisation it
//! keeps for the covariance and the linearity check, and the global search
//! over `l1` ([`global`]). The problem it minimises is [`crate::problem`]'s.

pub mod global;
pub(crate) mod linearization;
pub(crate) mod options;
pub(crate) mod refined;
pub(crate) mod robust_scale;
pub(crate) mod solve;

pub use crate::problem::calibration_problem::{total_cost, CalibrationProblem, FitState};
pub use options::RefineOptions;
pub use psdcal_solver::solver::{RobustLoss, SolverReport as RefineReport, Termination};
pub use refined::Refined;
pub use solve::{refine, start_model};

/// Which error the refinement minimises (defined once, in psdcal-model: the
/// same enum is calibration.json's `fit.cost`).
pub use psdcal_model::CostKind;
