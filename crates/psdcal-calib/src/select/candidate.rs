//! A candidate group of parameters (docs/model.md §4.8): the groups the
//! forward selection may add, a candidate's fit from the current one (with
//! its other starts: `l1` on strong evidence, the aspect from a square
//! start), its screening by the score statistic, and its held-out score
//! ([`crate::select::influence`]).

use psdcal_model::stages::{with_aspect, Aspect};
use psdcal_model::{Model, Param};

use crate::data::CalibrationData;
use crate::refine::global::{refine_global, GlobalOptions, GlobalReport};
use crate::refine::linearization::AtSolution;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::solve::refine;
use crate::select::influence::image_influence;
use crate::select::screen::{evidence_threshold, score_statistic};
use crate::start::initialize::initialize;
use crate::CalibError;

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
pub(crate) const L1: Group = Group::Params(&[Param::L1]);

/// Starting values of `l1` (mm⁻²) tried besides the current fit's (with
/// `k1` lowered by as much): a local refinement from `l1 = 0` can end in
/// another minimum than the global search's (docs/model.md §4.5), which
/// runs once `l1` is chosen.
pub const L1_STARTS: [f64; 3] = [-2e-3, -1e-3, 1e-3];

/// The score statistic above which `l1` is also refined from
/// [`L1_STARTS`]: evidence at 3σ (χ²₁ = 9) that the PSD's distortion is
/// in the data, where its cost may have several minima.
pub const STRONG_SCORE: f64 = 9.0;

/// Starting aspects tried besides the current fit's (`1 + a` = 1/2 and 2:
/// an interlaced field's pixels, either way), each from the start on the
/// data rescaled to square.
pub const ASPECT_STARTS: [f64; 2] = [-0.5, 1.0];

impl Group {
    /// Whether `options` already free the group.
    pub(crate) fn in_options(self, options: &RefineOptions) -> bool {
        match self {
            Group::Params(params) => params.iter().any(|p| options.free.contains(p)),
            Group::Aspect => options
                .free_stage_parameters
                .iter()
                .any(|n| n == Aspect::NAME),
        }
    }

    /// The names of the group's parameters.
    pub(crate) fn names(self) -> Vec<String> {
        match self {
            Group::Params(params) => params.iter().map(|p| p.name().to_string()).collect(),
            Group::Aspect => vec![Aspect::NAME.to_string()],
        }
    }

    /// `options` with the group freed.
    pub(crate) fn added_to(self, options: &RefineOptions) -> RefineOptions {
        let mut next = options.clone();
        match self {
            Group::Params(params) => next.free.extend_from_slice(params),
            Group::Aspect => next.free_stage_parameters.push(Aspect::NAME.into()),
        }
        next
    }
}

/// A scored fit.
pub(crate) struct Scored {
    pub refined: Refined,
    pub options: RefineOptions,
    pub global: Option<GlobalReport>,
    /// Per image, the sum of its points' squared held-out angles, deg².
    pub sums: Vec<f64>,
    /// The RMS held-out angle, degrees.
    pub rms_deg: f64,
}

pub(crate) fn score(
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
/// `l1` is refined locally, also from [`L1_STARTS`] when `strong` (its
/// score statistic is over [`STRONG_SCORE`]; the global search over `l1`
/// runs in [`searched_l1`] and once `l1` is chosen, [`settled`]); the
/// aspect also from [`ASPECT_STARTS`] when `cold_aspect` (the closed-form
/// start was rejected, as it is for strongly non-square data); the lowest
/// cost kept.
fn fit_candidate(
    data: &CalibrationData,
    current: &Scored,
    group: Group,
    next: &RefineOptions,
    (cold_aspect, strong): (bool, bool),
    global: &GlobalOptions,
) -> Option<Scored> {
    let mut model = current.refined.model.clone();
    if group == Group::Aspect && model.index(Aspect::NAME).is_none() {
        model = with_aspect(&model, 0.0).ok()?;
    }
    let poses = &current.refined.poses;
    let mut fits = vec![refine(data, model.clone(), poses, next)];
    if group == L1 && strong {
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
pub(crate) fn settled(
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

/// What became of a candidate group in a round.
pub(crate) enum Outcome {
    /// Not refitted: its score statistic (at most the evidence threshold).
    Screened(f64),
    /// Refitted from the current fit: its score statistic and its scores.
    Fitted(Option<f64>, Box<Scored>),
    /// Its fit failed.
    Failed,
}

/// Screens `group` by its score statistic ([`crate::select::screen`]) and
/// refits it when the data may ask for it (the aspect of a start the
/// closed form could not give always: its cold starts).
pub(crate) fn evaluate(
    data: &CalibrationData,
    current: &Scored,
    group: Group,
    cold_aspect: bool,
    global: &GlobalOptions,
) -> Outcome {
    let next = group.added_to(&current.options);
    let lm = score_statistic(data, &current.refined, &next, &group.names()).ok();
    let cold = cold_aspect && group == Group::Aspect;
    if let (Some((lm, k)), false) = (lm, cold) {
        if lm <= evidence_threshold(k) {
            return Outcome::Screened(lm);
        }
    }
    // Other starts of l1 only on strong evidence for it.
    let strong = lm.is_none_or(|(lm, _)| lm > STRONG_SCORE);
    match fit_candidate(data, current, group, &next, (cold_aspect, strong), global) {
        Some(scored) => Outcome::Fitted(lm.map(|(lm, _)| lm), Box::new(scored)),
        None => Outcome::Failed,
    }
}

/// The `l1` candidate `scored`, or the global search's fit over `l1` from
/// the current one when its cost is lower (another group passed: the model
/// misses something, and the cost over `l1` may have several minima).
pub(crate) fn searched_l1(
    data: &CalibrationData,
    current: &Scored,
    scored: Scored,
    global: &GlobalOptions,
) -> Scored {
    let model = current.refined.model.clone();
    let searched = refine_global(data, model, &current.refined.poses, &scored.options, global);
    match searched {
        Ok((r, _)) if r.report.termination.converged() && r.cost < scored.refined.cost => {
            let options = scored.options.clone();
            score(data, r, options, current.global.clone()).unwrap_or(scored)
        }
        _ => scored,
    }
}
