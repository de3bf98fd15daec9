//! The cost every fit of a planar template minimises (docs/model.md §4.6, the
//! paper's (P29)): the template-plane (or image-plane) error of each observed
//! point under the model and its image's pose ([`calibration_problem`]),
//! whitened by the point covariance of a noise model ([`weighting`]), with an
//! optional Gaussian prior on some parameters as one more residual group
//! ([`prior`]).
//!
//! Below every other concept of the crate: the start, the refinement, the
//! uncertainty, the diagnostics and the pose planning all evaluate this cost.

pub mod calibration_problem;
pub mod prior;
pub mod weighting;
