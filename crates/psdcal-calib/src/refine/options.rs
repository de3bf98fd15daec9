//! What a refinement is asked ([`RefineOptions`]): the cost (template or
//! image plane, (P29)), the freed parameters by name (standard ones, the
//! channel gains, other stages'), the noise model that whitens the residuals,
//! an optional robust loss and Gaussian prior, and the solver's budget and
//! tolerances. The covariance order of the freed parameters is
//! [`RefineOptions::free_names`]: the standard ones as listed, the gains,
//! then the other stages'.

use psdcal_model::stages::gains::GAIN_NAMES;
use psdcal_model::{CostKind, Param};
use psdcal_solver::solver::RobustLoss;

use crate::problem::prior::Prior;
use crate::problem::weighting::NoiseModel;

/// Options of [`refine`](fn@crate::refine).
#[derive(Debug, Clone, PartialEq)]
pub struct RefineOptions {
    /// The cost minimised.
    pub cost: CostKind,
    /// The freed standard parameters (the others stay at their start values).
    pub free: Vec<Param>,
    /// Also estimate the relative channel gains `g_x2, g_y1, g_y2`: needs the
    /// data's amplitudes; every impact point is then recomputed from its
    /// amplitudes divided by the current gains (docs/model.md §1).
    pub fit_gains: bool,
    /// Freed parameters of the model's other stages, by name.
    pub free_stage_parameters: Vec<String>,
    /// How the points' noise is weighted ([`crate::weighting`]; uniform,
    /// the paper's unweighted cost, by default).
    pub noise: NoiseModel,
    /// Optional robust loss (off by default).
    pub robust: Option<RobustLoss>,
    /// Iteration budget (accepted and rejected steps both count).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub cost_tolerance: f64,
    /// Stop when the step changes the residuals by less than this fraction
    /// of their norm.
    pub step_tolerance: f64,
    /// Starting damping.
    pub initial_lambda: f64,
    /// A Gaussian prior on some freed parameters (none by default): its
    /// residuals join the cost ([`crate::prior`]).
    pub prior: Option<Prior>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            cost: CostKind::Template,
            free: vec![Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2],
            noise: NoiseModel::Uniform,
            robust: None,
            fit_gains: false,
            free_stage_parameters: Vec::new(),
            max_iterations: 500,
            cost_tolerance: 1e-10,
            step_tolerance: 1e-10,
            initial_lambda: 1e-3,
            prior: None,
        }
    }
}

impl RefineOptions {
    /// Names of every freed parameter, in covariance order: the standard
    /// ones as listed, the gains, then the other stages'.
    pub fn free_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.free.iter().map(|p| p.name().to_string()).collect();
        if self.fit_gains {
            names.extend(GAIN_NAMES.iter().map(|n| n.to_string()));
        }
        names.extend(self.free_stage_parameters.iter().cloned());
        names
    }
}
