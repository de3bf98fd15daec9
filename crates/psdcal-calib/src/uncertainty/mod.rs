//! How well a fit determines its parameters (docs/model.md §4.6): the linear
//! covariance `σ² (JᵀJ)⁻¹` or the sandwich at the solution ([`covariance`]),
//! a fixed stage's uncertainty carried into it ([`carried`]), the check that
//! the cost is quadratic over ±3σ ([`linearity`]) with the profile cost where
//! it is not ([`profile`]), and the case bootstrap by image ([`bootstrap`]).

pub mod bootstrap;
pub mod carried;
pub mod covariance;
pub mod linearity;
pub mod profile;
