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

/// Runs `trials` paired trials from `seed` (module documentation).
pub fn compare_poses(
    options: &SimulationOptions,
    planned: &[Pose],
    trials: usize,
    seed: u64,
) -> Vec<PlanTrial> {
    let run = |sim: Result<psdcal_sim::Simulation, psdcal_sim::SimError>| -> Option<f64> {
        let sim = sim.ok()?;
        let result = calibrate(&sim.calibration_data(), &CalibrateOptions::default()).ok()?;
        Some(sim.aoa_rms_error(&result.sensor_model(), &ChannelGains::UNIT))
    };
    (0..trials)
        .into_par_iter()
        .map(|k| {
            let s = seed + k as u64;
            PlanTrial {
                random: run(simulate(options, &mut ChaCha8Rng::seed_from_u64(s))),
                planned: run(simulate_at(
                    options,
                    planned,
                    &mut ChaCha8Rng::seed_from_u64(s),
                )),
            }
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
/// defaults of `calibrate`), the point noise of the simulation's chain at
/// its SNR (none without one: `ρ = 0` gives a zero covariance).
pub fn simulation_setup(options: &SimulationOptions) -> PlanSetup {
    let mut truth = options.lens.model();
    if options.psd_distortion {
        truth.distortion.l1 = psdcal_model::SensorModel::PAPER_L1;
    }
    let relative_noise = options
        .snr_db
        .and_then(|snr| options.chain.amplitude_std(1.0, snr).ok())
        .unwrap_or(0.0);
    PlanSetup {
        model: Model::standard(&truth),
        template: options.template.template().leds,
        geometry: options.geometry,
        free: psdcal_calib::RefineOptions::default().free_names(),
        cost: psdcal_model::CostKind::Template,
        relative_noise,
    }
}
