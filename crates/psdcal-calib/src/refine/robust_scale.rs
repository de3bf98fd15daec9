//! The robust loss's scale in units of the residuals' own noise
//! (docs/model.md §4.6): `calibrate --robust huber:K` down-weights residuals
//! beyond `K σ̂`, where `σ̂` is a robust estimate of the noise of one
//! coordinate of a residual in the cost's own units (template-plane or
//! sensor millimetres, or whitened units under a noise model):
//!
//! ```text
//! σ̂ = median ‖r_k‖ / √(2 ln 2)      (2-row terms: ‖r‖ of a 2-D Gaussian of σ
//!                                     per coordinate has median σ √(2 ln 2))
//! σ̂ = median |r_k| / 0.6745          (1-row terms)
//! ```
//!
//! The median ignores up to half of the points as outliers. It is taken at
//! the start (whose residuals are wider than the noise: a loose loss that
//! still bounds gross outliers), then again at the solution; when the two
//! differ by more than [`RESCALE_TOLERANCE`] the fit is refined once more
//! with the loss at the solution's `σ̂`. A fit without residuals (an exact
//! fit, `σ̂ = 0`) has no outliers: the loss is then dropped.

use psdcal_solver::solver::{Problem, RobustLoss};

use crate::data::CalibrationData;
use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::problem::weighting::PointWeights;
use crate::refine::options::RefineOptions;
use crate::CalibError;

/// Relative change of `σ̂` from the start to the solution above which the
/// fit is refined again at the solution's `σ̂`.
pub const RESCALE_TOLERANCE: f64 = 0.1;

/// `√(2 ln 2)`: the median of the norm of a 2-D standard Gaussian.
const MEDIAN_NORM_2D: f64 = 1.177_410_022_515_474_6;
/// The median of the absolute value of a standard Gaussian.
const MEDIAN_ABS_1D: f64 = 0.674_489_750_196_081_7;

/// `σ̂` of the residuals of `state` in the cost of `options` (module
/// documentation); `None` when there are none or they are all zero.
pub fn residual_noise(
    data: &CalibrationData,
    state: &FitState,
    options: &RefineOptions,
) -> Result<Option<f64>, CalibError> {
    let weights = PointWeights::compute(
        data,
        options.noise,
        options.cost,
        &state.model,
        &state.poses,
    )?;
    let problem = CalibrationProblem::new(data, options.cost, &state.model, &[], weights.as_ref())?;
    let mut norms = Vec::with_capacity(data.point_count());
    let mut rows = 2;
    problem.evaluate(state, false, &mut |t| {
        rows = t.r.len();
        norms.push(t.r.iter().map(|v| v * v).sum::<f64>().sqrt());
    })?;
    if norms.is_empty() {
        return Ok(None);
    }
    let mid = norms.len() / 2;
    let median = *norms.select_nth_unstable_by(mid, f64::total_cmp).1;
    let sigma = median
        / if rows == 1 {
            MEDIAN_ABS_1D
        } else {
            MEDIAN_NORM_2D
        };
    Ok((sigma.is_finite() && sigma > 0.0).then_some(sigma))
}

/// `options` with its robust loss, given in units of `σ̂`, made absolute at
/// `sigma` (dropped when `sigma` is `None`).
pub fn absolute(
    options: &RefineOptions,
    relative: RobustLoss,
    sigma: Option<f64>,
) -> RefineOptions {
    RefineOptions {
        robust: sigma.map(|s| relative.scaled(s)),
        ..options.clone()
    }
}
