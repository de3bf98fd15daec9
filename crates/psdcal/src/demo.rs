//! The main job on built-in data: simulate the paper's lens 2 at 40 dB,
//! calibrate it from automatic initialisation, and compare with the truth
//! (each parameter with its σ, and the angle-of-arrival error over held-out
//! directions).

use std::time::Instant;

use psdcal_calib::{calibrate, CalibrateOptions};
use psdcal_model::{ChannelGains, Param};
use psdcal_sim::{simulate, Lens, SimulationOptions, TemplateKind};
use psdcal_study::SimulationData;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::convert;
use crate::error::{Error, Result};

/// One recovered parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoParameter {
    /// The parameter.
    pub param: Param,
    /// Its true value.
    pub truth: f64,
    /// The estimate.
    pub estimate: f64,
    /// The estimate's standard deviation.
    pub std: Option<f64>,
}

/// The demo's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Demo {
    /// The seed.
    pub seed: u64,
    /// Images calibrated.
    pub images: usize,
    /// Points used.
    pub points: usize,
    /// The estimated parameters against the truth.
    pub parameters: Vec<DemoParameter>,
    /// Sum of squared template-plane errors, mm².
    pub residual_mm2: f64,
    /// RMS sensor error, mm.
    pub rms_image_mm: f64,
    /// Iterations.
    pub iterations: usize,
    /// RMS angle-of-arrival error over held-out directions, degrees.
    pub aoa_rms_error_deg: f64,
    /// Wall time, s.
    pub elapsed_s: f64,
}

/// Runs the demo with `seed`.
pub fn demo(seed: u64) -> Result<Demo> {
    let started = Instant::now();
    let options = SimulationOptions {
        lens: Lens::Two,
        snr_db: Some(40.0),
        images: 9,
        template: TemplateKind::Scatter14,
        ..SimulationOptions::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sim = simulate(&options, &mut rng)?;
    let data = sim.calibration_data();
    let result = calibrate(&data, &CalibrateOptions::default()).map_err(Error::Calibrate)?;
    let aoa_rms_error_deg = sim
        .aoa_rms_error(&convert::model(&result), &ChannelGains::UNIT)
        .to_degrees();
    let report = convert::fit_report(&result);
    Ok(Demo {
        seed,
        images: data.images.len(),
        points: data.point_count(),
        parameters: Param::ALL
            .into_iter()
            .zip(&report.parameters)
            .filter(|(_, row)| row.std.is_some())
            .map(|(p, row)| DemoParameter {
                param: p,
                truth: sim.truth.get(p),
                estimate: row.value,
                std: row.std,
            })
            .collect(),
        residual_mm2: report.residual_mm2,
        rms_image_mm: report.rms_image_mm,
        iterations: report.iterations,
        aoa_rms_error_deg,
        elapsed_s: started.elapsed().as_secs_f64(),
    })
}
