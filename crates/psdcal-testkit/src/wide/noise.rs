//! The point noise of a wide scenario and its SNR equivalent.
//!
//! Noise-free in 20 % of the scenarios; otherwise Gaussian on each
//! coordinate of each measured point with σ log-uniform in
//! [`SIGMA_RANGE_MM`]. The SNR equivalent is the mapping psdcal's robustness
//! experiment uses, `σ = 0.4 µm · 10^((40 − SNR)/20)`, the sensor-plane noise
//! that the paper's 40 dB residuals (Tables 3–4) imply: σ = 1e-5 mm is
//! 72 dB, 1.26e-3 mm is 30 dB (the noisiest) and 1e-2 mm is 12 dB,
//! so the draw reaches 18 dB beyond it.

use rand::Rng;

/// The range σ is drawn from (log-uniform), mm.
pub const SIGMA_RANGE_MM: (f64, f64) = (1e-5, 1e-2);

/// The fraction of noise-free scenarios.
pub const NOISE_FREE_FRACTION: f64 = 0.2;

/// Draws σ (mm; 0 for a noise-free scenario): one Bernoulli draw, then (if
/// noisy) one uniform draw of log σ.
pub fn draw_sigma<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    if rng.random_bool(NOISE_FREE_FRACTION) {
        return 0.0;
    }
    let (lo, hi) = SIGMA_RANGE_MM;
    rng.random_range(lo.ln()..hi.ln()).exp()
}

/// The SNR (dB) that σ (mm) stands for: `40 − 20 log10(σ / 0.4 µm)`;
/// infinite for σ = 0.
pub fn snr_db_equivalent(sigma_mm: f64) -> f64 {
    if sigma_mm <= 0.0 {
        f64::INFINITY
    } else {
        40.0 - 20.0 * (sigma_mm / 4e-4).log10()
    }
}
