//! k-fold cross-validation of a map model and the choice among candidates
//! (docs/model.md §8.3).
//!
//! The kept scan points are dealt into `k` folds by a seeded shuffle
//! (ChaCha8). For each fold the model is fitted to the other folds (the
//! normal equations of all points minus those of the fold) and predicts the
//! fold's displacements; `e_i = |d_i − map(m_i)|` is point `i`'s held-out
//! error. A model's score is `MSE = mean e_i²`; the cross-validated RMS is
//! `√MSE`.
//!
//! **Choice (the one-standard-error rule).** With the best score `MSE*` and
//! its standard error `SE = sd(e_i²)/√n` over the points, the chosen model is
//! the one with the fewest coefficients whose `MSE ≤ MSE* + SE` (a
//! polynomial before a spline of as many): a more flexible model must earn
//! its coefficients by more than the noise in the score, so a field that is
//! exactly cubic gets order 3, not an overfitted 5.

use nalgebra::Vector2;
use psdcal_model::stages::{MapBasis, PsdMap};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::error::PsdMapError;
use crate::normal::{accumulate, NormalEquations};
use crate::penalty::penalty;
use crate::solve::solve;

/// A candidate's score.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateScore {
    /// The model.
    pub basis: MapBasis,
    /// Its cross-validated RMS error, mm.
    pub cv_rms_mm: f64,
    /// Held-out squared error of each kept point, mm².
    pub squared_errors: Vec<f64>,
}

/// The fold of each point (`0 … k − 1`), by a shuffle seeded with `seed`.
pub fn fold_of_points(n: usize, k: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let mut fold = vec![0; n];
    for (rank, i) in order.into_iter().enumerate() {
        fold[i] = rank % k;
    }
    fold
}

/// Cross-validates `map`'s basis on the points (all kept).
pub fn cross_validate(
    map: &PsdMap,
    measured: &[Vector2<f64>],
    displacement: &[Vector2<f64>],
    fold: &[usize],
    k: usize,
) -> Result<CandidateScore, PsdMapError> {
    let ones = vec![1.0; measured.len()];
    let all = accumulate(map, measured, displacement, &ones);
    let p = penalty(&map.basis());
    let label = map.basis().label();
    let mut squared_errors = vec![0.0; measured.len()];
    for f in 0..k {
        let mut held = NormalEquations::zeros(map.terms());
        for i in (0..measured.len()).filter(|&i| fold[i] == f) {
            held.add(map, &measured[i], &displacement[i], 1.0);
        }
        held.symmetrize();
        let solution = solve(&all.minus(&held), &p, &label)?;
        let block = solution.block();
        for i in (0..measured.len()).filter(|&i| fold[i] == f) {
            let e = displacement[i] - map.displacement(&block, &measured[i]);
            squared_errors[i] = e.norm_squared();
        }
    }
    let mse = squared_errors.iter().sum::<f64>() / measured.len() as f64;
    Ok(CandidateScore {
        basis: map.basis(),
        cv_rms_mm: mse.sqrt(),
        squared_errors,
    })
}

/// The index of the chosen candidate by the one-standard-error rule (the
/// scores must not be empty).
pub fn choose(scores: &[CandidateScore]) -> usize {
    let mse = |s: &CandidateScore| s.cv_rms_mm * s.cv_rms_mm;
    let best = (0..scores.len())
        .min_by(|&a, &b| mse(&scores[a]).total_cmp(&mse(&scores[b])))
        .unwrap_or(0);
    let e = &scores[best].squared_errors;
    let n = e.len().max(2) as f64;
    let mean = e.iter().sum::<f64>() / n;
    let var = e.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    let limit = mse(&scores[best]) + (var / n).sqrt();
    let complexity = |s: &CandidateScore| {
        (
            s.basis.terms(),
            matches!(s.basis, MapBasis::Spline { .. }) as usize,
        )
    };
    (0..scores.len())
        .filter(|&i| mse(&scores[i]) <= limit)
        .min_by_key(|&i| complexity(&scores[i]))
        .unwrap_or(best)
}
