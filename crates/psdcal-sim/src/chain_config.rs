//! The signal chain's parameters ([`ChainConfig`]), their checks, and the
//! noise level of a per-channel SNR (docs/model.md §6): the chain itself is
//! [`crate::signal::SignalChain`].
//!
//! # Defaults ([`ChainConfig::default`])
//!
//! | parameter | default | why |
//! | --- | --- | --- |
//! | `f0_hz` | 1000 | the paper's LED modulation |
//! | `bandwidth_hz` | 600 | the paper's band-pass |
//! | `band_placement` | [`BandPlacement::Geometric`] | unit gain, zero phase at `f0` (the peak) |
//! | `sample_rate_hz` | 20 000 | ≥ 4·(f0 + B/2) = 5.2 kHz with margin; 20 samples a cycle (integer, so whole cycles are whole samples); pre-warping small (`tan(π/20)/(π/20)` = 1.008); 1300 samples a record keep a channel record near 10 µs |
//! | `filter_order` | 2 | the paper gives none; 4 poles, skirts 12 dB/octave away from the band, fast settling |
//! | `record_cycles` | 65 | 65 ms per LED: the transient plus a 40-cycle window |
//! | `transient_cycles` | 25 | the slowest pole of the order-2 filter decays at 1058 /s (τ = 0.945 ms; [`crate::butterworth::BandPass::decay_rate`]; the narrow-band estimate π B sin(π/4) = 1333 /s is optimistic for a band this wide); 25 ms = 26.5 τ leaves ≈ 3e-12 of the switch-on transient, below the 1e-9 exactness of a noise-free record (10 ms would leave ≈ 3e-5, 20 ms ≈ 6e-10). Higher orders settle more slowly (order 4: 531 /s): check `settling_time` and lengthen both counts |
//! | window | 40 cycles, `M` = 800 | `κ ≈ √(2/800)` = 0.05: demodulation gains 10 log10(M/2) = 26 dB over the per-sample SNR |
//! | `demodulation` | [`Demodulation::Iq`] | unbiased, phase-independent |
//! | `amplifier_gain_v_per_a` | 94 088 | the paper's transimpedance (P43), R = 100 kΩ, C = 100 pF, at f0 = 1 kHz (used by [`SignalChain::measure_point`](crate::signal::SignalChain::measure_point) only) |

use psdcal_model::psd::transimpedance_gain;
use serde::{Deserialize, Serialize};

use crate::butterworth::BandPlacement;
use psdcal_signal::SignalError;

/// Largest amplitude or noise standard deviation accepted (any unit): keeps
/// every intermediate sum finite.
pub const MAX_LEVEL: f64 = 1e100;

/// Longest record accepted, samples (50 s at 20 kHz; a chain holds about
/// 48 bytes of tables per sample).
pub const MAX_RECORD_SAMPLES: usize = 1_000_000;

/// How a channel's amplitude is estimated from the filtered record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Demodulation {
    /// Synchronous I/Q (least squares on `cos`, `sin` at f0) over whole
    /// cycles: `Â = √(I² + Q²)`.
    #[default]
    Iq,
    /// `Â = √(2 · mean(y²))` over the same window (biased upwards by the noise
    /// power in the band).
    Rms,
}

/// Parameters of the signal chain; see the [module documentation](self) for
/// the defaults and their justification.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChainConfig {
    /// Modulation frequency `f0`, Hz (centre of the band-pass).
    pub f0_hz: f64,
    /// Band-pass bandwidth `B` between the −3 dB edges, Hz.
    pub bandwidth_hz: f64,
    /// How the band lies around `f0`.
    pub band_placement: BandPlacement,
    /// Sample rate `fs`, Hz; at least `4 · (f0 + B/2)`.
    pub sample_rate_hz: f64,
    /// Butterworth order `N` (`2N` poles), 1 to [`crate::butterworth::MAX_ORDER`].
    pub filter_order: usize,
    /// Record length, cycles of `f0`.
    pub record_cycles: usize,
    /// Cycles skipped at the start of the record (filter transient) before
    /// demodulating; fewer than `record_cycles`.
    pub transient_cycles: usize,
    /// Amplitude estimator.
    pub demodulation: Demodulation,
    /// Gain of the reference channel x1, V/A, used by
    /// [`SignalChain::measure_point`](crate::signal::SignalChain::measure_point) to turn photocurrents into volts.
    pub amplifier_gain_v_per_a: f64,
}

impl Default for ChainConfig {
    fn default() -> Self {
        Self {
            f0_hz: 1000.0,
            bandwidth_hz: 600.0,
            band_placement: BandPlacement::Geometric,
            sample_rate_hz: 20_000.0,
            filter_order: 2,
            record_cycles: 65,
            transient_cycles: 25,
            demodulation: Demodulation::Iq,
            amplifier_gain_v_per_a: transimpedance_gain(100e3, 100e-12, 1000.0),
        }
    }
}

impl ChainConfig {
    /// Checks every parameter; the errors are those listed on [`SignalError`].
    pub fn validate(&self) -> Result<(), SignalError> {
        let positive = |name: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(SignalError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and positive",
                })
            }
        };
        positive("f0_hz", self.f0_hz)?;
        positive("bandwidth_hz", self.bandwidth_hz)?;
        positive("sample_rate_hz", self.sample_rate_hz)?;
        positive("amplifier_gain_v_per_a", self.amplifier_gain_v_per_a)?;
        if self.filter_order == 0 || self.filter_order > crate::butterworth::MAX_ORDER {
            return Err(SignalError::InvalidOrder {
                order: self.filter_order,
                max: crate::butterworth::MAX_ORDER,
            });
        }
        if self.bandwidth_hz >= 2.0 * self.f0_hz {
            return Err(SignalError::BandwidthTooWide {
                bandwidth_hz: self.bandwidth_hz,
                f0_hz: self.f0_hz,
            });
        }
        let minimum_hz = 4.0 * (self.f0_hz + 0.5 * self.bandwidth_hz);
        if self.sample_rate_hz < minimum_hz {
            return Err(SignalError::SampleRateTooLow {
                sample_rate_hz: self.sample_rate_hz,
                minimum_hz,
            });
        }
        if self.record_cycles <= self.transient_cycles {
            return Err(SignalError::RecordTooShort {
                record_cycles: self.record_cycles,
                transient_cycles: self.transient_cycles,
            });
        }
        let samples = (self.record_cycles as f64 * self.sample_rate_hz / self.f0_hz).round();
        // `samples` is finite here (every factor was checked).
        if samples > MAX_RECORD_SAMPLES as f64 {
            return Err(SignalError::RecordTooLong {
                samples,
                max: MAX_RECORD_SAMPLES,
            });
        }
        Ok(())
    }
}

/// The noise standard deviation `σ = V · 10^(−SNR/20) / √2` that gives the
/// per-channel `SNR_dB = 10 log10((V²/2)/σ²)` for the amplitude `V`.
///
/// Errors: `snr_db` not finite; `amplitude` negative, non-finite or above
/// [`MAX_LEVEL`]; `σ` above [`MAX_LEVEL`].
pub fn noise_sigma(amplitude: f64, snr_db: f64) -> Result<f64, SignalError> {
    check_amplitude("channel", amplitude)?;
    sigma_for(amplitude, snr_db)
}

pub(crate) fn check_snr(snr_db: Option<f64>) -> Result<(), SignalError> {
    match snr_db {
        Some(snr_db) if !snr_db.is_finite() => Err(SignalError::NonFiniteSnr { snr_db }),
        _ => Ok(()),
    }
}

pub(crate) fn check_amplitude(channel: &'static str, value: f64) -> Result<(), SignalError> {
    if value.is_finite() && (0.0..=MAX_LEVEL).contains(&value) {
        Ok(())
    } else {
        Err(SignalError::InvalidAmplitude { channel, value })
    }
}

/// `σ` for a checked amplitude.
pub(crate) fn sigma_for(amplitude: f64, snr_db: f64) -> Result<f64, SignalError> {
    check_snr(Some(snr_db))?;
    let sigma = amplitude * std::f64::consts::FRAC_1_SQRT_2 * 10f64.powf(-snr_db / 20.0);
    if sigma.is_finite() && sigma <= MAX_LEVEL {
        Ok(sigma)
    } else {
        Err(SignalError::NoiseTooLarge { sigma })
    }
}
