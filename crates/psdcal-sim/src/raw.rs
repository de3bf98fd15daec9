//! Raw recordings as a data-acquisition card would record them
//! (docs/model.md §8 "Demodulation"): the four electrode channels sampled at
//! `fs` while the LEDs are switched (time multiplexing: one record per LED)
//! or modulated at once (frequency multiplexing: one record per image, each
//! LED at its own tone), with the impairments of a real card.
//!
//! # Signal
//!
//! Record `r` spans the samples `[r L, (r+1) L)` (records back to back,
//! `L = round(duration fs)`); during it, channel `k` carries
//!
//! ```text
//! x_k[n] = Σ_i V_ik sin(2π f_i (1 + ε) t + φ_ri) + e_k[n] + impairments,   t = n / fs,
//! ```
//!
//! `V_ik` the clean amplitude (peak volts) of LED `i` on channel `k`,
//! `φ_ri` uniform in `[0, 2π)`, `ε` the clock mismatch. The white noise
//! `e_k` has `σ_k² = Σ_i σ_ik²` with `σ_ik = V_ik 10^(−SNR/20) / √2`, the
//! per-channel SNR of docs/model.md §6 for each LED (one LED: exactly that
//! SNR).
//!
//! # Impairments ([`Impairments`], each switchable)
//!
//! | name | model | default |
//! | --- | --- | --- |
//! | `dc` | a constant offset per channel (ambient light, amplifier offset), `d_k` | 0.5, −0.3, 0.2, 0.4 V |
//! | `hum` | 50 Hz mains and its harmonics: `h (sin(2π 50 t + ψ) + ⅓ sin(2π 150 t) + ⅕ sin(2π 250 t))` | `h` = 20 mV |
//! | `drift` | slow drift, `δ t + 0.05 sin(2π 0.1 t)` V | `δ` = 10 mV/s |
//! | `quantise` | a 16-bit ADC over ±10 V: `x → round(x / q) q`, `q` = 20/65536 V, clipped to the range | on |
//! | `clock` | the LEDs' clock off the card's by `ε` (tens of ppm) | 40 ppm |
//! | `transients` | a switching spike at each record's start, `s e^{−(t − t_r)/τ}` | `s` = 0.2 V, `τ` = 0.2 ms |
//!
//! Quantisation adds a white noise of `q/√12` = 88 µV; the others are
//! removed by the band-pass, the skipped transient and the clock estimate.
//!
//! # Random numbers
//!
//! From the caller's ChaCha8: per record, one phase per LED (uniform), then
//! per sample the four channels' standard normals (only with noise); the
//! hum phase once at the start.

use std::f64::consts::TAU;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Serialize;

use crate::SimError;

/// One sample of the four channels `[vx1, vx2, vy1, vy2]`, V.
pub type Frame = [f64; 4];

/// The card's impairments (module documentation); [`Impairments::none`]
/// switches all of them off, [`Default`] all on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Impairments {
    /// Per-channel DC offset, V.
    pub dc_offset_v: [f64; 4],
    /// 50 Hz hum amplitude, V.
    pub hum_v: f64,
    /// Linear drift, V/s (plus a 0.1 Hz wander of 50 mV when non-zero).
    pub drift_v_per_s: f64,
    /// 16-bit quantisation over ±10 V.
    pub quantise: bool,
    /// Clock mismatch `ε`, parts per million.
    pub clock_ppm: f64,
    /// Switching spike at each record start, V.
    pub transient_v: f64,
}

impl Default for Impairments {
    fn default() -> Self {
        Self {
            dc_offset_v: [0.5, -0.3, 0.2, 0.4],
            hum_v: 0.02,
            drift_v_per_s: 0.01,
            quantise: true,
            clock_ppm: 40.0,
            transient_v: 0.2,
        }
    }
}

impl Impairments {
    /// No impairment at all.
    pub fn none() -> Self {
        Self {
            dc_offset_v: [0.0; 4],
            hum_v: 0.0,
            drift_v_per_s: 0.0,
            quantise: false,
            clock_ppm: 0.0,
            transient_v: 0.0,
        }
    }
}

/// One impairment, to switch on by name ([`Impairments::only`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Impairment {
    /// DC offsets.
    Dc,
    /// 50 Hz hum and harmonics.
    Hum,
    /// Slow drift.
    Drift,
    /// 16-bit quantisation over ±10 V.
    Quantise,
    /// Clock mismatch.
    Clock,
    /// Switching transients.
    Transients,
}

impl Impairment {
    /// Every impairment, in the order the command line lists them.
    pub const ALL: [Impairment; 6] = [
        Impairment::Dc,
        Impairment::Hum,
        Impairment::Drift,
        Impairment::Quantise,
        Impairment::Clock,
        Impairment::Transients,
    ];

    /// Its name (the command line's, and its serialisation).
    pub fn name(self) -> &'static str {
        match self {
            Impairment::Dc => "dc",
            Impairment::Hum => "hum",
            Impairment::Drift => "drift",
            Impairment::Quantise => "quantise",
            Impairment::Clock => "clock",
            Impairment::Transients => "transients",
        }
    }

    /// One item of a list of impairments (`--impairments`, any case):
    /// an impairment's name, or `none` (`Ok(None)`: a clean card);
    /// refused with the accepted names.
    pub fn parse_item(text: &str) -> Result<Option<Impairment>, String> {
        let wanted = text.trim().to_ascii_lowercase();
        if wanted == "none" {
            return Ok(None);
        }
        Self::ALL
            .into_iter()
            .find(|i| i.name() == wanted)
            .map(Some)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|i| i.name()).collect();
                format!(
                    "unknown value '{text}'; expected one of {}, none",
                    names.join(", ")
                )
            })
    }
}

impl Impairments {
    /// The listed impairments at their defaults, the others off.
    pub fn only(list: &[Impairment]) -> Self {
        let all = Self::default();
        let mut out = Self::none();
        for item in list {
            match item {
                Impairment::Dc => out.dc_offset_v = all.dc_offset_v,
                Impairment::Hum => out.hum_v = all.hum_v,
                Impairment::Drift => out.drift_v_per_s = all.drift_v_per_s,
                Impairment::Quantise => out.quantise = true,
                Impairment::Clock => out.clock_ppm = all.clock_ppm,
                Impairment::Transients => out.transient_v = all.transient_v,
            }
        }
        out
    }
}

/// The ADC's full scale, V (±10 V).
pub const FULL_SCALE_V: f64 = 10.0;

/// The 16-bit step over ±10 V, V.
pub const QUANTUM_V: f64 = 2.0 * FULL_SCALE_V / 65536.0;

/// Time constant of the switching spike, s.
pub const TRANSIENT_TAU_S: f64 = 2e-4;

/// One record: the LEDs on, each `(frequency_hz, amplitudes)`.
#[derive(Debug, Clone, PartialEq)]
pub struct RawRecord {
    /// `(frequency, V_k)` per LED on.
    pub leds: Vec<(f64, Frame)>,
}

/// A recording to synthesise.
#[derive(Debug, Clone, PartialEq)]
pub struct RawPlan {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Samples per record, `L`.
    pub record_samples: usize,
    /// The records, in time order.
    pub records: Vec<RawRecord>,
    /// Per-channel SNR per LED, dB (`None`: no noise).
    pub snr_db: Option<f64>,
    /// The impairments.
    pub impairments: Impairments,
}

impl RawPlan {
    /// Samples in the recording.
    pub fn samples(&self) -> usize {
        self.records.len() * self.record_samples
    }

    /// Synthesises the recording (module documentation) and hands it to
    /// `sink` one record at a time (memory: one record).
    ///
    /// Errors: a non-positive or non-finite rate, frequency or amplitude, a
    /// non-finite SNR or impairment, an empty record length; the sink's error.
    pub fn generate<E: From<SimError>>(
        &self,
        rng: &mut ChaCha8Rng,
        mut sink: impl FnMut(&[Frame]) -> Result<(), E>,
    ) -> Result<(), E> {
        self.check().map_err(E::from)?;
        let fs = self.sample_rate_hz;
        let imp = &self.impairments;
        let clock = 1.0 + imp.clock_ppm * 1e-6;
        let hum_phase = TAU * rng.random::<f64>();
        let mut frames = vec![[0.0; 4]; self.record_samples];
        for (r, record) in self.records.iter().enumerate() {
            let phases: Vec<f64> = record
                .leds
                .iter()
                .map(|_| TAU * rng.random::<f64>())
                .collect();
            let mut sigma = [0.0; 4];
            if let Some(snr) = self.snr_db {
                let scale = 10f64.powf(-snr / 20.0) / 2f64.sqrt();
                for (_, amps) in &record.leds {
                    for k in 0..4 {
                        sigma[k] += (amps[k] * scale).powi(2);
                    }
                }
                for s in sigma.iter_mut() {
                    *s = s.sqrt();
                }
            }
            let first = r * self.record_samples;
            for (i, frame) in frames.iter_mut().enumerate() {
                let n = first + i;
                let t = n as f64 / fs;
                let mut clean = 0.0f64;
                let mut tones = [0.0; 4];
                for ((f, amps), phase) in record.leds.iter().zip(&phases) {
                    // Reduce the cycles to one turn before scaling.
                    let turns = (f * clock * n as f64 / fs).fract();
                    let s = (TAU * turns + phase).sin();
                    for k in 0..4 {
                        tones[k] += amps[k] * s;
                    }
                }
                if imp.hum_v != 0.0 {
                    clean += imp.hum_v
                        * ((TAU * 50.0 * t + hum_phase).sin()
                            + (TAU * 150.0 * t).sin() / 3.0
                            + (TAU * 250.0 * t).sin() / 5.0);
                }
                if imp.drift_v_per_s != 0.0 {
                    clean += imp.drift_v_per_s * t + 0.05 * (TAU * 0.1 * t).sin();
                }
                if imp.transient_v != 0.0 {
                    clean += imp.transient_v * (-(i as f64) / (fs * TRANSIENT_TAU_S)).exp();
                }
                for k in 0..4 {
                    let mut x = tones[k] + clean + imp.dc_offset_v[k];
                    if self.snr_db.is_some() {
                        let e: f64 = rng.sample(StandardNormal);
                        x += sigma[k] * e;
                    }
                    if imp.quantise {
                        x = ((x / QUANTUM_V).round() * QUANTUM_V)
                            .clamp(-FULL_SCALE_V, FULL_SCALE_V - QUANTUM_V);
                    }
                    frame[k] = x;
                }
            }
            sink(&frames)?;
        }
        Ok(())
    }

    fn check(&self) -> Result<(), SimError> {
        let bad = |what: String| Err(SimError::Options(what));
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return bad(format!("sample rate {} Hz", self.sample_rate_hz));
        }
        if self.record_samples == 0 {
            return bad("records of 0 samples".to_string());
        }
        if let Some(snr) = self.snr_db {
            if !snr.is_finite() {
                return bad(format!("SNR {snr} dB: must be finite"));
            }
        }
        let imp = &self.impairments;
        let values = imp.dc_offset_v.iter().chain([
            &imp.hum_v,
            &imp.drift_v_per_s,
            &imp.clock_ppm,
            &imp.transient_v,
        ]);
        if values.into_iter().any(|v| !v.is_finite()) || imp.clock_ppm.abs() > 1e4 {
            return bad("impairments must be finite (clock within ±10⁴ ppm)".to_string());
        }
        for record in &self.records {
            for (f, amps) in &record.leds {
                if !(f.is_finite() && *f > 0.0 && *f < 0.5 * self.sample_rate_hz) {
                    return bad(format!("a tone of {f} Hz: must lie between 0 and fs/2"));
                }
                if amps
                    .iter()
                    .any(|a| !(a.is_finite() && *a >= 0.0 && *a <= FULL_SCALE_V))
                {
                    return bad(format!("amplitudes {amps:?}: must lie in [0, 10] V"));
                }
            }
        }
        Ok(())
    }
}
