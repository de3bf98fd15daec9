//! The parameter set the data choose (docs/model.md §4.8): forward
//! selection over groups of parameters by held-out angle error.
//!
//! From the base fit (`f, cx, cy, k1, k2`, or what the options free), each
//! group not yet chosen — `a`; `k3`; `p1, p2`; `l1`; `skew` — is screened
//! by its score statistic ([`crate::select::screen`]: a group whose
//! statistic is under the evidence threshold cannot pass) and otherwise
//! added and the fit refined from the current one
//! ([`crate::select::candidate`]; with `l1`, by the global search over
//! `l1`, as an explicit fit does). The candidates of a round are fitted in
//! parallel (rayon, in order: the same answers on any number of threads). Each candidate is scored by
//! its leave-one-image-out angle error from the linearisation
//! ([`crate::select::influence`]): per image `i` the sum `s_i` of its
//! points' squared held-out angles. A candidate replaces the current set
//! when (1) its score statistic is beyond the 3σ point of χ²_k (the data
//! themselves show the group is not noise: `evidence_threshold`), (2) it
//! lowers the total held-out error `Σ s_i`, and (3) it does so beyond the
//! noise of the images: the mean of the per-image differences
//! `d_i = s_i(candidate) − s_i(current)` or of the per-image log ratios
//! `l_i = ln(s_i(candidate)/s_i(current))` is below zero by more than
//! [`PASS_SE`] of its standard error (`sd/√n`). The ratios weigh each
//! image's change by its own held-out error (a PSD distortion that cut every
//! image's held-out error fivefold passed at only 1.7 standard errors of
//! the differences, dominated by the worst images); the differences follow
//! the total where a few images carry the gain (an aspect on a real set).
//! Of the groups that pass in a round, the one with the fewest parameters
//! among those within one standard error of the round's best (log ratios)
//! is taken (the simplest within the noise of the best), and rounds go on
//! until none passes.

use rayon::prelude::*;
use serde::Serialize;

use crate::data::CalibrationData;
use crate::refine::global::{GlobalOptions, GlobalReport};
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::select::candidate::{
    evaluate, score, searched_l1, settled, Group, Outcome, Scored, GROUPS, L1,
};
use crate::select::choice_spread::{difference_of, pass_probability, Neighbour};
use crate::select::screen::evidence_threshold;
use crate::CalibError;

/// Whether [`calibrate`](fn@crate::calibrate) fits the parameters it is
/// given or chooses them by held-out error (`calibrate` without `--fit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelChoice {
    /// Fit exactly the freed parameters of the options.
    Given,
    /// Start from the freed parameters and add the groups the held-out
    /// error asks for ([module documentation](self)).
    #[default]
    HeldOut,
}

impl ModelChoice {
    /// The text form: `given` or `held-out`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Given => "given",
            Self::HeldOut => "held-out",
        }
    }
}

/// One scored candidate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// The freed parameters.
    pub free: Vec<String>,
    /// The score statistic of the group added, in noise variances
    /// ([`crate::select::screen`]; `None` for the base): a candidate whose
    /// statistic is at most the evidence threshold is not refitted.
    pub score_statistic: Option<f64>,
    /// RMS held-out angle error over every point, degrees (`None`: not
    /// refitted).
    pub held_out_rms_deg: Option<f64>,
    /// Mean over images of the difference of the per-image sums of squared
    /// held-out angles against the set it was compared with, deg²
    /// (negative: better).
    pub difference_deg2: Option<f64>,
    /// Standard error of `difference_deg2`, deg².
    pub standard_error_deg2: Option<f64>,
    /// Mean over images of `ln(s_i(candidate)/s_i(compared))`, the
    /// per-image sums of squared held-out angles (negative: better).
    pub log_ratio: Option<f64>,
    /// Standard error of `log_ratio`.
    pub log_ratio_se: Option<f64>,
    /// Whether it became the current set.
    pub accepted: bool,
}

impl CandidateScore {
    /// A candidate not refitted, with its score statistic.
    fn screened(free: Vec<String>, lm: f64) -> Self {
        Self {
            free,
            score_statistic: Some(lm),
            held_out_rms_deg: None,
            difference_deg2: None,
            standard_error_deg2: None,
            log_ratio: None,
            log_ratio_se: None,
            accepted: false,
        }
    }
}

/// The choice: every candidate scored, in the order tried, and the chosen
/// freed parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelChoiceReport {
    /// The rule, in words.
    pub rule: &'static str,
    /// The candidates, the base first.
    pub candidates: Vec<CandidateScore>,
    /// The chosen freed parameters.
    pub chosen: Vec<String>,
    /// Why no candidate was scored, when none was (the given parameters
    /// were fitted).
    pub skipped: Option<String>,
    /// The models without one of the groups taken and the probability
    /// that another data set would choose them, whose spread the default σ
    /// includes ([`crate::select::choice_spread`]).
    pub neighbours: Vec<NeighbourScore>,
}

/// A neighbouring model in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NeighbourScore {
    /// The group taken, which the neighbour lacks.
    pub group: Vec<String>,
    /// The probability that another data set would not take it.
    pub probability: f64,
}

impl ModelChoiceReport {
    /// No choice: `free` fitted as given, for `reason`.
    pub fn skipped(free: Vec<String>, reason: String) -> Self {
        Self {
            rule: RULE,
            candidates: Vec::new(),
            chosen: free,
            skipped: Some(reason),
            neighbours: Vec::new(),
        }
    }
}

/// How many standard errors (of the per-image differences or log ratios)
/// a group must lower the held-out error by to be added: one, the noise of
/// the held-out error (docs/model.md §4.8).
pub const PASS_SE: f64 = 1.0;

/// A held-out RMS angle under which the fit is exact to the float
/// precision (degrees; 1.7e-11 rad): no group is judged beside it.
pub const EXACT_FIT_DEG: f64 = 1e-9;

/// The rule, in words.
const RULE: &str = "forward selection: a group of parameters is added when its score statistic \
                    is beyond the 3-sigma point of chi-square and it lowers the \
                    leave-one-image-out angle error by more than one standard error of the \
                    per-image differences or log ratios; of those passing in a round, the \
                    simplest within one standard error of the best";

/// What the choice returns: the chosen fit, its options, its global
/// search's report, and the report of the choice.
pub(crate) struct Chosen {
    pub refined: Refined,
    pub options: RefineOptions,
    pub global: Option<GlobalReport>,
    pub report: ModelChoiceReport,
    /// The models one group away that the data could as well have chosen
    /// ([`crate::select::choice_spread`]).
    pub neighbours: Vec<Neighbour>,
}

/// Among the candidates that passed, the one with the fewest parameters
/// (the first in [`GROUPS`] order among equals) whose per-image sums are
/// within one standard error of the best's (their mean log ratio).
fn simplest_near_best(passing: Vec<(usize, Scored, Group)>) -> Option<(usize, Scored, Group)> {
    let best = passing
        .iter()
        .min_by(|a, b| a.1.rms_deg.total_cmp(&b.1.rms_deg))?
        .1
        .sums
        .clone();
    passing
        .into_iter()
        .filter(|(_, s, _)| {
            let (mean, se) = log_ratio(&s.sums, &best);
            mean <= se
        })
        .min_by_key(|(_, s, _)| s.options.free_names().len())
}

/// Mean and standard error of the per-image log ratios `ln(a/b)` (both
/// kept off zero by a millionth of `b`'s mean).
fn log_ratio(a: &[f64], b: &[f64]) -> (f64, f64) {
    let floor = 1e-6 * b.iter().sum::<f64>() / b.len().max(1) as f64;
    let l: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(x, y)| ((x + floor) / (y + floor)).ln())
        .collect();
    mean_and_se(&l)
}

/// Mean and standard error of `d`.
fn mean_and_se(d: &[f64]) -> (f64, f64) {
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// Mean and standard error of the per-image differences `a − b`.
fn difference(a: &[f64], b: &[f64]) -> (f64, f64) {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    mean_and_se(&d)
}

/// Chooses the freed parameters from the base fit `base` (its options
/// `options`) by forward selection ([module documentation](self));
/// `cold_aspect`: also try the aspect from [`ASPECT_STARTS`].
pub(crate) fn choose(
    data: &CalibrationData,
    base: Refined,
    base_global: Option<GlobalReport>,
    options: &RefineOptions,
    cold_aspect: bool,
    global: &GlobalOptions,
) -> Result<Chosen, CalibError> {
    let mut current = score(data, base, options.clone(), base_global)?;
    let mut candidates = vec![CandidateScore {
        free: options.free_names(),
        score_statistic: None,
        held_out_rms_deg: Some(current.rms_deg),
        difference_deg2: None,
        standard_error_deg2: None,
        log_ratio: None,
        log_ratio_se: None,
        accepted: true,
    }];
    if current.rms_deg <= EXACT_FIT_DEG {
        // Nothing to gain over a fit at the float precision's noise.
        return Ok(Chosen {
            report: ModelChoiceReport {
                candidates,
                ..ModelChoiceReport::skipped(
                    options.free_names(),
                    format!(
                        "the given parameters fit exactly (held-out error {:.1e}°)",
                        current.rms_deg
                    ),
                )
            },
            refined: current.refined,
            options: current.options,
            global: current.global,
            neighbours: Vec::new(),
        });
    }
    let mut remaining: Vec<Group> = GROUPS
        .iter()
        .copied()
        .filter(|g| !g.in_options(options))
        .collect();
    // Per candidate, the probability another data set would pass it.
    let mut pass: Vec<f64> = vec![1.0];
    let mut taken: Vec<Neighbour> = Vec::new();
    loop {
        let mut passing: Vec<(usize, Scored, Group)> = Vec::new();
        // l1 last in a round: its global search runs when another group
        // passed (the model misses something), local refinements otherwise.
        let order = remaining
            .iter()
            .filter(|g| **g != L1)
            .chain(remaining.iter().filter(|g| **g == L1));
        let groups: Vec<Group> = order.copied().collect();
        let outcomes: Vec<Outcome> = groups
            .par_iter()
            .map(|&group| evaluate(data, &current, group, cold_aspect, global))
            .collect();
        for (group, outcome) in groups.into_iter().zip(outcomes) {
            let free = group.added_to(&current.options).free_names();
            let (lm, scored) = match outcome {
                Outcome::Failed => continue,
                Outcome::Screened(lm) => {
                    candidates.push(CandidateScore::screened(free, lm));
                    pass.push(0.0);
                    continue;
                }
                Outcome::Fitted(lm, scored) => (lm, *scored),
            };
            // l1's global search when another group passed in this round.
            let scored = if group == L1 && !passing.is_empty() {
                searched_l1(data, &current, scored, global)
            } else {
                scored
            };
            let (mean, se) = difference(&scored.sums, &current.sums);
            let (log_ratio, log_se) = log_ratio(&scored.sums, &current.sums);
            candidates.push(CandidateScore {
                free,
                score_statistic: lm,
                held_out_rms_deg: Some(scored.rms_deg),
                difference_deg2: Some(mean),
                standard_error_deg2: Some(se),
                log_ratio: Some(log_ratio),
                log_ratio_se: Some(log_se),
                accepted: false,
            });
            let threshold = evidence_threshold(group.names().len());
            let evidence = lm.is_none_or(|lm| lm > threshold);
            let held_out = mean < -PASS_SE * se || log_ratio < -PASS_SE * log_se;
            // The held-out test's statistic, in standard errors.
            let t =
                (-mean / se.max(f64::MIN_POSITIVE)).max(-log_ratio / log_se.max(f64::MIN_POSITIVE));
            pass.push(pass_probability(t, PASS_SE, lm, threshold));
            if evidence && mean < 0.0 && held_out && log_ratio.is_finite() {
                passing.push((candidates.len() - 1, scored, group));
            }
        }
        let best = simplest_near_best(passing);
        match best {
            Some((k, scored, group)) => {
                candidates[k].accepted = true;
                remaining.retain(|g| *g != group);
                let after = settled(data, scored, group, global)?;
                let names = after.options.free_names();
                taken.push(Neighbour {
                    free: group.names(),
                    delta: difference_of(&after, &current, &names),
                    probability: 1.0 - pass[k],
                });
                current = after;
            }
            None => break,
        }
    }
    let neighbours: Vec<NeighbourScore> = taken
        .iter()
        .map(|n| NeighbourScore {
            group: n.free.clone(),
            probability: n.probability,
        })
        .collect();
    Ok(Chosen {
        report: ModelChoiceReport {
            rule: RULE,
            candidates,
            chosen: current.options.free_names(),
            skipped: None,
            neighbours,
        },
        refined: current.refined,
        options: current.options,
        global: current.global,
        neighbours: taken,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn difference_is_mean_and_standard_error() {
        let (m, se) = difference(&[3.0, 5.0, 7.0], &[1.0, 1.0, 1.0]);
        assert!((m - 4.0).abs() < 1e-15);
        // d = 2, 4, 6: sd 2, SE 2/√3.
        assert!((se - 2.0 / 3f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn log_ratio_weighs_every_image_alike() {
        // Every image's held-out error cut fivefold, one image 100 times
        // larger than the others: the ratios agree, the differences do not.
        let before = [1.0, 1.0, 1.0, 100.0];
        let after: Vec<f64> = before.iter().map(|s| s / 5.0).collect();
        let (m, se) = log_ratio(&after, &before);
        assert!((m - (0.2f64 + 1e-6 * 25.75 / 1.0).ln()).abs() < 1e-3, "{m}");
        assert!(se < 1e-4, "{se}");
        let (d, d_se) = difference(&after, &before);
        assert!(d < 0.0 && -d < 2.0 * d_se, "{d} ± {d_se}");
    }
}
