//! Pose planning (docs/model.md §8.6): which template poses make the most
//! accurate calibration, predicted before any data exist.
//!
//! The prediction is the covariance of the estimate `calibrate` computes —
//! the unweighted least-squares fit of the freed parameters and every pose,
//! on the template plane by default — linearised at the nominal model with
//! the point noise the SNR gives ([`information`]), `C = S⁻¹ M S⁻¹`, and
//! propagated to the angle of arrival over a grid of the active area
//! ([`aoa_metric`]). A plan draws admissible candidate poses from a seed
//! ([`candidates`]) and picks `N` of them by greedy selection and exchange
//! ([`select`]). [`plan_next`] picks the one pose that most lowers the AoA
//! σ of a calibration from poses already taken (their `S_i`, `M_i` at the
//! calibration's model are the starting sums).
//!
//! The channel gains are modelled like any freed parameter: a `PlanSetup`
//! whose model owns a gains stage (`Model::standard_with_gains`) with
//! `g_x2, g_y1, g_y2` among `free` predicts `calibrate --fit …,gains`
//! (`g_x1 = 1`, as the calibration fixes it); the gains enter through the
//! electrode amplitudes of each LED ([`information`], [`aoa_metric`]).

pub mod aoa_metric;
pub mod candidates;
pub mod information;
pub mod select;

use nalgebra::{DMatrix, Vector2};
use psdcal_model::{ParameterCovariance, Pose, MIN_IMAGES};
use rayon::prelude::*;

pub use aoa_metric::{cell_centres, AoaMetric};
pub use candidates::{draw_candidates, Candidate, PoseRanges, MAX_TILT_DEG};
pub use information::{pose_information, PlanSetup, PoseInformation};
pub use select::{Objective, Scorer};

use crate::CalibError;

/// How to plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Number of poses.
    pub images: usize,
    /// The mount's ranges.
    pub ranges: PoseRanges,
    /// Candidate poses drawn.
    pub candidates: usize,
    /// Seed of the candidates.
    pub seed: u64,
    /// What is minimised.
    pub objective: Objective,
    /// The AoA grid has `grid × grid` cells over the active area.
    pub grid: usize,
}

impl Default for PlanOptions {
    /// Nine poses, default ranges, 1 500 candidates, seed 1, RMS, 9 × 9 grid.
    fn default() -> Self {
        Self {
            images: 9,
            ranges: PoseRanges::default(),
            candidates: 1500,
            seed: 1,
            objective: Objective::Rms,
            grid: 9,
        }
    }
}

/// The predicted uncertainty of a calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// The freed parameters' covariance.
    pub covariance: ParameterCovariance,
    /// The grid's measured points, mm.
    pub grid: Vec<Vector2<f64>>,
    /// The AoA σ at each grid point, rad.
    pub sigma: Vec<f64>,
    /// Its RMS over the grid, rad.
    pub rms: f64,
    /// Its largest value, rad.
    pub max: f64,
}

/// A plan: the chosen poses and what they predict.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The poses, in the order chosen.
    pub poses: Vec<Candidate>,
    /// The prediction with them (and the prior's images, for `plan_next`).
    pub prediction: Prediction,
    /// The prior's RMS and largest AoA σ (rad), for `plan_next`.
    pub before: Option<(f64, f64)>,
    /// How many admissible candidates were drawn.
    pub candidates: usize,
}

fn information_of(setup: &PlanSetup, poses: &[Pose]) -> Result<Vec<PoseInformation>, CalibError> {
    poses
        .par_iter()
        .map(|pose| pose_information(setup, pose))
        .collect()
}

fn prediction(
    setup: &PlanSetup,
    metric: &AoaMetric,
    s: &DMatrix<f64>,
    m: &DMatrix<f64>,
) -> Result<Prediction, CalibError> {
    let c = information::parameter_covariance(s, m).ok_or_else(|| CalibError::Degenerate {
        reason: format!(
            "these poses do not determine {}: allow more tilt (--tilt-max) or a wider --distance range, or fix a parameter",
            setup.free.join(", ")
        ),
    })?;
    let sigma = metric.sigma_map(&c);
    let rms = metric.mean_square(&c).max(0.0).sqrt();
    let max = sigma.iter().copied().fold(0.0, f64::max);
    let covariance =
        ParameterCovariance::new(setup.free.clone(), c).map_err(|e| CalibError::Numerical {
            stage: "plan",
            reason: e.to_string(),
        })?;
    Ok(Prediction {
        covariance,
        grid: metric.points.clone(),
        sigma,
        rms,
        max,
    })
}

/// The predicted uncertainty of a calibration from `poses`.
pub fn predict(setup: &PlanSetup, poses: &[Pose], grid: usize) -> Result<Prediction, CalibError> {
    let metric = AoaMetric::new(
        &setup.model,
        &setup.free,
        cell_centres(&setup.geometry, grid),
    )?;
    let infos = information_of(setup, poses)?;
    let scorer = Scorer::new(&infos, &metric, Objective::Rms, None);
    let (s, m) = scorer.sums(&(0..infos.len()).collect::<Vec<_>>());
    prediction(setup, &metric, &s, &m)
}

fn candidates_for(
    setup: &PlanSetup,
    options: &PlanOptions,
    needed: usize,
) -> Result<Vec<Candidate>, CalibError> {
    let found = draw_candidates(
        setup,
        &options.ranges,
        options.candidates.max(needed),
        options.seed,
    )?;
    if found.len() < needed {
        let (lo, hi) = candidates::distance_range(setup, &options.ranges)?;
        return Err(CalibError::InvalidInput {
            reason: format!(
                "only {} pose(s) at distances {lo:.0}–{hi:.0} mm with tilt up to {:.1}° keep every LED {} mm inside \
                 the active area ({} needed): widen --distance (larger distances shrink the template's image), \
                 or lower --tilt-max or --margin",
                found.len(),
                options.ranges.tilt_max.to_degrees(),
                options.ranges.margin_mm,
                needed
            ),
        });
    }
    Ok(found)
}

/// Plans `options.images` poses (module documentation).
pub fn plan(setup: &PlanSetup, options: &PlanOptions) -> Result<Plan, CalibError> {
    if options.images < MIN_IMAGES {
        return Err(CalibError::TooFewImages {
            usable: options.images,
            needed: MIN_IMAGES,
        });
    }
    if options.grid == 0 {
        return Err(CalibError::InvalidInput {
            reason: "the AoA grid needs at least one cell".into(),
        });
    }
    let found = candidates_for(setup, options, options.images)?;
    let metric = AoaMetric::new(
        &setup.model,
        &setup.free,
        cell_centres(&setup.geometry, options.grid),
    )?;
    let poses: Vec<Pose> = found.iter().map(|c| c.pose).collect();
    let infos = information_of(setup, &poses)?;
    let scorer = Scorer::new(&infos, &metric, options.objective, None);
    let chosen = scorer.select(options.images);
    let (s, m) = scorer.sums(&chosen);
    Ok(Plan {
        poses: chosen.iter().map(|&i| found[i]).collect(),
        prediction: prediction(setup, &metric, &s, &m)?,
        before: None,
        candidates: found.len(),
    })
}

/// The one pose that most lowers the AoA σ of a calibration from the poses
/// `taken` (module documentation); `before` is their own prediction.
pub fn plan_next(
    setup: &PlanSetup,
    options: &PlanOptions,
    taken: &[Pose],
) -> Result<Plan, CalibError> {
    let metric = AoaMetric::new(
        &setup.model,
        &setup.free,
        cell_centres(&setup.geometry, options.grid.max(1)),
    )?;
    let taken_infos = information_of(setup, taken)?;
    let p = setup.free.len();
    let (mut s0, mut m0) = (DMatrix::zeros(p, p), DMatrix::zeros(p, p));
    for info in &taken_infos {
        s0 += &info.schur;
        m0 += &info.noise;
    }
    let before = prediction(setup, &metric, &s0, &m0)?;
    let found = candidates_for(setup, options, 1)?;
    let poses: Vec<Pose> = found.iter().map(|c| c.pose).collect();
    let infos = information_of(setup, &poses)?;
    let scorer = Scorer::new(&infos, &metric, options.objective, Some((s0, m0)));
    let chosen = scorer.select(1);
    let (s, m) = scorer.sums(&chosen);
    Ok(Plan {
        poses: chosen.iter().map(|&i| found[i]).collect(),
        prediction: prediction(setup, &metric, &s, &m)?,
        before: Some((before.rms, before.max)),
        candidates: found.len(),
    })
}
