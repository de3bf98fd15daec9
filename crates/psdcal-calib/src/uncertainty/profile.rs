//! The profile cost at `θ̂_k ± 3σ_k`: the second stage of the check of the
//! linear covariance (docs/model.md §4.6, "When the linearisation fails").
//!
//! The walk of [`crate::linearity`] follows the quadratic model's direction
//! and says only whether the cost is quadratic there. Where it is not, the
//! profile says whether that matters: for each freed parameter `k` and each
//! side, `θ_k` is held at `θ̂_k ± 3σ_k` and every other parameter and pose
//! refitted (started from the solution with `θ_k` moved), and the rise
//!
//! ```text
//! r = (min_{θ_−k} cost(θ_k = θ̂_k ± 3σ_k) − cost(θ̂)) / (9 s²),   s² = cost(θ̂) / dof
//! ```
//!
//! is 1 for a linear model. The likelihood's own 3σ interval (where the
//! profile has risen by `9 s²`) reaches about `3σ_k / √r` on that side: a
//! rise below [`MIN_PROFILE_RISE`] = 1/4 puts it beyond `6σ_k`, twice the
//! reported, and σ understates the uncertainty; a negative rise means a
//! point 3σ away fits better than the solution, which is then not the
//! minimum. A rise above 1 (the cost climbs faster than its quadratic
//! model, common on weak geometry) leaves σ conservative and is accepted.
//!
//! The channel gains, fitted as one block, are not profiled. The `2p`
//! refits run in parallel (rayon) and are gathered in order.

use rayon::prelude::*;
use serde::Serialize;

use crate::data::CalibrationData;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::solve::refine;

/// Smallest accepted profile rise `r` (module documentation).
pub const MIN_PROFILE_RISE: f64 = 0.25;

/// The profile's rise at `θ̂_k ± 3σ_k` over `9 s²`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterProfile {
    /// The freed parameter.
    pub name: String,
    /// `r` at `θ̂_k − 3σ_k` (NaN when the refit failed).
    pub minus: f64,
    /// `r` at `θ̂_k + 3σ_k` (NaN when the refit failed).
    pub plus: f64,
}

impl ParameterProfile {
    /// The smaller rise of the two sides (NaN when a side failed).
    pub fn least_rise(&self) -> f64 {
        if self.minus.is_nan() || self.plus.is_nan() {
            f64::NAN
        } else {
            self.minus.min(self.plus)
        }
    }

    /// Whether σ understates this parameter's uncertainty (a rise below
    /// [`MIN_PROFILE_RISE`] on a side, or a side that cannot be refitted).
    pub fn understated(&self) -> bool {
        let r = self.least_rise();
        r.is_nan() || r < MIN_PROFILE_RISE
    }
}

/// The profile (module documentation) of every freed parameter but the
/// gains, `std` the reported σ of each in `options.free_names()` order.
/// Empty when the fit is exact or has no degrees of freedom.
pub fn profile_at_three_sigma(
    data: &CalibrationData,
    refined: &Refined,
    options: &RefineOptions,
    std: &[f64],
) -> Vec<ParameterProfile> {
    let names = options.free_names();
    let observations = 2 * data.point_count() + options.prior.as_ref().map_or(0, |p| p.len());
    let unknowns = names.len() + 6 * refined.poses.len();
    if observations <= unknowns || refined.cost.is_nan() || refined.cost <= 0.0 {
        return Vec::new();
    }
    let nine_s2 = 9.0 * refined.cost / (observations - unknowns) as f64;
    let held = |name: &str| -> Option<RefineOptions> {
        let mut o = options.clone();
        let before = o.free.len() + o.free_stage_parameters.len();
        o.free.retain(|p| p.name() != name);
        o.free_stage_parameters.retain(|p| p != name);
        (o.free.len() + o.free_stage_parameters.len() < before).then_some(o)
    };
    names
        .par_iter()
        .zip(std)
        .filter_map(|(name, &sigma)| {
            let o = held(name)?;
            let at = refined.model.get(name)?;
            let rise = |sign: f64| -> f64 {
                let mut model = refined.model.clone();
                if model.set(name, at + sign * 3.0 * sigma).is_err() {
                    return f64::NAN;
                }
                refine(data, model, &refined.poses, &o)
                    .ok()
                    .filter(|r| r.report.termination.converged())
                    .map_or(f64::NAN, |r| (r.cost - refined.cost) / nine_s2)
            };
            Some(ParameterProfile {
                name: name.clone(),
                minus: rise(-1.0),
                plus: rise(1.0),
            })
        })
        .collect()
}
