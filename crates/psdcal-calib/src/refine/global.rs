//! Finding the global minimum when the PSD distortion `l1` is freed together
//! with the lens distortion `k1`.
//!
//! The two radial terms have distinct centres (the electrical centre (0, 0)
//! and the optical centre (cx, cy)); near either centre they trade off
//! (`k1 + l1` is what the data see, docs/model.md §2), so the template-plane
//! cost (P29) is a long curved valley with several basins. A start computed
//! without the PSD term (the closed form on the raw points) can have a
//! biased centre and lie in a wrong basin; a profile continued from it stays
//! on that branch. The search therefore never relies on one branch:
//!
//! 1. *Cold starts*: at every `cold_every`-th value of the `l1` grid the
//!    measured points are corrected for that `l1` (the PSD stage,
//!    `u = m (1 + l1 |m|² + l2 |m|⁴)`, (P14)–(P16)), the whole start
//!    ([`mod@crate::initialize`]: preliminary correction, DLT, closed form) is
//!    run on them, and the fit with `l1` held there is refined from it.
//! 2. *Profile*: for every `l1` of the grid, `l1` held and every other freed
//!    parameter refined, in two sweeps (upwards and downwards over the whole
//!    grid), each point warm-started from its neighbour's solution (`k1`
//!    shifted by the change of `l1`, so the sum the data see is kept) and
//!    compared with the cold start there; the sweep continues from the lower
//!    of the two. The profile is the lower of the sweeps at each point.
//! 3. *Restarts*: from every local minimum of the profile and the lowest
//!    points not next to one, a full refinement with `l1` freed (the plain
//!    start enters the profile at its grid point).
//! 4. *Final check*: a fit with `l1` free cannot end above a fit with `l1`
//!    held, so a profile point below the winner (beyond the solver's
//!    tolerance) is restarted too, until none is.
//!
//! The lowest final cost wins. Distinct minima are reported with their costs,
//! and how many starts reached the winner ([`GlobalReport::winner_found`]);
//! [`GlobalReport::competing`] says whether another minimum is within the
//! noise of it (the diagnostic `local_minimum_suspected`).

use std::sync::atomic::{AtomicUsize, Ordering};

use psdcal_model::{Model, Param, Pose};
use rayon::prelude::*;
use serde::Serialize;

use crate::data::CalibrationData;
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::solve::refine;
use crate::start::initialize::{initialize, InitOptions};
use crate::CalibError;

/// Options of [`refine_global`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalOptions {
    /// Values of `l1` (mm⁻²) at which the profile is taken, ascending.
    pub l1_grid: Vec<f64>,
    /// A cold start at every `cold_every`-th grid value (1: at all of them).
    pub cold_every: usize,
    /// How many of the lowest profile points are restarted besides the
    /// profile's local minima.
    pub restarts: usize,
    /// The start run on the points corrected for each cold `l1`.
    pub init: InitOptions,
}

impl Default for GlobalOptions {
    /// `l1` from −8e-3 to 8e-3 mm⁻² in steps of 2e-3 (the paper's PSD has
    /// −1.3e-3; a pin-cushion PSD's distortion is about 1 % of its size,
    /// which for a 9 mm sensor is |l1| ≈ 1e-3), a cold start at each.
    fn default() -> Self {
        Self {
            l1_grid: (-4..=4).map(|k| k as f64 * 2e-3).collect(),
            cold_every: 1,
            restarts: 2,
            init: InitOptions::default(),
        }
    }
}

/// One local minimum found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LocalMinimum {
    /// Its cost (mm² for the template-plane cost).
    pub cost: f64,
    /// Its `l1`, mm⁻².
    pub l1: f64,
    /// Its `k1`, mm⁻².
    pub k1: f64,
    /// Its focal length, mm.
    pub f: f64,
    /// Its optical centre, mm.
    pub cx: f64,
    /// Its optical centre, mm.
    pub cy: f64,
    /// How many of the full refinements ended here.
    pub found: usize,
}

/// What the global search did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GlobalReport {
    /// `(l1, cost)` along the profile (`l1` fixed); `None` cost where no
    /// refinement succeeded at that `l1`.
    pub profile: Vec<(f64, Option<f64>)>,
    /// The distinct minima reached by the restarts, lowest first.
    pub minima: Vec<LocalMinimum>,
    /// Total refinements run.
    pub refinements: usize,
    /// Cold starts that produced a profile point.
    pub cold_starts: usize,
    /// Profile points restarted by the final check.
    pub final_check_restarts: usize,
}

impl GlobalReport {
    /// How many full refinements reached the winner.
    pub fn winner_found(&self) -> usize {
        self.minima.first().map_or(0, |m| m.found)
    }

    /// The runner-up's cost excess over the winner in units of the residual
    /// variance per coordinate, `Δcost / σ²` (a Δχ²), when there is a
    /// runner-up; `sigma2` from the winner's fit.
    pub fn runner_up_delta_chi2(&self, sigma2: f64) -> Option<f64> {
        let (best, next) = (self.minima.first()?, self.minima.get(1)?);
        (sigma2 > 0.0).then(|| (next.cost - best.cost) / sigma2)
    }

    /// Whether another minimum competes with the winner: a Δχ² below
    /// [`COMPETING_DELTA_CHI2`], i.e. the data barely prefer the winner.
    pub fn competing(&self, sigma2: f64) -> bool {
        self.runner_up_delta_chi2(sigma2)
            .is_some_and(|d| d < COMPETING_DELTA_CHI2)
    }
}

/// Δχ² below which a second minimum competes with the winner (a 3σ margin
/// for one parameter).
pub const COMPETING_DELTA_CHI2: f64 = 9.0;

/// Largest difference of `l1` (mm⁻²) between two stops of the solver at
/// the same minimum.
const SAME_MINIMUM_L1: f64 = 1e-5;

/// Largest relative cost difference between two stops at the same minimum.
const SAME_MINIMUM_COST: f64 = 1e-6;

/// Relative cost excess of the winner over a profile point that the final
/// check tolerates (the profile is refined to a cost tolerance of 1e-6).
const FINAL_CHECK_MARGIN: f64 = 1e-5;

/// Relative cost tolerance of a profile point: the profile locates basins;
/// the restarts settle the minimum.
const PROFILE_TOLERANCE: f64 = 1e-4;

/// Iteration budget of a profile point (an unconverged point is still an
/// upper bound of the profile there, which is all the final check needs).
const PROFILE_ITERATIONS: usize = 6;

/// Rounds of the final check.
const FINAL_CHECK_ROUNDS: usize = 3;

/// `data` with every measured point corrected for the PSD distortion
/// `(l1, l2)` (the PSD stage alone), without amplitudes.
fn psd_corrected(data: &CalibrationData, l1: f64, l2: f64) -> CalibrationData {
    let mut out = data.clone();
    out.amplitudes = None;
    for image in &mut out.images {
        for o in &mut image.points {
            o.measured =
                psdcal_model::stages::psd_radial::PsdRadial::eval(l1, l2, &o.measured, None);
        }
    }
    out
}

/// Refines from `(model, poses)`; when `l1` is among the freed parameters,
/// searches for the global minimum as the module documentation describes.
pub fn refine_global(
    data: &CalibrationData,
    model: impl Into<Model>,
    poses: &[Pose],
    options: &RefineOptions,
    global: &GlobalOptions,
) -> Result<(Refined, Option<GlobalReport>), CalibError> {
    let model: Model = model.into();
    if !options.free.contains(&Param::L1) {
        return Ok((refine(data, &model, poses, options)?, None));
    }
    let grid = &global.l1_grid;
    if grid.is_empty() || !grid.windows(2).all(|w| w[0] < w[1]) {
        return Err(CalibError::InvalidInput {
            reason: "the l1 grid of the global search must be non-empty and ascending".into(),
        });
    }
    let search = Search::new(data, &model, options);
    // The independent fits of each step run in parallel (rayon); each is
    // deterministic and the results are combined in grid order, so the
    // answer does not depend on the number of threads.
    let cold = search.cold_starts(grid, global);
    let cold_starts = cold.iter().filter(|c| c.is_some()).count();
    let profile = search.profile(grid, &cold, poses);
    let costs: Vec<f64> = profile
        .iter()
        .map(|r| r.as_ref().map_or(f64::INFINITY, |r| r.cost))
        .collect();
    let mut order: Vec<usize> = (0..grid.len()).filter(|&k| costs[k].is_finite()).collect();
    order.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
    let mut seeds = restart_seeds(&costs, &order, global.restarts);
    let mut finals = search.restarts(&profile, &seeds);
    let final_check_restarts =
        search.final_check(&profile, &costs, &order, &mut seeds, &mut finals);
    finals.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let minima = distinct_minima(&finals);
    let best = finals
        .into_iter()
        .next()
        .ok_or_else(|| CalibError::NotConverged {
            reason: "no refinement of the l1 profile succeeded".into(),
        })?;
    let report = GlobalReport {
        profile: grid
            .iter()
            .zip(&costs)
            .map(|(l, c)| (*l, c.is_finite().then_some(*c)))
            .collect(),
        minima,
        refinements: search.refinements.load(Ordering::Relaxed),
        cold_starts,
        final_check_restarts,
    };
    Ok((best, Some(report)))
}

/// Step 3, the restarts' grid points: the profile's local minima, then the
/// lowest points (`order`: the finite ones by cost) that are not next to a
/// seed already (a neighbour of a profile minimum lies in its basin), up to
/// `restarts` more than one; in grid order. The plain start is in the
/// profile at its grid point.
fn restart_seeds(costs: &[f64], order: &[usize], restarts: usize) -> Vec<usize> {
    let n = costs.len();
    let mut seeds: Vec<usize> = (0..n)
        .filter(|&k| {
            costs[k].is_finite()
                && (k == 0 || costs[k] <= costs[k - 1])
                && (k + 1 == n || costs[k] <= costs[k + 1])
        })
        .collect();
    for &k in order {
        if seeds.len() > restarts.max(1) {
            break;
        }
        if !seeds.iter().any(|&s| s.abs_diff(k) <= 1) {
            seeds.push(k);
        }
    }
    seeds.sort_unstable();
    seeds
}

/// The refinements of one search (counted).
struct Search<'a> {
    data: &'a CalibrationData,
    model: &'a Model,
    options: &'a RefineOptions,
    profile_options: RefineOptions,
    refinements: AtomicUsize,
}

impl<'a> Search<'a> {
    /// The search from `model` for `options`: its profile fits hold `l1`
    /// and stop at a looser tolerance.
    fn new(data: &'a CalibrationData, model: &'a Model, options: &'a RefineOptions) -> Self {
        Search {
            data,
            model,
            options,
            profile_options: RefineOptions {
                free: options
                    .free
                    .iter()
                    .copied()
                    .filter(|p| *p != Param::L1)
                    .collect(),
                cost_tolerance: PROFILE_TOLERANCE,
                max_iterations: PROFILE_ITERATIONS,
                ..options.clone()
            },
            refinements: AtomicUsize::new(0),
        }
    }

    /// Step 1, the cold starts, at every `cold_every`-th grid point and the last.
    fn cold_starts(&self, grid: &[f64], global: &GlobalOptions) -> Vec<Option<Refined>> {
        (0..grid.len())
            .into_par_iter()
            .map(|k| {
                (k % global.cold_every.max(1) == 0 || k + 1 == grid.len())
                    .then(|| self.cold(grid[k], &global.init))
                    .flatten()
            })
            .collect()
    }

    /// Step 2, the profile: two sweeps over the grid, the lower at each point;
    /// the plain start (`self.model`, `poses`) enters at its nearest grid
    /// point.
    fn profile(
        &self,
        grid: &[f64],
        cold: &[Option<Refined>],
        poses: &[Pose],
    ) -> Vec<Option<Refined>> {
        let l1_start = self.model.get("l1").unwrap_or(0.0);
        let nearest = (0..grid.len())
            .min_by(|&a, &b| {
                (grid[a] - l1_start)
                    .abs()
                    .total_cmp(&(grid[b] - l1_start).abs())
            })
            .unwrap_or(0);
        let plain = self.fixed_at(self.model, poses, grid[nearest]);
        let (up, down) = rayon::join(
            || self.sweep(grid, (0..grid.len()).collect(), cold, (nearest, &plain)),
            || {
                self.sweep(
                    grid,
                    (0..grid.len()).rev().collect(),
                    cold,
                    (nearest, &plain),
                )
            },
        );
        up.into_iter().zip(down).map(|(a, b)| lower(a, b)).collect()
    }

    /// Step 3, the full refinements from the profile at `seeds`.
    fn restarts(&self, profile: &[Option<Refined>], seeds: &[usize]) -> Vec<Refined> {
        seeds
            .par_iter()
            .filter_map(|&k| {
                profile[k]
                    .as_ref()
                    .and_then(|p| self.free(&p.model, &p.poses))
            })
            .collect()
    }

    /// Step 4, the final check: no profile point (`l1` held) may lie below the
    /// winner among `finals`; those that do are restarted (added to `seeds`,
    /// their fits to `finals`), for at most [`FINAL_CHECK_ROUNDS`] rounds.
    /// Returns how many were restarted.
    fn final_check(
        &self,
        profile: &[Option<Refined>],
        costs: &[f64],
        order: &[usize],
        seeds: &mut Vec<usize>,
        finals: &mut Vec<Refined>,
    ) -> usize {
        let mut final_check_restarts = 0;
        for _ in 0..FINAL_CHECK_ROUNDS {
            let best = finals.iter().map(|r| r.cost).fold(f64::INFINITY, f64::min);
            let beaten: Vec<usize> = order
                .iter()
                .copied()
                .filter(|&k| !seeds.contains(&k) && costs[k] < best * (1.0 - FINAL_CHECK_MARGIN))
                .collect();
            if beaten.is_empty() {
                break;
            }
            seeds.extend(&beaten);
            final_check_restarts += beaten.len();
            let restarted: Vec<Refined> = beaten
                .par_iter()
                .filter_map(|&k| {
                    let start = profile[k].as_ref()?;
                    match self.free(&start.model, &start.poses) {
                        Some(r) if r.cost <= start.cost * (1.0 + FINAL_CHECK_MARGIN) => Some(r),
                        // A free fit above its own fixed-l1 start (the solver
                        // stopped early in the valley): the profile point itself
                        // is the better answer, refined once more with l1 free
                        // from a tighter start.
                        _ => self.free_tight(&start.model, &start.poses),
                    }
                })
                .collect();
            finals.extend(restarted);
        }
        final_check_restarts
    }

    /// The fit with `l1` held at `l1`, from `(model, poses)` with `k1`
    /// shifted so that `k1 + l1` is kept.
    fn fixed_at(&self, model: &Model, poses: &[Pose], l1: f64) -> Option<Refined> {
        let mut m = model.clone();
        let k1 = m.get("k1").unwrap_or(0.0) + m.get("l1").unwrap_or(0.0) - l1;
        m.set("k1", k1).ok()?;
        m.set("l1", l1).ok()?;
        self.refinements.fetch_add(1, Ordering::Relaxed);
        refine(self.data, &m, poses, &self.profile_options)
            .ok()
            .filter(|r| r.cost.is_finite())
    }

    /// The cold start at `l1`: the whole start on the points corrected for
    /// `l1`, then the fit with `l1` held.
    fn cold(&self, l1: f64, init: &InitOptions) -> Option<Refined> {
        let l2 = self.model.get("l2").unwrap_or(0.0);
        let corrected = psd_corrected(self.data, l1, l2);
        // The paper's start (closed form, preliminary k1, k2, homography
        // poses), without the refined closed form or the focal search: the
        // fit with l1 held refines it, and other starts compete.
        let cheap = InitOptions {
            refine_start: false,
            search_fallback: false,
            ..*init
        };
        let start = initialize(&corrected, &cheap).ok()?;
        let mut m = self.model.clone();
        for p in [Param::F, Param::Cx, Param::Cy, Param::K1, Param::K2] {
            if self.options.free.contains(&p) {
                m.set(p.name(), start.model.get(p.name())?).ok()?;
            }
        }
        m.set("l1", l1).ok()?;
        self.refinements.fetch_add(1, Ordering::Relaxed);
        refine(self.data, &m, &start.poses, &self.profile_options)
            .ok()
            .filter(|r| r.cost.is_finite())
    }

    /// One sweep over the grid in `order`: each point from its predecessor's
    /// solution, compared with the cold start and (at its grid point) the
    /// plain start; the lower continues.
    fn sweep(
        &self,
        grid: &[f64],
        order: Vec<usize>,
        cold: &[Option<Refined>],
        (plain_at, plain): (usize, &Option<Refined>),
    ) -> Vec<Option<Refined>> {
        let mut out: Vec<Option<Refined>> = vec![None; grid.len()];
        let mut current: Option<Refined> = None;
        for k in order {
            let warm = current
                .as_ref()
                .and_then(|c| self.fixed_at(&c.model, &c.poses, grid[k]));
            let mut here = lower(warm, cold[k].clone());
            if k == plain_at {
                here = lower(here, plain.clone());
            }
            if here.is_some() {
                current = here.clone();
            }
            out[k] = here;
        }
        out
    }

    /// The full refinement (every freed parameter, `l1` included).
    fn free(&self, model: &Model, poses: &[Pose]) -> Option<Refined> {
        self.refinements.fetch_add(1, Ordering::Relaxed);
        refine(self.data, model, poses, self.options)
            .ok()
            .filter(|r| r.cost.is_finite())
    }

    /// [`Self::free`] with the cost tolerance tightened a thousandfold.
    fn free_tight(&self, model: &Model, poses: &[Pose]) -> Option<Refined> {
        self.refinements.fetch_add(1, Ordering::Relaxed);
        let tight = RefineOptions {
            cost_tolerance: self.options.cost_tolerance * 1e-3,
            ..self.options.clone()
        };
        refine(self.data, model, poses, &tight)
            .ok()
            .filter(|r| r.cost.is_finite())
    }
}

/// The lower-cost of two optional fits.
fn lower(a: Option<Refined>, b: Option<Refined>) -> Option<Refined> {
    match (a, b) {
        (Some(a), Some(b)) => Some(if b.cost < a.cost { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// The distinct minima among `finals` (sorted by cost), each with how many
/// fits reached it: the same minimum has the same `l1` (to 1e-5 mm⁻², a
/// hundredth of the paper's PSD term: the valley is flat along `l1`, two
/// stops of the solver in it differ by more than rounding, and distinct
/// basins lie a grid step of 2e-3 apart) and the same cost (to 1e-6
/// relative, the solver's cost tolerance).
fn distinct_minima(finals: &[Refined]) -> Vec<LocalMinimum> {
    let mut minima: Vec<LocalMinimum> = Vec::new();
    for r in finals {
        let sensor = r.model.sensor_model();
        let (d, k) = (&sensor.distortion, &sensor.intrinsics);
        let same = minima.iter_mut().find(|m| {
            (m.l1 - d.l1).abs() <= SAME_MINIMUM_L1
                && (m.cost - r.cost).abs() <= SAME_MINIMUM_COST * m.cost.max(1e-300)
        });
        match same {
            Some(m) => m.found += 1,
            None => minima.push(LocalMinimum {
                cost: r.cost,
                l1: d.l1,
                k1: d.k1,
                f: k.f,
                cx: k.cx,
                cy: k.cy,
                found: 1,
            }),
        }
    }
    minima
}
