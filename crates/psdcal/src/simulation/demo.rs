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

use crate::base::error::{Error, Result};
use crate::base::summary::Summary;
use crate::calibration::convert;

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

impl Demo {
    /// The demo's summary: the parameters against the truth (error over
    /// σ), the residual and the angle-of-arrival error.
    pub fn summary(&self) -> Summary {
        let json = serde_json::json!({
            "seed": self.seed,
            "lens": 2,
            "snr_db": 40.0,
            "images": self.images,
            "points": self.points,
            "parameters": self.parameters.iter().map(|p| serde_json::json!({
                "name": p.param.name(), "truth": p.truth, "estimate": p.estimate, "std": p.std,
            })).collect::<Vec<_>>(),
            "residual_mm2": self.residual_mm2,
            "rms_image_mm": self.rms_image_mm,
            "iterations": self.iterations,
            "aoa_rms_error_deg": self.aoa_rms_error_deg,
            "elapsed_s": self.elapsed_s,
        });
        let mut text = format!(
            "psdcal demo: the paper's lens 2 (f = 8 mm, k1 = 1e-2, k2 = 3e-5, centre (0.5, -0.7) mm),\n\
             40 dB SNR per channel through the simulated signal chain, {} template poses\n\
             of the 14-LED template ({} points), seed {}; calibrated from automatic initialisation.\n\n\
             parameter         truth        estimate           std    error/std\n",
            self.images, self.points, self.seed
        );
        for p in &self.parameters {
            let z = p
                .std
                .filter(|s| *s > 0.0)
                .map_or("".into(), |s| format!("{:+.2}", (p.estimate - p.truth) / s));
            text.push_str(&format!(
                "{:<6} {:>15.6e} {:>15.6e} {:>13.3e} {:>12}\n",
                p.param.name(),
                p.truth,
                p.estimate,
                p.std.unwrap_or(0.0),
                z
            ));
        }
        text.push_str(&format!(
            "\nresidual {:.4e} mm², RMS {:.3e} mm on the sensor, {} iterations\n\
             angle-of-arrival error over held-out directions: {:.4}° RMS ({:.1} mm at 5 m)\n\
             done in {:.2} s. Next: psdcal simulate --out sim, psdcal calibrate, psdcal study all\n",
            self.residual_mm2,
            self.rms_image_mm,
            self.iterations,
            self.aoa_rms_error_deg,
            5000.0 * self.aoa_rms_error_deg.to_radians(),
            self.elapsed_s
        ));
        Summary::new(text, json)
    }
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
