//! What the planner's tests share: seeded candidate poses, and the spread
//! of repeated estimates against a predicted covariance (the Monte Carlo
//! checks of the planner's prediction).

use nalgebra::{DMatrix, DVector};
use psdcal_calib::plan::{draw_candidates, PlanSetup, PoseRanges};
use psdcal_model::Pose;

/// `n` of the planner's candidate poses for `setup` (default ranges), drawn
/// from `seed`.
pub fn some_poses(setup: &PlanSetup, n: usize, seed: u64) -> Vec<Pose> {
    draw_candidates(setup, &PoseRanges::default(), n, seed)
        .unwrap()
        .into_iter()
        .map(|c| c.pose)
        .collect()
}

/// Asserts that each parameter's sample variance over `estimates` (one
/// vector per trial, in the order of `names`) is within `4·√(2/n)`
/// relative of the prediction's diagonal: a sample variance of `n`
/// draws has a relative standard deviation of about `√(2/n)`, so a correct
/// prediction fails this with probability below 1e-4 per parameter.
pub fn assert_variances_match(
    estimates: &[DVector<f64>],
    names: &[String],
    predicted: &DMatrix<f64>,
) {
    let n = estimates.len();
    let mean = estimates.iter().sum::<DVector<f64>>() / n as f64;
    let tolerance = 4.0 * (2.0 / n as f64).sqrt();
    for (k, name) in names.iter().enumerate() {
        let var = estimates
            .iter()
            .map(|e| (e[k] - mean[k]).powi(2))
            .sum::<f64>()
            / (n - 1) as f64;
        let want = predicted[(k, k)];
        assert!(
            (var / want - 1.0).abs() < tolerance,
            "{name}: variance {var:e} against predicted {want:e}"
        );
    }
}
