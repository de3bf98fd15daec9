//! The parameter set the data choose (docs/model.md §4.8): forward
//! selection over groups of parameters by held-out angle error.
//!
//! From the base fit (`f, cx, cy, k1, k2`, or what the options free), each
//! group not yet chosen — `k3`; `p1, p2`; `l1`; `skew` — is added in turn
//! and the fit refined from the current one (with `l1`, by the global
//! search over `l1`, as an explicit fit does). Each candidate is scored by
//! its leave-one-image-out angle error from the linearisation
//! ([`crate::select::influence`]): per image `i` the sum `s_i` of its
//! points' squared held-out angles. A candidate replaces the current set
//! when its mean `s_i` is lower by more than one standard error of the
//! per-image differences (`d_i = s_i(candidate) − s_i(current)`,
//! `SE = sd(d)/√n`). Of the groups that pass in a round, the one with the
//! fewest parameters among those within one standard error of the round's
//! best is taken (the simplest within the noise of the best), and rounds
//! go on until none passes.

use psdcal_model::stages::{with_aspect, Aspect};
use psdcal_model::{Model, Param};
use serde::Serialize;

use crate::data::CalibrationData;
use crate::refine::global::{refine_global, GlobalOptions, GlobalReport};
use crate::refine::linearization::AtSolution;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::solve::refine;
use crate::select::influence::image_influence;
use crate::start::initialize::initialize;
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

/// A group of parameters the forward selection may add.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Group {
    /// Standard parameters.
    Params(&'static [Param]),
    /// The aspect stage's `a` (docs/model.md §3.3).
    Aspect,
}

/// The groups the forward selection may add, simplest first.
pub const GROUPS: [Group; 5] = [
    Group::Aspect,
    Group::Params(&[Param::K3]),
    Group::Params(&[Param::P1, Param::P2]),
    Group::Params(&[Param::L1]),
    Group::Params(&[Param::Skew]),
];

/// The `l1` group.
const L1: Group = Group::Params(&[Param::L1]);

/// Starting values of `l1` (mm⁻²) tried besides the current fit's (with
/// `k1` lowered by as much): a local refinement from `l1 = 0` can end in
/// another minimum than the global search's (docs/model.md §4.5), which
/// runs once `l1` is chosen.
pub const L1_STARTS: [f64; 3] = [-2e-3, -1e-3, 1e-3];

/// Starting aspects tried besides the current fit's (`1 + a` = 1/2 and 2:
/// an interlaced field's pixels, either way), each from the start on the
/// data rescaled to square.
pub const ASPECT_STARTS: [f64; 2] = [-0.5, 1.0];

impl Group {
    /// Whether `options` already free the group.
    fn in_options(self, options: &RefineOptions) -> bool {
        match self {
            Group::Params(params) => params.iter().any(|p| options.free.contains(p)),
            Group::Aspect => options
                .free_stage_parameters
                .iter()
                .any(|n| n == Aspect::NAME),
        }
    }

    /// `options` with the group freed.
    fn added_to(self, options: &RefineOptions) -> RefineOptions {
        let mut next = options.clone();
        match self {
            Group::Params(params) => next.free.extend_from_slice(params),
            Group::Aspect => next.free_stage_parameters.push(Aspect::NAME.into()),
        }
        next
    }
}

/// One scored candidate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// The freed parameters.
    pub free: Vec<String>,
    /// RMS held-out angle error over every point, degrees.
    pub held_out_rms_deg: f64,
    /// Mean over images of the difference of the per-image sums of squared
    /// held-out angles against the set it was compared with, deg²
    /// (negative: better), and its standard error.
    pub difference_deg2: f64,
    /// Standard error of `difference_deg2`, deg².
    pub standard_error_deg2: f64,
    /// Whether it became the current set.
    pub accepted: bool,
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
}

impl ModelChoiceReport {
    /// No choice: `free` fitted as given, for `reason`.
    pub fn skipped(free: Vec<String>, reason: String) -> Self {
        Self {
            rule: RULE,
            candidates: Vec::new(),
            chosen: free,
            skipped: Some(reason),
        }
    }
}

/// A held-out RMS angle under which the fit is exact to the float
/// precision (degrees; 1.7e-11 rad): no group is judged beside it.
pub const EXACT_FIT_DEG: f64 = 1e-9;

/// The rule, in words.
const RULE: &str = "forward selection: a group of parameters is added when it lowers the \
                    leave-one-image-out angle error by more than one standard error";

/// What the choice returns: the chosen fit, its options, its global
/// search's report, and the report of the choice.
pub(crate) struct Chosen {
    pub refined: Refined,
    pub options: RefineOptions,
    pub global: Option<GlobalReport>,
    pub report: ModelChoiceReport,
}

/// A scored fit.
struct Scored {
    refined: Refined,
    options: RefineOptions,
    global: Option<GlobalReport>,
    sums: Vec<f64>,
    rms_deg: f64,
}

fn score(
    data: &CalibrationData,
    refined: Refined,
    options: RefineOptions,
    global: Option<GlobalReport>,
) -> Result<Scored, CalibError> {
    let influence = {
        let at = AtSolution::new(data, &refined, &options)?;
        image_influence(&at)?
    };
    let deg2 = (180.0 / std::f64::consts::PI).powi(2);
    Ok(Scored {
        sums: influence.image_sums().iter().map(|s| s * deg2).collect(),
        rms_deg: influence.rms_rad().to_degrees(),
        refined,
        options,
        global,
    })
}

/// A candidate's fit from the current one, scored; `None` when it fails.
/// `l1` is refined locally, also from [`L1_STARTS`], and by the global
/// search over `l1` when `search_l1` (another group passed in this round;
/// otherwise the global search runs once `l1` is chosen, [`settled`]); the aspect also from [`ASPECT_STARTS`] when
/// `cold_aspect` (the closed-form start was rejected, as it is for
/// strongly non-square data), the lowest cost kept.
fn fit_candidate(
    data: &CalibrationData,
    current: &Scored,
    group: Group,
    next: &RefineOptions,
    (cold_aspect, search_l1): (bool, bool),
    global: &GlobalOptions,
) -> Option<Scored> {
    let mut model = current.refined.model.clone();
    if group == Group::Aspect && model.index(Aspect::NAME).is_none() {
        model = with_aspect(&model, 0.0).ok()?;
    }
    let poses = &current.refined.poses;
    let mut fits = vec![refine(data, model.clone(), poses, next)];
    if group == L1 {
        // k1 takes up the PSD's l1 when it is held (docs/model.md §2.1).
        let k1 = model.get("k1").unwrap_or(0.0);
        for l0 in L1_STARTS {
            let mut start = model.clone();
            if start
                .set("l1", l0)
                .and_then(|_| start.set("k1", k1 - l0))
                .is_ok()
            {
                fits.push(refine(data, start, poses, next));
            }
        }
    }
    if group == Group::Aspect && cold_aspect && data.amplitudes.is_none() {
        for a0 in ASPECT_STARTS {
            fits.push(
                aspect_start(data, &model, a0, global)
                    .and_then(|(m, poses)| refine(data, m, &poses, next)),
            );
        }
    }
    if group == L1 && search_l1 {
        fits.push(refine_global(data, model.clone(), poses, next, global).map(|(r, _)| r));
    }
    let best = fits
        .into_iter()
        .filter_map(Result::ok)
        .filter(|r| r.report.termination.converged() && r.cost.is_finite())
        .min_by(|a, b| a.cost.total_cmp(&b.cost))?;
    // The l1 search's report stays with the fit it found (until `settled`
    // runs it again).
    score(data, best, next.clone(), current.global.clone()).ok()
}

/// A start with aspect `a0`: the initialisation on the data with `y`
/// scaled by `1/(1 + a0)` (square pixels), its centre mapped back
/// (`cy = c''(1 + a0)` for the stage's scale about `cy`), `model`'s other
/// values kept.
fn aspect_start(
    data: &CalibrationData,
    model: &Model,
    a0: f64,
    global: &GlobalOptions,
) -> Result<(Model, Vec<psdcal_model::Pose>), CalibError> {
    let mut squared = data.clone();
    for image in &mut squared.images {
        for p in &mut image.points {
            p.measured.y /= 1.0 + a0;
        }
    }
    squared.geometry.ly /= 1.0 + a0;
    let init = initialize(&squared, &global.init)?;
    let mut start = model.clone();
    for name in ["f", "cx", "k1", "k2"] {
        if let Some(v) = init.model.get(name) {
            start.set(name, v)?;
        }
    }
    start.set("cy", init.model.get("cy").unwrap_or(0.0) * (1.0 + a0))?;
    start.set(Aspect::NAME, a0)?;
    Ok((start, init.poses))
}

/// The chosen candidate as an explicit fit of its parameters gives it:
/// with `l1`, by the global search over `l1` from it.
fn settled(
    data: &CalibrationData,
    scored: Scored,
    group: Group,
    global: &GlobalOptions,
) -> Result<Scored, CalibError> {
    if group != L1 {
        return Ok(scored);
    }
    let (refined, report) = refine_global(
        data,
        scored.refined.model.clone(),
        &scored.refined.poses,
        &scored.options,
        global,
    )?;
    score(data, refined, scored.options, report)
}

/// Among the candidates that passed, the one with the fewest parameters
/// (the first in [`GROUPS`] order among equals) whose per-image sums are
/// within one standard error of the best's.
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
            let (mean, se) = difference(&s.sums, &best);
            mean <= se
        })
        .min_by_key(|(_, s, _)| s.options.free_names().len())
}

/// Mean and standard error of the per-image differences `a − b`.
fn difference(a: &[f64], b: &[f64]) -> (f64, f64) {
    let n = a.len() as f64;
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
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
        held_out_rms_deg: current.rms_deg,
        difference_deg2: 0.0,
        standard_error_deg2: 0.0,
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
        });
    }
    let mut remaining: Vec<Group> = GROUPS
        .iter()
        .copied()
        .filter(|g| !g.in_options(options))
        .collect();
    loop {
        let mut passing: Vec<(usize, Scored, Group)> = Vec::new();
        // l1 last in a round: its global search runs when another group
        // passed (the model misses something), local refinements otherwise.
        let order = remaining
            .iter()
            .filter(|g| **g != L1)
            .chain(remaining.iter().filter(|g| **g == L1));
        for &group in order {
            let next = group.added_to(&current.options);
            let starts = (cold_aspect, !passing.is_empty());
            let Some(scored) = fit_candidate(data, &current, group, &next, starts, global) else {
                continue;
            };
            let (mean, se) = difference(&scored.sums, &current.sums);
            candidates.push(CandidateScore {
                free: next.free_names(),
                held_out_rms_deg: scored.rms_deg,
                difference_deg2: mean,
                standard_error_deg2: se,
                accepted: false,
            });
            if mean < -se && mean.is_finite() {
                passing.push((candidates.len() - 1, scored, group));
            }
        }
        let best = simplest_near_best(passing);
        match best {
            Some((k, scored, group)) => {
                candidates[k].accepted = true;
                remaining.retain(|g| *g != group);
                current = settled(data, scored, group, global)?;
            }
            None => break,
        }
    }
    Ok(Chosen {
        report: ModelChoiceReport {
            rule: RULE,
            candidates,
            chosen: current.options.free_names(),
            skipped: None,
        },
        refined: current.refined,
        options: current.options,
        global: current.global,
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
}
