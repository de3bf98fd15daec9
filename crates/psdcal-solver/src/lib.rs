//! # psdcal-solver
//!
//! The one solver of psdcal (docs/model.md §4.6, §8): a sparse
//! Levenberg–Marquardt over a runtime-sized global parameter block and
//! independent six-parameter blocks (poses), eliminated by the Schur
//! complement, with Jacobi scaling, robust losses and a report that keeps the
//! last state. Calibration's refinement, its start and its preliminary
//! correction, and the least-squares intersection of rays, are all
//! [`Problem`]s for it.
#![warn(missing_docs)]

pub mod normal_equations;
pub mod solver;

pub use normal_equations::{inverse_scaled, NormalEquations, ResidualTerm, Step};
pub use solver::{
    cost, normal_equations as linearize, solve, Problem, RobustLoss, Solution, SolverOptions,
    SolverReport, Termination,
};
