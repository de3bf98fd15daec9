//! Choosing `N` poses among candidates (docs/model.md §8.6): greedy
//! selection, then exchange passes.
//!
//! The objective of a set `D` of poses is, with `S = S₀ + Σ_{i∈D} S_i`,
//! `M = M₀ + Σ_{i∈D} M_i` (`S₀`, `M₀` the sums of poses already taken,
//! zero for a new plan) and `C = S⁻¹ M S⁻¹`, the mean `tr(C H̄)` or the largest
//! `tr(C H_m)` of the squared AoA σ over the grid
//! ([`crate::plan::aoa_metric`]). Every pose adds a p × p term to `S` and
//! `M`, so a set is scored from two running sums and one p × p Cholesky
//! factorisation: adding, removing or swapping a pose is a rank-≤p update
//! of the sums.
//!
//! Greedy: starting from the empty set, add the candidate that lowers the
//! objective most, until `N`. While `S` is singular (fewer poses than the
//! parameters need) it is regularised by `λ diag(S̄)` (`S̄` the mean
//! candidate's `S_i`, `λ = 10⁻³`: a thousandth of a pose's information),
//! which only orders the first picks. Exchange: for each chosen pose in
//! turn, the best swap with an unchosen candidate is made when it lowers
//! the objective by more than 10⁻⁹ relatively; passes repeat until none
//! does (at most [`MAX_PASSES`]). Ties go to the lower candidate index, so
//! the result depends only on the candidates (drawn from the seed), not on
//! the thread count.

use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::plan::aoa_metric::AoaMetric;
use crate::plan::information::{parameter_covariance, PoseInformation};

/// Most exchange passes.
pub const MAX_PASSES: usize = 8;

/// Regularisation while the greedy start is singular.
const LAMBDA: f64 = 1e-3;

/// What a plan minimises over the active area.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Objective {
    /// The RMS of the AoA σ.
    #[default]
    Rms,
    /// The largest AoA σ.
    Max,
}

/// Scores sets of poses (module documentation).
pub struct Scorer<'a> {
    infos: &'a [PoseInformation],
    metric: &'a AoaMetric,
    objective: Objective,
    prior_s: DMatrix<f64>,
    prior_m: DMatrix<f64>,
    regulariser: DMatrix<f64>,
}

impl<'a> Scorer<'a> {
    /// A scorer of candidates `infos` on `metric`, with the sums `(S₀, M₀)`
    /// of poses already taken, if any.
    pub fn new(
        infos: &'a [PoseInformation],
        metric: &'a AoaMetric,
        objective: Objective,
        prior: Option<(DMatrix<f64>, DMatrix<f64>)>,
    ) -> Self {
        let p = metric.mean.nrows();
        let mut mean = DMatrix::zeros(p, p);
        for info in infos {
            mean += &info.schur;
        }
        let scale = 1.0 / infos.len().max(1) as f64;
        // A prior already makes `S` regular: no regulariser then.
        let lambda = if prior.is_some() { 0.0 } else { LAMBDA };
        let regulariser = DMatrix::from_diagonal(&(mean.diagonal() * (scale * lambda)));
        Self {
            infos,
            metric,
            objective,
            prior_s: prior
                .as_ref()
                .map_or_else(|| DMatrix::zeros(p, p), |(s, _)| s.clone()),
            prior_m: prior.map_or_else(|| DMatrix::zeros(p, p), |(_, m)| m),
            regulariser,
        }
    }

    /// The sums `S`, `M` of a set.
    pub fn sums(&self, set: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let (mut s, mut m) = (self.prior_s.clone(), self.prior_m.clone());
        for &i in set {
            s += &self.infos[i].schur;
            m += &self.infos[i].noise;
        }
        (s, m)
    }

    /// The objective (rad²) of sums `S`, `M`; `regularise` adds `λ diag(S̄)`
    /// to `S`. Infinite when `S` is singular.
    pub fn score(&self, s: &DMatrix<f64>, m: &DMatrix<f64>, regularise: bool) -> f64 {
        let s = if regularise {
            s + &self.regulariser
        } else {
            s.clone()
        };
        match parameter_covariance(&s, m) {
            None => f64::INFINITY,
            Some(c) => match self.objective {
                Objective::Rms => self.metric.mean_square(&c),
                Objective::Max => self.metric.max_square(&c),
            },
        }
    }

    /// The best candidate not in `exclude` to add to sums `(s, m)`, with its
    /// score; `None` when every candidate is excluded.
    fn best_addition(
        &self,
        s: &DMatrix<f64>,
        m: &DMatrix<f64>,
        exclude: &[usize],
        regularise: bool,
    ) -> Option<(usize, f64)> {
        (0..self.infos.len())
            .into_par_iter()
            .filter(|i| !exclude.contains(i))
            .map(|i| {
                let score = self.score(
                    &(s + &self.infos[i].schur),
                    &(m + &self.infos[i].noise),
                    regularise,
                );
                (i, score)
            })
            .reduce_with(|a, b| {
                if b.1 < a.1 || (b.1 == a.1 && b.0 < a.0) {
                    b
                } else {
                    a
                }
            })
    }

    /// Greedy then exchange (module documentation): `n` candidate indices.
    pub fn select(&self, n: usize) -> Vec<usize> {
        let mut set: Vec<usize> = Vec::with_capacity(n);
        while set.len() < n {
            let (s, m) = self.sums(&set);
            match self.best_addition(&s, &m, &set, true) {
                Some((i, _)) => set.push(i),
                None => break,
            }
        }
        let (s, m) = self.sums(&set);
        let mut current = self.score(&s, &m, true);
        for _ in 0..MAX_PASSES {
            let mut improved = false;
            for slot in 0..set.len() {
                let (s, m) = self.sums(&set);
                let out = set[slot];
                let s_without = &s - &self.infos[out].schur;
                let m_without = &m - &self.infos[out].noise;
                if let Some((i, score)) = self.best_addition(&s_without, &m_without, &set, true) {
                    if score < current * (1.0 - 1e-9) {
                        set[slot] = i;
                        current = score;
                        improved = true;
                    }
                }
            }
            if !improved {
                break;
            }
        }
        set
    }
}
