//! A simulated lensless raster scan of the bare PSD (docs/model.md §8.3,
//! scan.csv in docs/formats.md): the stage steps a light spot over the
//! active area; the PSD reports it through its non-linearity
//! ([`crate::nonlinearity`]) and the signal chain (§6).
//!
//! Positions: `n = ⌊L/step⌋ + 1` per axis, centred, `step` apart (0.25 mm on
//! 9 mm: 37 × 37 covering ±4.5 mm). At each commanded position `c` the
//! spot is really at `s = c + N(0, σ_stage²)` per axis; the PSD reports
//! `r = s + E(s)` (clamped to the active area, where a real PSD saturates);
//! the four electrode currents of `r` (photocurrent `I0`, amplifier gain of
//! the chain) go through the chain at the per-channel SNR, and the measured
//! point is computed from the demodulated amplitudes. A scan row is
//! (`c`, amplitudes, measured point).

use nalgebra::Vector2;
use psdcal_model::psd::{electrode_currents, impact_point};
use psdcal_model::{Amplitudes, PsdGeometry};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::nonlinearity::PsdNonlinearity;
use crate::signal::SignalChain;
use crate::simulate::DEFAULT_PHOTOCURRENT_A;
use crate::SimError;

/// Most positions per axis.
pub const MAX_SCAN_SIDE: usize = 401;

/// What to scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanOptions {
    /// Raster step, mm.
    pub step_mm: f64,
    /// Positioning error of the stage per axis (σ), mm.
    pub stage_sigma_mm: f64,
    /// Per-channel SNR, dB (`None`: no noise).
    pub snr_db: Option<f64>,
    /// Whether the PSD has the non-linearity of [`PsdNonlinearity`].
    pub nonlinearity: bool,
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// Spot photocurrent, A.
    pub photocurrent_a: f64,
    /// The signal chain.
    pub chain: SignalChain,
}

impl Default for ScanOptions {
    /// 0.25 mm raster, σ 0.3 µm, 50 dB, with the non-linearity.
    fn default() -> Self {
        Self {
            step_mm: 0.25,
            stage_sigma_mm: 3e-4,
            snr_db: Some(50.0),
            nonlinearity: true,
            geometry: PsdGeometry::default(),
            photocurrent_a: DEFAULT_PHOTOCURRENT_A,
            chain: SignalChain::default(),
        }
    }
}

/// One scan position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanSample {
    /// Commanded stage position, mm.
    pub stage: Vector2<f64>,
    /// Where the spot really was, mm.
    pub spot: Vector2<f64>,
    /// Demodulated amplitudes, V.
    pub amplitudes: Amplitudes,
    /// Measured point from them, mm.
    pub measured: Vector2<f64>,
}

/// The raster positions of one axis of side `l`.
fn axis(l: f64, step: f64) -> Vec<f64> {
    let n = ((l / step) * (1.0 + 1e-12)).floor() as usize + 1;
    let start = -0.5 * step * (n - 1) as f64;
    (0..n).map(|i| start + step * i as f64).collect()
}

/// Simulates a scan (module documentation), row by row along x then y.
pub fn simulate_scan(
    options: &ScanOptions,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<ScanSample>, SimError> {
    let g = options.geometry;
    let step = options.step_mm;
    let sides_ok = step.is_finite()
        && step > 0.0
        && (g.lx / step) < MAX_SCAN_SIDE as f64
        && (g.ly / step) < MAX_SCAN_SIDE as f64;
    if !sides_ok {
        return Err(SimError::Options(format!(
            "a scan step of {step} mm; expected a positive step giving at most {MAX_SCAN_SIDE} \
             positions per side"
        )));
    }
    let sigma = options.stage_sigma_mm;
    let stage_noise = Normal::new(0.0, sigma)
        .ok()
        .filter(|_| sigma.is_finite() && sigma >= 0.0 && sigma < 0.1 * step)
        .ok_or_else(|| {
            SimError::Options(format!(
                "a stage σ of {sigma} mm; expected 0 or more, below a tenth of the step"
            ))
        })?;
    let nl = PsdNonlinearity::new(g);
    let gain = options.chain.config().amplifier_gain_v_per_a;
    let (hx, hy) = (0.5 * g.lx, 0.5 * g.ly);
    let mut out = Vec::new();
    for &y in &axis(g.ly, step) {
        for &x in &axis(g.lx, step) {
            let stage = Vector2::new(x, y);
            let spot = stage + Vector2::new(stage_noise.sample(rng), stage_noise.sample(rng));
            let mut reported = if options.nonlinearity {
                nl.reported(&spot)
            } else {
                spot
            };
            reported.x = reported.x.clamp(-hx, hx);
            reported.y = reported.y.clamp(-hy, hy);
            let currents = electrode_currents(&g, &reported, options.photocurrent_a);
            let clean = Amplitudes {
                vx1: currents.vx1 * gain,
                vx2: currents.vx2 * gain,
                vy1: currents.vy1 * gain,
                vy2: currents.vy2 * gain,
            };
            let amplitudes = match options.snr_db {
                None => clean,
                Some(snr) => options.chain.measure(&clean, Some(snr), rng)?,
            };
            let measured = impact_point(&g, &amplitudes)?;
            out.push(ScanSample {
                stage,
                spot,
                amplitudes,
                measured,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn a_noise_free_scan_measures_the_nonlinearity_exactly() {
        let options = ScanOptions {
            step_mm: 1.5,
            stage_sigma_mm: 0.0,
            snr_db: None,
            ..ScanOptions::default()
        };
        let scan = simulate_scan(&options, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(scan.len(), 49);
        assert_eq!(scan[0].stage, Vector2::new(-4.5, -4.5));
        let nl = PsdNonlinearity::new(PsdGeometry::default());
        for s in &scan {
            assert!((s.measured - nl.reported(&s.stage)).norm() < 1e-12);
        }
        assert!(simulate_scan(
            &ScanOptions {
                step_mm: 0.0,
                ..options
            },
            &mut ChaCha8Rng::seed_from_u64(1)
        )
        .is_err());
    }
}
