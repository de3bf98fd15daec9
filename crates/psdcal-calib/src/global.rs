//! Finding the global minimum when the PSD distortion `l1` is freed together
//! with the lens distortion `k1`.
//!
//! The two radial terms have distinct centres (the electrical centre (0, 0)
//! and the optical centre (cx, cy)); near either centre they trade off
//! (`k1 + l1` is what the data see, docs/model.md §2), so the template-plane cost
//! (P29) is a long curved valley in which a single Levenberg–Marquardt run can
//! stop at a wrong local minimum.
//!
//! Strategy (a profile with restarts):
//! 1. *Profile*: for each `l1` on a grid, `l1` is held fixed and every other
//!    freed parameter refined, warm-started from the neighbouring grid point
//!    (continuation along the valley; `k1` starts at `k1 + l1_prev − l1` so the
//!    sum the data see is kept);
//! 2. *Restarts*: from every local minimum of the profile (and the lowest
//!    points), a full refinement with `l1` freed;
//! 3. the lowest final cost wins; distinct minima (different `l1`, or costs
//!    differing by more than 1e-9 relative) are reported with their costs.

use psdcal_model::{Model, Param, Pose};
use serde::Serialize;

use crate::data::CalibrationData;
use crate::refine::{refine, RefineOptions, Refined};
use crate::CalibError;

/// Options of [`refine_global`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalOptions {
    /// Values of `l1` (mm⁻²) at which the profile is taken.
    pub l1_grid: Vec<f64>,
    /// How many of the lowest profile points are restarted besides the
    /// profile's local minima.
    pub restarts: usize,
}

impl Default for GlobalOptions {
    /// `l1` from −8e-3 to 8e-3 mm⁻² in steps of 1e-3 (the paper's PSD has
    /// −1.3e-3; a pin-cushion PSD's distortion is about 1 % of its size,
    /// which for a 9 mm sensor is |l1| ≈ 1e-3).
    fn default() -> Self {
        Self {
            l1_grid: (-8..=8).map(|k| k as f64 * 1e-3).collect(),
            restarts: 2,
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
}

/// What the global search did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GlobalReport {
    /// `(l1, cost)` along the profile (`l1` fixed); `None` cost where the
    /// refinement failed at that `l1`.
    pub profile: Vec<(f64, Option<f64>)>,
    /// The distinct minima reached by the restarts, lowest first.
    pub minima: Vec<LocalMinimum>,
    /// Total refinements run.
    pub refinements: usize,
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
    let model = &model;
    if !options.free.contains(&Param::L1) {
        return Ok((refine(data, model, poses, options)?, None));
    }
    let l1_of = |m: &Model| m.get("l1").unwrap_or(0.0);
    let profile_options = RefineOptions {
        free: options
            .free
            .iter()
            .copied()
            .filter(|p| *p != Param::L1)
            .collect(),
        cost_tolerance: 1e-6,
        ..options.clone()
    };
    let mut refinements = 0;
    // Profile, continued outwards from the grid point nearest the start.
    let grid = &global.l1_grid;
    let start = (0..grid.len())
        .min_by(|&a, &b| {
            (grid[a] - l1_of(model))
                .abs()
                .total_cmp(&(grid[b] - l1_of(model)).abs())
        })
        .ok_or_else(|| CalibError::Numerical {
            stage: "global search",
            reason: "empty l1 grid".into(),
        })?;
    let mut profile: Vec<Option<Refined>> = vec![None; grid.len()];
    let downwards = (0..=start).rev();
    let upwards = start + 1..grid.len();
    let mut at_start = (model.clone(), poses.to_vec());
    for (pass, indices) in [downwards.collect::<Vec<_>>(), upwards.collect()]
        .into_iter()
        .enumerate()
    {
        // The upward pass continues from the profile's solution at the start.
        let mut current = if pass == 0 {
            (model.clone(), poses.to_vec())
        } else {
            at_start.clone()
        };
        for k in indices {
            let l1 = grid[k];
            let mut m = current.0.clone();
            let k1 = m.get("k1").unwrap_or(0.0) + l1_of(&m) - l1;
            m.set("k1", k1)?;
            m.set("l1", l1)?;
            refinements += 1;
            if let Ok(r) = refine(data, &m, &current.1, &profile_options) {
                current = (r.model.clone(), r.poses.clone());
                if k == start {
                    at_start = current.clone();
                }
                profile[k] = Some(r);
            }
        }
    }
    // Restart points: local minima of the profile and the lowest points.
    let costs: Vec<f64> = profile
        .iter()
        .map(|r| r.as_ref().map_or(f64::INFINITY, |r| r.cost))
        .collect();
    let mut seeds: Vec<usize> = (0..grid.len())
        .filter(|&k| {
            costs[k].is_finite()
                && (k == 0 || costs[k] <= costs[k - 1])
                && (k + 1 == grid.len() || costs[k] <= costs[k + 1])
        })
        .collect();
    let mut order: Vec<usize> = (0..grid.len()).filter(|&k| costs[k].is_finite()).collect();
    order.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
    seeds.extend(order.into_iter().take(global.restarts));
    seeds.sort_unstable();
    seeds.dedup();
    let mut finals: Vec<Refined> = Vec::new();
    // The plain start competes too.
    refinements += 1;
    if let Ok(r) = refine(data, model, poses, options) {
        finals.push(r);
    }
    for k in seeds {
        if let Some(p) = &profile[k] {
            refinements += 1;
            if let Ok(r) = refine(data, &p.model, &p.poses, options) {
                finals.push(r);
            }
        }
    }
    finals.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let mut minima: Vec<LocalMinimum> = Vec::new();
    for r in &finals {
        let sensor = r.model.sensor_model();
        let (d, k) = (&sensor.distortion, &sensor.intrinsics);
        let distinct = minima.iter().all(|m| {
            (m.l1 - d.l1).abs() > 1e-6 * (1.0 + m.l1.abs()).max(1e-3)
                && (m.cost - r.cost).abs() > 1e-9 * m.cost.max(1e-300)
        });
        if distinct {
            minima.push(LocalMinimum {
                cost: r.cost,
                l1: d.l1,
                k1: d.k1,
                f: k.f,
                cx: k.cx,
                cy: k.cy,
            });
        }
    }
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
        refinements,
    };
    Ok((best, Some(report)))
}
