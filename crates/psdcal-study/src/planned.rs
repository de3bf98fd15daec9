//! Planned against random poses (issue 16's acceptance, docs/model.md
//! §8.6): seeded simulations calibrated with `calibrate`'s defaults, once at
//! the study's random poses and once at a plan's poses.
//!
//! Trial `k` seeds ChaCha8 with `seed + k` twice: once for the random data
//! set (poses, gains, noise, as the study draws them) and once for the
//! planned one (gains, noise). Each calibration is scored by the simulator's
//! held-out RMS AoA error ([`psdcal_sim::Simulation::aoa_rms_error`]: a 9 × 9
//! grid of directions over 80 % of the sensor). The plan's prediction on that
//! same grid (its points measured through the true model) is what the
//! simulated spread `√(mean over trials of the squared RMS error)` is
//! compared with.
//!
//! With the gains ([`planned_errors`] with `fit_gains`, [`simulation_setup`]
//! with `gains`): the data carry the study's gain imbalance, `calibrate`
//! estimates the gains with the optics (`--fit f,cx,cy,k1,k2,gains`), the
//! held-out error divides the estimated gains out, and the plan's setup
//! frees `g_x2, g_y1, g_y2` at unit nominal gains.

use nalgebra::Vector2;
use psdcal_calib::plan::{AoaMetric, PlanSetup};
use psdcal_calib::{calibrate, CalibrateOptions};
use psdcal_model::{ChannelGains, Model, Pose};
use psdcal_sim::{simulate, simulate_at, SimulationOptions};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::SimulationData;

/// One trial's RMS AoA errors, rad (`None`: the calibration failed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanTrial {
    /// At the study's random poses.
    pub random: Option<f64>,
    /// At the planned poses.
    pub planned: Option<f64>,
}

/// Runs `trials` paired trials from `seed` (module documentation), the
/// gains estimated too when `fit_gains`.
pub fn compare_poses(
    options: &SimulationOptions,
    planned: &[Pose],
    trials: usize,
    seed: u64,
    fit_gains: bool,
) -> Vec<PlanTrial> {
    let with_plan = planned_errors(options, planned, trials, seed, fit_gains);
    (0..trials)
        .into_par_iter()
        .zip(with_plan)
        .map(|(k, planned)| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed + k as u64);
            PlanTrial {
                random: simulate(options, &mut rng)
                    .ok()
                    .and_then(|sim| score(&sim, fit_gains)),
                planned,
            }
        })
        .collect()
}

/// `sim` calibrated with `calibrate`'s defaults (the gains estimated too
/// when `fit_gains`), its held-out RMS AoA error (rad).
fn score(sim: &psdcal_sim::Simulation, fit_gains: bool) -> Option<f64> {
    let mut options = CalibrateOptions::default();
    options.refine.fit_gains = fit_gains;
    let result = calibrate(&sim.calibration_data(), &options).ok()?;
    let gains = result.gains.unwrap_or(ChannelGains::UNIT);
    Some(sim.aoa_rms_error(&result.sensor_model(), &gains))
}

/// The held-out RMS AoA errors (rad) of `trials` simulations at the poses
/// `planned` (trial `k` seeded with `seed + k`), each calibrated with
/// `calibrate`'s defaults, the gains estimated too when `fit_gains`
/// (`None`: the simulation or calibration failed).
pub fn planned_errors(
    options: &SimulationOptions,
    planned: &[Pose],
    trials: usize,
    seed: u64,
    fit_gains: bool,
) -> Vec<Option<f64>> {
    (0..trials)
        .into_par_iter()
        .map(|k| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed + k as u64);
            score(&simulate_at(options, planned, &mut rng).ok()?, fit_gains)
        })
        .collect()
}

/// The simulator's held-out grid measured through `model` (the points
/// [`psdcal_sim::Simulation::aoa_rms_error`] scores).
pub fn held_out_points(model: &Model, options: &SimulationOptions) -> Vec<Vector2<f64>> {
    let g = &options.geometry;
    (0..9)
        .flat_map(|i| (0..9).map(move |j| (i, j)))
        .filter_map(|(i, j)| {
            let ideal = Vector2::new(
                0.4 * g.lx * (i as f64 / 4.0 - 1.0),
                0.4 * g.ly * (j as f64 / 4.0 - 1.0),
            );
            model.measured_from_ideal(&ideal).ok()
        })
        .collect()
}

/// The predicted RMS AoA σ (rad) of `poses` on the held-out grid.
pub fn predicted_rms(
    setup: &PlanSetup,
    poses: &[Pose],
    options: &SimulationOptions,
) -> Result<f64, psdcal_calib::CalibError> {
    let metric = AoaMetric::new(
        &setup.model,
        &setup.free,
        held_out_points(&setup.model, options),
    )?;
    let p = psdcal_calib::plan::predict(setup, poses, 1)?;
    Ok(metric.mean_square(p.covariance.matrix()).max(0.0).sqrt())
}

/// The median of the values present.
pub fn median(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let mut v: Vec<f64> = values.flatten().collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// `√(mean of squares)` of the values present.
pub fn rms(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let v: Vec<f64> = values.flatten().collect();
    (!v.is_empty()).then(|| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt())
}

/// The planner's view of a simulation's sensor: its true model as the
/// nominal one, `f, cx, cy, k1, k2` freed on the template plane (the
/// defaults of `calibrate`) — and the gains `g_x2, g_y1, g_y2` at unit
/// nominal values when `gains` — the point noise of the simulation's chain
/// at its SNR (none without one: `ρ = 0` gives a zero covariance).
pub fn simulation_setup(options: &SimulationOptions, gains: bool) -> PlanSetup {
    let mut truth = options.lens.model();
    if options.psd_distortion {
        truth.distortion.l1 = psdcal_model::SensorModel::PAPER_L1;
    }
    let relative_noise = options
        .snr_db
        .and_then(|snr| options.chain.amplitude_std(1.0, snr).ok())
        .unwrap_or(0.0);
    let refine = psdcal_calib::RefineOptions {
        fit_gains: gains,
        ..psdcal_calib::RefineOptions::default()
    };
    let model = if gains {
        Model::standard_with_gains(&truth, options.geometry, &ChannelGains::UNIT)
    } else {
        Model::standard(&truth)
    };
    PlanSetup {
        model,
        template: options.template.template().leds,
        geometry: options.geometry,
        free: refine.free_names(),
        cost: psdcal_model::CostKind::Template,
        relative_noise,
    }
}
