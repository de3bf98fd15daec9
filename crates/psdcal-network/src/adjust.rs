//! The bundle adjustment's passes, the dropped frames and the covariance
//! (docs/network.md):
//!
//! 1. the point noise `σ` is first taken robustly from the start's
//!    residuals: for 2-D Gaussian residuals of σ per axis, `‖r‖²` has median
//!    `2 ln 2 · σ²`;
//! 2. one pass under the Cauchy loss (scale 3σ), stopped once an iteration
//!    moves the cost by less than 10⁻³ of itself (it only has to tell the
//!    bad frames apart), then `σ` re-estimated by the median; a frame with
//!    a sighting beyond `outlier_sigma · σ` is dropped (a wrong or reflected
//!    LED), a static LED's sighting too;
//! 3. a least-squares pass on what is kept (to a χ² within 10⁻⁸ of its
//!    minimum), `σ² = Σ‖r‖² / (2n − unknowns)`, repeated when `σ` moved by
//!    more than 5 % (it weighs the prior), three passes at most;
//! 4. the covariance of the global block (sensor poses and lenses, the
//!    lab prior included) is `S⁻¹` of the whitened normal equations at the
//!    solution, with `S` the Schur complement of the wand poses.

use nalgebra::{DMatrix, Vector2};
use psdcal_model::Pose;
use psdcal_solver::inverse_scaled;
use psdcal_solver::solver::{
    normal_equations as linearize, solve, RobustLoss, SolverOptions, SolverReport,
};

use crate::data::{Led, NetworkData};
use crate::problem::{Layout, NetworkProblem, NetworkState};
use crate::NetworkError;

/// Options of the adjustment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdjustOptions {
    /// A sighting farther than this many σ drops its frame.
    pub outlier_sigma: f64,
    /// Cauchy scale, in σ.
    pub robust_sigma: f64,
    /// Iteration budget of each pass.
    pub max_iterations: usize,
}

impl Default for AdjustOptions {
    fn default() -> Self {
        Self {
            outlier_sigma: 5.0,
            robust_sigma: 3.0,
            max_iterations: 100,
        }
    }
}

/// Why a frame was not used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DropReason {
    /// Too few of its LEDs were seen by two sensors to place the wand.
    NotPlaced,
    /// A sighting disagreed with the others beyond the outlier threshold.
    Outlier,
}

/// The adjusted network.
#[derive(Debug, Clone)]
pub struct Adjusted {
    /// The solution.
    pub state: NetworkState,
    /// Frame index of each block.
    pub frames: Vec<usize>,
    /// Observations per block.
    pub by_block: Vec<Vec<usize>>,
    /// Static observations kept.
    pub statics: Vec<usize>,
    /// Dropped frames and why.
    pub dropped: Vec<(usize, DropReason)>,
    /// Static-frame sightings dropped as outliers.
    pub dropped_statics: Vec<usize>,
    /// The point noise σ, mm.
    pub sigma_mm: f64,
    /// Covariance of the global block (layout order).
    pub covariance: DMatrix<f64>,
    /// The layout of the global block.
    pub layout: Layout,
    /// The last pass's solver report.
    pub report: SolverReport,
    /// Passes × iterations, all passes.
    pub iterations: usize,
}

/// The blocks being fitted: frame, observations and start (anchor) of each.
struct Blocks {
    frames: Vec<usize>,
    by_block: Vec<Vec<usize>>,
    anchors: Vec<Pose>,
}

impl Blocks {
    /// Drops the blocks flagged `bad` (and their wand poses in `state`).
    fn drop_flagged(
        &mut self,
        bad: &[bool],
        state: &mut NetworkState,
        dropped: &mut Vec<(usize, DropReason)>,
    ) {
        let mut k = 0;
        let mut keep = |_: &_| {
            k += 1;
            !bad[k - 1]
        };
        let frames = std::mem::take(&mut self.frames);
        for (f, b) in frames.iter().zip(bad) {
            if *b {
                dropped.push((*f, DropReason::Outlier));
            }
        }
        self.frames = frames.into_iter().filter(|f| keep(f)).collect();
        let mut k = 0;
        self.by_block.retain(|_| {
            k += 1;
            !bad[k - 1]
        });
        let mut k = 0;
        self.anchors.retain(|_| {
            k += 1;
            !bad[k - 1]
        });
        let mut k = 0;
        state.wands.retain(|_| {
            k += 1;
            !bad[k - 1]
        });
    }
}

/// Runs the passes from `sensors` and `wands` (module documentation).
pub fn adjust(
    data: &NetworkData,
    sensors: &[Pose],
    wands: &[Option<Pose>],
    options: &AdjustOptions,
) -> Result<Adjusted, NetworkError> {
    let layout = Layout::new(data, data.frame_leds.is_empty());
    let mut dropped: Vec<(usize, DropReason)> = Vec::new();
    let mut frames = Vec::new();
    let mut block_of = vec![None; data.frames.len()];
    for (f, w) in wands.iter().enumerate() {
        match w {
            Some(_) => {
                block_of[f] = Some(frames.len());
                frames.push(f);
            }
            None => dropped.push((f, DropReason::NotPlaced)),
        }
    }
    let mut state = NetworkState {
        sensors: sensors.to_vec(),
        models: data.sensors.iter().map(|s| s.model.clone()).collect(),
        wands: frames
            .iter()
            .map(|&f| wands[f].unwrap_or_else(Pose::identity))
            .collect(),
    };
    let mut by_block = vec![Vec::new(); frames.len()];
    let mut statics = Vec::new();
    for (k, o) in data.observations.iter().enumerate() {
        match o.led {
            Led::Wand(_) => {
                if let Some(b) = block_of.get(o.frame).copied().flatten() {
                    by_block[b].push(k);
                }
            }
            Led::Frame(_) => statics.push(k),
        }
    }
    let mut blocks = Blocks {
        frames,
        by_block,
        anchors: state.wands.clone(),
    };
    let problem_at = |blocks: &Blocks, statics: &[usize], sigma: f64, state: &NetworkState| {
        NetworkProblem::new(
            data,
            &layout,
            blocks.by_block.clone(),
            statics.to_vec(),
            sigma,
            &blocks.anchors,
            &state.models,
        )
    };
    // Sightings that cannot be projected at the start (behind a sensor)
    // count as outliers of their frame.
    let probe = problem_at(&blocks, &statics, 1.0, &state)?;
    let mut bad = vec![false; blocks.frames.len()];
    let mut start_r2 = Vec::new();
    for (b, obs) in blocks.by_block.iter().enumerate() {
        for &k in obs {
            match probe.residual_mm(&state, Some(b), k) {
                Ok(r) => start_r2.push(r.norm_squared()),
                Err(_) => bad[b] = true,
            }
        }
    }
    statics.retain(|&k| probe.residual_mm(&state, None, k).is_ok());
    blocks.drop_flagged(&bad, &mut state, &mut dropped);
    let mut sigma = robust_sigma(&mut start_r2).max(1e-9);
    let mut iterations = 0;
    let robust = SolverOptions {
        max_iterations: options.max_iterations,
        cost_tolerance: 1e-3,
        step_tolerance: 1e-6,
        robust: Some(RobustLoss::Cauchy {
            scale: options.robust_sigma,
        }),
        ..SolverOptions::default()
    };
    let problem = problem_at(&blocks, &statics, sigma, &state)?;
    let solution = solve(&problem, state.clone(), &robust)?;
    iterations += solution.report.iterations;
    state = solution.state;
    let problem = problem_at(&blocks, &statics, sigma, &state)?;
    sigma = robust_sigma(&mut residuals_r2(&problem, &state)?).max(1e-9);
    // Outliers.
    let limit = options.outlier_sigma * sigma;
    let mut bad = vec![false; blocks.frames.len()];
    for (b, obs) in blocks.by_block.iter().enumerate() {
        for &k in obs {
            if !problem
                .residual_mm(&state, Some(b), k)
                .is_ok_and(|r| r.norm() <= limit)
            {
                bad[b] = true;
            }
        }
    }
    let mut dropped_statics = Vec::new();
    statics.retain(|&k| {
        let ok = problem
            .residual_mm(&state, None, k)
            .is_ok_and(|r| r.norm() <= limit);
        if !ok {
            dropped_statics.push(k);
        }
        ok
    });
    blocks.drop_flagged(&bad, &mut state, &mut dropped);
    if blocks.frames.is_empty() {
        return Err(NetworkError::TooFewFrames {
            usable: 0,
            needed: 1,
        });
    }
    let ls = SolverOptions {
        max_iterations: options.max_iterations,
        // χ² within 1e-8 of itself: the estimate within a small fraction
        // of its σ of the minimum.
        cost_tolerance: 1e-8,
        step_tolerance: 1e-10,
        ..SolverOptions::default()
    };
    let mut report = None;
    for pass in 0..3 {
        let problem = problem_at(&blocks, &statics, sigma, &state)?;
        let solution = solve(&problem, state.clone(), &ls)?;
        iterations += solution.report.iterations;
        state = solution.state;
        report = Some(solution.report);
        let (ss, n) = residual_sum(&problem, &state)?;
        let unknowns = layout.len + 6 * blocks.frames.len();
        let dof = (2 * n).saturating_sub(unknowns).max(1);
        let new_sigma = (ss / dof as f64).sqrt().max(1e-12);
        let moved = (new_sigma / sigma - 1.0).abs();
        sigma = new_sigma;
        if moved < 0.05 || pass == 2 {
            break;
        }
    }
    let problem = problem_at(&blocks, &statics, sigma, &state)?;
    let ne = linearize(&problem, &state, None)?;
    // The wand poses' own covariances are not wanted: S⁻¹ alone.
    let covariance = ne
        .schur_complement()
        .and_then(|s| inverse_scaled(&s))
        .ok_or(NetworkError::Numerical {
            stage: "covariance",
            reason: "the network's information matrix is singular (a sensor or the gauge is not \
                 determined by the data)"
                .into(),
        })?;
    dropped.sort_unstable();
    Ok(Adjusted {
        state,
        frames: blocks.frames,
        by_block: blocks.by_block,
        statics,
        dropped,
        dropped_statics,
        sigma_mm: sigma,
        covariance,
        layout,
        report: report.expect("at least one pass"),
        iterations,
    })
}

/// σ from squared 2-D residual norms by their median (module
/// documentation); sorts the slice.
pub fn robust_sigma(r2: &mut [f64]) -> f64 {
    if r2.is_empty() {
        return 0.0;
    }
    (crate::start::median(r2) / (2.0 * std::f64::consts::LN_2)).sqrt()
}

fn residuals_r2(
    problem: &NetworkProblem<'_>,
    state: &NetworkState,
) -> Result<Vec<f64>, NetworkError> {
    let mut out = Vec::new();
    for (b, obs) in problem.blocks().iter().enumerate() {
        for &k in obs {
            let r: Vector2<f64> =
                problem
                    .residual_mm(state, Some(b), k)
                    .map_err(|e| NetworkError::Numerical {
                        stage: "bundle adjustment",
                        reason: e.to_string(),
                    })?;
            out.push(r.norm_squared());
        }
    }
    Ok(out)
}

/// `Σ ‖r‖²` (mm²) over every sighting and their count.
fn residual_sum(
    problem: &NetworkProblem<'_>,
    state: &NetworkState,
) -> Result<(f64, usize), NetworkError> {
    let mut r2 = residuals_r2(problem, state)?;
    for &k in problem.statics() {
        if let Ok(r) = problem.residual_mm(state, None, k) {
            r2.push(r.norm_squared());
        }
    }
    Ok((r2.iter().sum(), r2.len()))
}
