//! The electrode signal chain of docs/model.md §6 (the paper's Sections 4.3–4.5):
//! modulated channel records with white Gaussian noise at a per-channel SNR,
//! a Butterworth band-pass ([`crate::butterworth`]), amplitude estimation by
//! synchronous I/Q demodulation over whole cycles (or RMS), and the impact
//! point of docs/model.md §1.
//!
//! # Conventions
//!
//! Amplitudes in volts or any consistent unit (only ratios reach the impact
//! point); frequencies in Hz; time in seconds; sample index `n = 0 … L−1` at
//! `t = n / fs`; phases in radians. Record length and transient are counted in
//! cycles of the modulation frequency `f0` (1 cycle = 1 ms at 1 kHz).
//!
//! # Synthesis
//!
//! Each channel `k` carries the record
//!
//! ```text
//! x_k[n] = V_k sin(2π f0 n / fs + φ) + e_k[n],   e_k[n] ~ N(0, σ_k²) i.i.d.,
//! SNR_dB = 10 log10((V_k² / 2) / σ_k²)   ⇔   σ_k = V_k · 10^(−SNR_dB / 20) / √2,
//! ```
//!
//! i.e. the SNR is the same on every channel, each relative to its own
//! amplitude `V_k` (docs/model.md §6). The LED is switched on at `t = 0` with the
//! filter at rest, so the record contains the filter's switch-on transient.
//! The phase `φ` is drawn uniformly in `[0, 2π)` once per [`SignalChain::measure`]
//! call and shared by the four channels (they see the same LED); it does not
//! affect the estimate except through the noise.
//!
//! Random numbers: all from the caller's `ChaCha8Rng`, in this order per
//! [`SignalChain::measure`] call: one `f64` for `φ` (`φ = 2π u`, `u` in
//! `[0, 1)`), then `L` standard normals (`rand_distr::StandardNormal`) for
//! channel x1, `L` for x2, `L` for y1, `L` for y2. Without noise
//! (`snr_db = None`) only `φ` is drawn. The layout does not depend on the
//! amplitudes, so studies can use common random numbers across conditions.
//!
//! # Filtering
//!
//! `y = h ∗ x` with the band-pass `h` of [`crate::butterworth::BandPass`], from
//! the zero state, over the whole record. Its gain `|H(f0)|` at the modulation
//! frequency is divided out of the estimate (it is 1 for the default
//! [`BandPlacement::Geometric`](crate::butterworth::BandPlacement::Geometric) band; its phase at `f0` does not matter to a
//! magnitude estimate).
//!
//! # Demodulation
//!
//! Over the window `W = [n_s, L)` that starts after `transient_cycles` whole
//! cycles and holds `M = L − n_s` samples (`record_cycles − transient_cycles`
//! whole cycles), with `c_n = cos(2π f0 n / fs)` and `s_n = sin(2π f0 n / fs)`:
//!
//! - **I/Q** ([`Demodulation::Iq`]): the least-squares fit
//!   `y[n] ≈ I c_n + Q s_n`, `(I, Q)ᵀ = G⁻¹ Σ_W y[n] (c_n, s_n)ᵀ` with the Gram
//!   matrix `G = Σ_W (c_n, s_n)ᵀ(c_n, s_n)`. When the window holds whole
//!   cycles of an integer number of samples each (`fs / f0` an integer, as at
//!   the defaults) `G = (M/2)·1` and this is exactly
//!   `I = (2/M) Σ_W y[n] c_n`, `Q = (2/M) Σ_W y[n] s_n`; otherwise `G⁻¹`
//!   removes the residual cross-talk. Then `Â = √(I² + Q²) / |H(f0)|`.
//!   A pure sinusoid `A sin(2π f0 n/fs + φ)` gives `(I, Q) = A (sin φ, cos φ)`.
//! - **RMS** ([`Demodulation::Rms`]): `Â = √(2 · (1/M) Σ_W y[n]²) / |H(f0)|`.
//!
//! # Noise of the estimate (theory)
//!
//! The chain is linear up to the final modulus, so the noise part of `I` is
//! `Σ_W w^I_n (h ∗ e)[n] = Σ_k e[k] g^I_k` with `w^I` the first row of
//! `G⁻¹ (c_n, s_n)ᵀ` on `W` (zero elsewhere) and
//! `g^I_k = Σ_n w^I_n h[n − k]`, the filter run over the time-reversed
//! weights. Hence, exactly for this record length, filter and window,
//! `var I = σ² Σ_k (g^I_k)²`, and likewise for `Q`. At high SNR the modulus
//! moves only with the noise component along the signal's direction in the
//! `(I, Q)` plane; averaged over the uniform phase `φ`,
//!
//! ```text
//! std(Â) = κ σ,   κ² = (Σ_k (g^I_k)² + Σ_k (g^Q_k)²) / (2 |H(f0)|²)
//! ```
//!
//! ([`SignalChain::noise_factor`]). Asymptotically — the window much longer
//! than the filter's memory, `|H|` flat over the demodulator's resolution
//! `1/T`, `T = M / fs` — `g ≈ |H(f0)| w` and `κ² → 2/M`
//! ([`SignalChain::asymptotic_noise_factor`]): white noise of variance `σ²` at
//! rate `fs` has the one-sided density `S = 2σ²/fs` V²/Hz, and averaging over
//! `T` seconds passes `var(Â) ≈ S / T = 2σ²/M`. The exact `κ` is slightly
//! smaller (by 0.5 % at the defaults: κ = 0.04977) because the filter also
//! removes the demodulator's far side lobes. The relative std of `Â` is
//! `κ · 10^(−SNR/20) / √2` (1.1e-3 at 30 dB with the defaults). The estimate
//! is biased upwards by the noise across the signal direction (Rice), by about
//! `κ²σ² / (2A)`: below 1e-6 relative at 30 dB, negligible.
//!
//! The RMS estimate has the same first-order noise (its linear term is the
//! in-phase projection with weights `2/M`), so `κ` applies to it too, plus a
//! positive bias from the noise power in the band,
//! `≈ σ² ν / (A |H(f0)|²)` with `ν` the filter's noise gain
//! ([`crate::butterworth::BandPass::noise_gain`], 0.067 at the defaults:
//! 3e-5 relative at 30 dB).
//!
//! # Parameters
//!
//! [`ChainConfig`], with its defaults and their reasons, is in
//! [`crate::chain_config`].
//!
//! # Implementation
//!
//! For I/Q the chain is linear up to the final modulus, so
//! [`SignalChain::measure_channel`] evaluates
//! `(I, Q)ᵀ = C (A sin φ, A cos φ)ᵀ + σ Σ_k ε_k (g^I_k, g^Q_k)ᵀ`, `ε_k` the
//! standard normal draws, with the clean response `C` (the `cos` and `sin`
//! tables filtered from rest and demodulated once, transient included) and
//! the weights `g` above, both precomputed when the chain is built: the
//! draws and their order are those of the literal chain
//! ([`SignalChain::synthesize`] → [`BandPass::filter`] →
//! [`SignalChain::demodulate`]) and the result is the same to rounding
//! (tested to 1e-12), about twice as fast at the defaults — the recursion of
//! the filter is the bottleneck otherwise. The RMS estimate is not linear: it streams
//! each sample through the filter and agrees with the literal chain to the
//! bit. Nothing is allocated per record.
//!

use std::f64::consts::TAU;
use std::fmt;

use nalgebra::Vector2;
use psdcal_model::psd::{electrode_currents, impact_point, is_on_active_area};
use psdcal_model::{Amplitudes, ChannelGains, PsdGeometry};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::butterworth::{BandPass, FilterState};
use crate::chain_config::{check_amplitude, check_snr, sigma_for};
pub use crate::chain_config::{
    noise_sigma, ChainConfig, Demodulation, MAX_LEVEL, MAX_RECORD_SAMPLES,
};
use psdcal_signal::lockin::{IqSums as Accumulator, LockIn};
pub use psdcal_signal::SignalError;

/// The signal chain: a validated [`ChainConfig`] with its designed filter and
/// the precomputed reference tables. Immutable and cheap to share across
/// threads; one channel record allocates nothing.
///
/// Serialises as its [`ChainConfig`]; deserialising validates it.
#[derive(Clone, Serialize, Deserialize)]
#[serde(try_from = "ChainConfig", into = "ChainConfig")]
pub struct SignalChain {
    config: ChainConfig,
    filter: BandPass,
    /// `L`.
    record_len: usize,
    /// `n_s`, first sample of the demodulation window.
    window_start: usize,
    /// The I/Q detector: `cos(2π f0 n / fs)`, `sin(2π f0 n / fs)`,
    /// `n = 0 … L−1`, and `G⁻¹`.
    lockin: LockIn,
    /// `1 / |H(f0)|`.
    inv_gain: f64,
    /// `κ`.
    noise_factor: f64,
    /// `(g^I_k, g^Q_k)`, `k = 0 … L−1`: the I/Q response to a unit noise
    /// sample at `k` (filter run over the time-reversed weights).
    noise_weights: Vec<[f64; 2]>,
    /// `(I, Q)` of the filtered clean record per unit `(A sin φ, A cos φ)`:
    /// column 0 from the filtered `cos` table, column 1 from `sin`.
    clean_iq: [[f64; 2]; 2],
}

impl fmt::Debug for SignalChain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SignalChain")
            .field("config", &self.config)
            .field("record_samples", &self.record_len)
            .field("window_start", &self.window_start)
            .field("band_edges_hz", &self.filter.band_edges_hz())
            .field("noise_factor", &self.noise_factor)
            .finish()
    }
}

impl PartialEq for SignalChain {
    /// Two chains are equal when their configurations are (everything else
    /// is derived from it).
    fn eq(&self, other: &Self) -> bool {
        self.config == other.config
    }
}

impl Default for SignalChain {
    /// The chain of [`ChainConfig::default`].
    fn default() -> Self {
        // The default configuration is valid (tested), so the infallible
        // construction applies.
        Self::build(ChainConfig::default())
    }
}

impl TryFrom<ChainConfig> for SignalChain {
    type Error = SignalError;
    fn try_from(config: ChainConfig) -> Result<Self, SignalError> {
        Self::new(config)
    }
}

impl From<SignalChain> for ChainConfig {
    fn from(chain: SignalChain) -> Self {
        chain.config
    }
}

impl SignalChain {
    /// Validates `config`, designs the filter and precomputes the tables.
    pub fn new(config: ChainConfig) -> Result<Self, SignalError> {
        config.validate()?;
        // Re-validates the band against Nyquist (implied by the checks above).
        BandPass::design(
            config.filter_order,
            config.f0_hz,
            config.bandwidth_hz,
            config.sample_rate_hz,
            config.band_placement,
        )?;
        Ok(Self::build(config))
    }

    /// Construction from a validated configuration.
    fn build(config: ChainConfig) -> Self {
        let filter = BandPass::design_valid(
            config.filter_order,
            config.f0_hz,
            config.bandwidth_hz,
            config.sample_rate_hz,
            config.band_placement,
        );
        let cycle = config.sample_rate_hz / config.f0_hz;
        let record_len = (config.record_cycles as f64 * cycle).round() as usize;
        let window_start = (config.transient_cycles as f64 * cycle).round() as usize;
        let lockin = LockIn::new_valid(
            config.f0_hz,
            config.sample_rate_hz,
            record_len,
            window_start,
        );
        let gain = filter.magnitude(config.f0_hz);
        let inv_gain = 1.0 / gain;
        let mut chain = Self {
            config,
            filter,
            record_len,
            window_start,
            lockin,
            inv_gain,
            noise_factor: 0.0,
            noise_weights: Vec::new(),
            clean_iq: [[0.0; 2]; 2],
        };
        chain.noise_weights = chain.reversed_weights();
        let total: f64 = chain
            .noise_weights
            .iter()
            .map(|g| g[0] * g[0] + g[1] * g[1])
            .sum();
        chain.noise_factor = (0.5 * total).sqrt() * chain.inv_gain;
        chain.clean_iq = chain.clean_response();
        chain
    }

    /// `g^I_k = Σ_n w^I_n h[n − k]` and the same for `Q`: the filter run over
    /// the time-reversed demodulation weights (module documentation).
    fn reversed_weights(&self) -> Vec<[f64; 2]> {
        let mut g = vec![[0.0; 2]; self.record_len];
        for (r, row) in self.lockin.gram_inv().iter().enumerate() {
            let mut state = FilterState::new();
            for m in 0..self.record_len {
                let n = self.record_len - 1 - m;
                let w = if n >= self.window_start {
                    row[0] * self.lockin.cos()[n] + row[1] * self.lockin.sin()[n]
                } else {
                    0.0
                };
                g[n][r] = state.process(&self.filter, w);
            }
        }
        g
    }

    /// `(I, Q)` of the filtered `cos` and `sin` tables (switch-on transient
    /// included), as the columns of a 2×2 matrix.
    fn clean_response(&self) -> [[f64; 2]; 2] {
        let mut out = [[0.0; 2]; 2];
        for (col, table) in [self.lockin.cos(), self.lockin.sin()]
            .into_iter()
            .enumerate()
        {
            let mut y = table.to_vec();
            self.filter.filter(&mut y);
            let mut acc = Accumulator::default();
            for (n, &v) in y.iter().enumerate().skip(self.window_start) {
                acc.add(v, self.lockin.cos()[n], self.lockin.sin()[n]);
            }
            let (i, q) = self.iq(&acc);
            out[0][col] = i;
            out[1][col] = q;
        }
        out
    }

    /// The configuration.
    pub fn config(&self) -> &ChainConfig {
        &self.config
    }

    /// The band-pass filter.
    pub fn filter(&self) -> &BandPass {
        &self.filter
    }

    /// Samples per record, `L = round(record_cycles · fs / f0)`.
    pub fn record_samples(&self) -> usize {
        self.record_len
    }

    /// The demodulation window `n_s .. L` (sample indices).
    pub fn window(&self) -> std::ops::Range<usize> {
        self.window_start..self.record_len
    }

    /// The gain `|H(f0)|` of the filter at the modulation frequency (divided
    /// out of every estimate).
    pub fn gain_at_f0(&self) -> f64 {
        1.0 / self.inv_gain
    }

    /// `κ`: the standard deviation of the amplitude estimate per unit of
    /// input noise standard deviation, `std(Â) = κ σ`, exact to first order in
    /// `1/SNR` for this filter, record and window, averaged over the uniform
    /// phase (module documentation). I/Q and RMS alike.
    pub fn noise_factor(&self) -> f64 {
        self.noise_factor
    }

    /// The asymptotic `κ = √(2/M)` (`M` samples in the window), with
    /// `|H(f0)| = 1`.
    pub fn asymptotic_noise_factor(&self) -> f64 {
        (2.0 / (self.record_len - self.window_start) as f64).sqrt()
    }

    /// Theoretical standard deviation `κ σ` of the amplitude estimate of a
    /// channel of amplitude `amplitude` at `snr_db` (module documentation).
    pub fn amplitude_std(&self, amplitude: f64, snr_db: f64) -> Result<f64, SignalError> {
        Ok(self.noise_factor * noise_sigma(amplitude, snr_db)?)
    }

    /// The clean sample `A sin(ω n + φ) = (A sin φ) c_n + (A cos φ) s_n`.
    #[inline(always)]
    fn clean(&self, n: usize, a_cos: f64, a_sin: f64) -> f64 {
        a_cos * self.lockin.cos()[n] + a_sin * self.lockin.sin()[n]
    }

    /// Writes the noisy record `x[n] = A sin(2π f0 n/fs + φ) + e[n]`,
    /// `n = 0 … L−1`, into `out` (cleared and refilled; reuse it to avoid
    /// allocations). Draws exactly what [`SignalChain::measure_channel`] draws,
    /// in the same order.
    pub fn synthesize(
        &self,
        amplitude: f64,
        phase_rad: f64,
        snr_db: Option<f64>,
        rng: &mut ChaCha8Rng,
        out: &mut Vec<f64>,
    ) -> Result<(), SignalError> {
        let (a_cos, a_sin, sigma) = self.channel_setup(amplitude, phase_rad, snr_db)?;
        out.clear();
        out.reserve(self.record_len);
        match sigma {
            Some(sigma) => {
                for n in 0..self.record_len {
                    let e: f64 = rng.sample(StandardNormal);
                    out.push(self.clean(n, a_cos, a_sin) + sigma * e);
                }
            }
            None => out.extend((0..self.record_len).map(|n| self.clean(n, a_cos, a_sin))),
        }
        Ok(())
    }

    /// Estimates the amplitude from a record that has already been filtered
    /// (length [`SignalChain::record_samples`]), with the configured method:
    /// the literal last step of the chain. `synthesize`, then
    /// [`BandPass::filter`], then `demodulate` is the reference that
    /// [`SignalChain::measure_channel`] reproduces.
    pub fn demodulate(&self, filtered: &[f64]) -> Result<f64, SignalError> {
        if filtered.len() != self.record_len {
            return Err(SignalError::RecordLength {
                expected: self.record_len,
                found: filtered.len(),
            });
        }
        let mut acc = Accumulator::default();
        for (n, &y) in filtered.iter().enumerate().skip(self.window_start) {
            acc.add(y, self.lockin.cos()[n], self.lockin.sin()[n]);
        }
        self.finish(&acc)
    }

    /// One channel record end to end: synthesis with amplitude `amplitude`,
    /// phase `phase_rad` and noise at `snr_db` (none for `None`), filtering,
    /// demodulation. Allocates nothing. I/Q is evaluated by linearity from
    /// precomputed responses, RMS by streaming every sample through the
    /// filter (module documentation, *Implementation*); either way it draws
    /// exactly what [`SignalChain::synthesize`] draws and returns what
    /// `synthesize` → [`BandPass::filter`] → [`SignalChain::demodulate`]
    /// returns (to the bit for RMS, to rounding for I/Q).
    pub fn measure_channel(
        &self,
        amplitude: f64,
        phase_rad: f64,
        snr_db: Option<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<f64, SignalError> {
        let (a_cos, a_sin, sigma) = self.channel_setup(amplitude, phase_rad, snr_db)?;
        self.run(a_cos, a_sin, sigma, rng)
    }

    /// Checks a single channel's inputs; returns the cos/sin coefficients and
    /// the noise σ.
    fn channel_setup(
        &self,
        amplitude: f64,
        phase_rad: f64,
        snr_db: Option<f64>,
    ) -> Result<(f64, f64, Option<f64>), SignalError> {
        check_amplitude("channel", amplitude)?;
        if !phase_rad.is_finite() {
            return Err(SignalError::InvalidParameter {
                name: "phase_rad",
                value: phase_rad,
                reason: "must be finite",
            });
        }
        let sigma = snr_db.map(|snr| sigma_for(amplitude, snr)).transpose()?;
        let (s, c) = phase_rad.sin_cos();
        Ok((amplitude * s, amplitude * c, sigma))
    }

    /// One record: the linear I/Q path, or the streaming RMS path.
    #[inline]
    fn run(
        &self,
        a_cos: f64,
        a_sin: f64,
        sigma: Option<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<f64, SignalError> {
        match (self.config.demodulation, sigma) {
            (Demodulation::Iq, _) => self.run_iq(a_cos, a_sin, sigma, rng),
            (Demodulation::Rms, Some(sigma)) => self.run_with::<true>(a_cos, a_sin, sigma, rng),
            (Demodulation::Rms, None) => self.run_with::<false>(a_cos, a_sin, 0.0, rng),
        }
    }

    /// I/Q by linearity: `(I, Q) = C (A sin φ, A cos φ)ᵀ + σ Σ_k ε_k (g^I_k, g^Q_k)`
    /// with the precomputed clean response `C` and noise weights `g`; the
    /// same numbers as synthesising, filtering and demodulating the record
    /// (to rounding), from the same draws, without the per-sample filter
    /// recursion.
    #[inline]
    fn run_iq(
        &self,
        a_cos: f64,
        a_sin: f64,
        sigma: Option<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<f64, SignalError> {
        let c = &self.clean_iq;
        let mut i = c[0][0] * a_cos + c[0][1] * a_sin;
        let mut q = c[1][0] * a_cos + c[1][1] * a_sin;
        if let Some(sigma) = sigma {
            // Draws in blocks on the stack, then the two dot products: keeps
            // the normal sampler's branches out of the accumulation loop.
            const BLOCK: usize = 64;
            let mut eps = [0.0; BLOCK];
            let (mut ni, mut nq) = (0.0, 0.0);
            for chunk in self.noise_weights.chunks(BLOCK) {
                let eps = &mut eps[..chunk.len()];
                for e in eps.iter_mut() {
                    *e = rng.sample(StandardNormal);
                }
                for (g, e) in chunk.iter().zip(eps.iter()) {
                    ni += g[0] * e;
                    nq += g[1] * e;
                }
            }
            i += sigma * ni;
            q += sigma * nq;
        }
        Self::finite(i.hypot(q) * self.inv_gain)
    }

    /// Synthesis, filtering and window sums in one pass (the RMS path);
    /// `NOISY` selects the noise draws at compile time. The sample expression
    /// is the one of `synthesize`, so the two paths agree to the bit.
    #[inline(always)]
    fn run_with<const NOISY: bool>(
        &self,
        a_cos: f64,
        a_sin: f64,
        sigma: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<f64, SignalError> {
        let mut state = FilterState::new();
        let filter = &self.filter;
        let mut sample = |n: usize| {
            let mut x = self.clean(n, a_cos, a_sin);
            if NOISY {
                let e: f64 = rng.sample(StandardNormal);
                x += sigma * e;
            }
            x
        };
        for n in 0..self.window_start {
            let x = sample(n);
            state.process(filter, x);
        }
        let mut acc = Accumulator::default();
        for n in self.window_start..self.record_len {
            let x = sample(n);
            let y = state.process(filter, x);
            acc.add(y, self.lockin.cos()[n], self.lockin.sin()[n]);
        }
        self.finish(&acc)
    }

    /// `(I, Q) = G⁻¹ (Σ y c, Σ y s)`.
    fn iq(&self, acc: &Accumulator) -> (f64, f64) {
        self.lockin.iq(acc)
    }

    /// The estimate from the window sums.
    fn finish(&self, acc: &Accumulator) -> Result<f64, SignalError> {
        let estimate = match self.config.demodulation {
            Demodulation::Iq => {
                let (i, q) = self.iq(acc);
                i.hypot(q) * self.inv_gain
            }
            Demodulation::Rms => {
                let m = (self.record_len - self.window_start) as f64;
                (2.0 * acc.yy / m).sqrt() * self.inv_gain
            }
        };
        Self::finite(estimate)
    }

    /// Passes finite estimates; never lets a NaN or infinity out.
    fn finite(estimate: f64) -> Result<f64, SignalError> {
        if estimate.is_finite() {
            Ok(estimate)
        } else {
            // Not reachable within MAX_LEVEL; kept so no NaN can escape.
            Err(SignalError::InvalidAmplitude {
                channel: "estimate",
                value: estimate,
            })
        }
    }

    /// Measures the four channels of `clean` (their amplitudes at the
    /// demodulator input, volts or any unit) with noise at `snr_db` per
    /// channel (`None`: no noise), one random phase shared by the four
    /// channels. Draw order: module documentation.
    ///
    /// Errors: non-finite SNR; a negative, non-finite or too large amplitude;
    /// noise σ above [`MAX_LEVEL`].
    pub fn measure(
        &self,
        clean: &Amplitudes,
        snr_db: Option<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<Amplitudes, SignalError> {
        check_snr(snr_db)?;
        let channels = [
            ("x1", clean.vx1),
            ("x2", clean.vx2),
            ("y1", clean.vy1),
            ("y2", clean.vy2),
        ];
        let mut sigmas = [None; 4];
        for ((name, value), sigma) in channels.iter().zip(sigmas.iter_mut()) {
            check_amplitude(name, *value)?;
            *sigma = snr_db.map(|snr| sigma_for(*value, snr)).transpose()?;
        }
        let phase = TAU * rng.random::<f64>();
        let (s, c) = phase.sin_cos();
        let mut out = [0.0; 4];
        for (((_, amplitude), sigma), estimate) in channels.iter().zip(sigmas).zip(out.iter_mut()) {
            *estimate = self.run(amplitude * s, amplitude * c, sigma, rng)?;
        }
        Ok(Amplitudes {
            vx1: out[0],
            vx2: out[1],
            vy1: out[2],
            vy2: out[3],
        })
    }

    /// One LED spot end to end: the electrode currents of a spot of total
    /// photocurrent `i0` (A) at `point` (mm, sensor frame, docs/model.md §1), times
    /// [`ChainConfig::amplifier_gain_v_per_a`] and the relative channel
    /// `gains` (`Amplitudes::apply_gains`) → volts; the chain of
    /// [`SignalChain::measure`]; the impact point of the measured amplitudes
    /// by the balanced formula `impact_point` (gains not divided out: that is
    /// the electrical calibration's job). Returns the measured amplitudes and
    /// the measured point.
    ///
    /// Errors: invalid geometry, point, `i0` or gains; a point off the active
    /// area; the chain's errors; [`SignalError::NonPositiveTotal`] when the
    /// measured amplitudes sum to zero (`i0 = 0`).
    pub fn measure_point(
        &self,
        geometry: &PsdGeometry,
        point: &Vector2<f64>,
        i0: f64,
        gains: &ChannelGains,
        snr_db: Option<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<(Amplitudes, Vector2<f64>), SignalError> {
        for (name, value) in [("geometry.lx", geometry.lx), ("geometry.ly", geometry.ly)] {
            if !value.is_finite() || value <= 0.0 {
                return Err(SignalError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and positive",
                });
            }
        }
        if !point.x.is_finite() || !point.y.is_finite() {
            return Err(SignalError::InvalidParameter {
                name: "point",
                value: if point.x.is_finite() {
                    point.y
                } else {
                    point.x
                },
                reason: "must be finite",
            });
        }
        if !i0.is_finite() || i0 < 0.0 {
            return Err(SignalError::InvalidParameter {
                name: "i0",
                value: i0,
                reason: "must be finite and non-negative",
            });
        }
        gains.validate()?;
        if !is_on_active_area(geometry, point) {
            return Err(SignalError::OffActiveArea {
                x_mm: point.x,
                y_mm: point.y,
            });
        }
        let volts = i0 * self.config.amplifier_gain_v_per_a;
        let clean = electrode_currents(geometry, point, volts).apply_gains(gains);
        let measured = self.measure(&clean, snr_db, rng)?;
        let point = impact_point(geometry, &measured)?;
        Ok((measured, point))
    }
}
