//! Demodulation of one record (docs/model.md §8 "Demodulation"): the samples
//! of `C` channels while one LED (one tone) or several LEDs (several tones,
//! frequency multiplexing) are on, in; per tone and channel the amplitude
//! (peak volts), its noise and SNR, and the modulation frequency out.
//!
//! # Steps
//!
//! 1. **Band-pass** every channel from rest at the record's first sample:
//!    Butterworth of order `N`, centred on the tone with bandwidth `B` for
//!    one tone, with edges `f_min − B/2`, `f_max + B/2` for several
//!    ([`crate::butterworth`]).
//! 2. **Skip the transient**: `n_s = ⌈t_s fs⌉` samples with
//!    `t_s = ln(1/tol) / decay_rate` ([`BandPass::settling_time`]); the
//!    switch-on transient is then below `tol` of its start (1e-11 by default:
//!    24 ms for the default filter; averaged over the window it moves the
//!    amplitude by about 1e-13, below the 1e-12 exactness of a noise-free
//!    record).
//! 3. **Window**: one tone — the last whole number of cycles of the record
//!    after `n_s`, `M = round(⌊(L − n_s) f/fs⌋ fs/f)` samples; several tones —
//!    all of `[n_s, L)`. The window must hold [`MIN_WINDOW_CYCLES`] cycles of
//!    the lowest tone, and the tones must be `2/T` apart (`T = M/fs`,
//!    [`crate::tones::check_separable`]).
//! 4. **Joint least squares** over the window for every tone at once
//!    ([`crate::lockin`] generalised to `K` tones): the basis
//!    `(c_{1,n}, s_{1,n}, …, c_{K,n}, s_{K,n})`, the `2K × 2K` Gram matrix `G`,
//!    `θ = G⁻¹ Σ y φ`; per tone `Â = √(I² + Q²) / |H(f)|`. With one tone this
//!    is exactly the lock-in of [`crate::lockin`]; with several it removes the
//!    cross-talk between the tones exactly (no noise: exact to rounding).
//! 5. **Frequency** (when the LED and the card have different clocks, all
//!    tones scale by the same ratio `1 + ρ`): the window is cut into `J`
//!    equal sub-windows (`J` = [`DemodConfig::subwindows`] for one tone; for
//!    several, the largest `J` at which the tones stay `2J/T` apart, none
//!    below 2), each detected at the current frequencies. A tone at `f + δf`
//!    makes `z_j = I_j + i Q_j` turn by `−2π δf D / fs` from one sub-window to
//!    the next (`D` samples apart), so
//!    `δf_k = −arg(Σ_c Σ_j z_{j+1} z̄_j) fs / (2π D)` and
//!    `ρ = Σ_k w_k δf_k / f_k / Σ_k w_k` with `w_k = |Σ z_{j+1} z̄_j| f_k²` (the
//!    precision of each ratio). Repeated at the new frequencies until a
//!    pass moves the highest tone by less than 1e-7 cycles over the window
//!    (at most [`MAX_FREQUENCY_PASSES`] passes); the amplitudes are then detected
//!    at `f_k (1 + ρ)`. An offset beyond [`MAX_CLOCK_OFFSET`] is not trusted
//!    (aliasing of the phase steps) and the nominal frequencies are kept.
//!    Each pass is one sweep over the window (the sub-windows' sums, and
//!    those of the few samples after the last, add up to the whole
//!    window's); when a pass's step would turn the highest tone by under
//!    [`SETTLED_TURNS`] cycles (exact clocks: the first pass) the step is
//!    not taken and the pass's sums at its own frequencies are the fit's
//!    (no further sweep; the effect of so small a step on an amplitude is
//!    ~1e-17).
//! 6. **Noise**: the residual of the fit, `RSS = Σ y² − θᵀ Σ y φ`, over
//!    `M − 2K` degrees of freedom is the variance of the filtered noise,
//!    `σ² ν` for white input noise of variance `σ²` (`ν` the filter's
//!    [`BandPass::noise_gain`]); hence the input-equivalent
//!    `σ̂ = √(RSS / ((M − 2K) ν))` per channel. The amplitude's standard
//!    deviation is `σ_Â = σ̂ √(((G⁻¹)_II + (G⁻¹)_QQ) / 2)` (the noise near the
//!    tone passes with `|H(f)|²`, divided out with the gain): `σ̂ √(2/M)` for
//!    a lone tone over whole cycles. The SNR is the per-sample
//!    `10 log10((Â²/2) / σ̂²)` of docs/model.md §6, clamped to
//!    `±`[`MAX_SNR_DB`] (a noise-free record has no finite SNR).
//! 7. **Dark**: a tone is dark when the total light is, `Σ_c Â_c ≤
//!    dark_factor · Σ_c σ_Âc` (pure noise gives `Σ Â ≈ 1.25 Σ σ_Â`), never
//!    because one channel is weak.
//!
//! Before any of it, a sample within one 16-bit step of the full scale
//! (`|x| ≥ FS (1 − 2⁻¹⁵)`) makes the record [`SignalError::Saturated`].
//!
//! # Conventions
//!
//! Volts in, peak volts out; sample `n` of the record at `t = n/fs` after its
//! first sample; every record is demodulated on its own (its own filter
//! start, frequency estimate and noise).

use std::f64::consts::TAU;
use std::ops::Range;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::butterworth::BandPass;
use crate::error::SignalError;
use crate::stream::StreamFilter;
use crate::tones::{check_separable, project_frames};

/// Fewest cycles of the lowest tone in the detection window.
pub const MIN_WINDOW_CYCLES: f64 = 4.0;

/// SNR reported for a noise-free channel (and its negative for a channel
/// with no signal at all), dB.
pub const MAX_SNR_DB: f64 = 200.0;

/// Largest relative clock offset `|ρ|` the frequency estimate trusts.
pub const MAX_CLOCK_OFFSET: f64 = 1e-3;

/// A pass whose step would turn the highest tone by fewer cycles than this
/// over the window ends the estimate without the step: its frequencies and
/// whole-window sums are the fit's (module documentation, step 5).
pub const SETTLED_TURNS: f64 = 1e-9;

/// Most passes of the frequency estimate (each shrinks the offset left by
/// about three orders of magnitude; it stops when a pass moves the highest
/// tone by less than 1e-7 cycles over the window).
pub const MAX_FREQUENCY_PASSES: usize = 4;

/// Parameters of the demodulation; see the module documentation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DemodConfig {
    /// Band-pass bandwidth `B`, Hz (600: the paper's).
    pub bandwidth_hz: f64,
    /// Butterworth order `N` (2).
    pub filter_order: usize,
    /// What is left of the switch-on transient when the window starts
    /// (1e-11).
    pub settle_tolerance: f64,
    /// Sub-windows of the frequency estimate, at least 2 (8).
    pub subwindows: usize,
    /// Estimate the modulation frequency from the record (true).
    pub estimate_frequency: bool,
    /// The ADC's full scale `FS`, V (10: a ±10 V card).
    pub full_scale_v: f64,
    /// The dark threshold, in noise standard deviations of the total (3).
    pub dark_factor: f64,
}

impl Default for DemodConfig {
    fn default() -> Self {
        Self {
            bandwidth_hz: 600.0,
            filter_order: 2,
            settle_tolerance: 1e-11,
            subwindows: 8,
            estimate_frequency: true,
            full_scale_v: 10.0,
            dark_factor: 3.0,
        }
    }
}

impl DemodConfig {
    /// Checks the parameters that the filter design does not.
    pub fn validate(&self) -> Result<(), SignalError> {
        let bad = |name, value: f64, reason| {
            Err(SignalError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if !(self.settle_tolerance > 0.0 && self.settle_tolerance < 1.0) {
            return bad(
                "settle_tolerance",
                self.settle_tolerance,
                "must lie strictly between 0 and 1",
            );
        }
        if self.subwindows < 2 {
            return bad(
                "subwindows",
                self.subwindows as f64,
                "at least 2 sub-windows",
            );
        }
        if !(self.full_scale_v.is_finite() && self.full_scale_v > 0.0) {
            return bad(
                "full_scale_v",
                self.full_scale_v,
                "must be finite and positive",
            );
        }
        if !(self.dark_factor.is_finite() && self.dark_factor >= 0.0) {
            return bad(
                "dark_factor",
                self.dark_factor,
                "must be finite and non-negative",
            );
        }
        Ok(())
    }
}

/// One tone's estimates on every channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ToneEstimate<const C: usize> {
    /// The tone asked for, Hz.
    pub nominal_hz: f64,
    /// The frequency detected at (the estimate, or the nominal one), Hz.
    pub frequency_hz: f64,
    /// Amplitude per channel, peak volts.
    pub amplitudes: [f64; C],
    /// Standard deviation of each amplitude, V.
    pub amplitude_std: [f64; C],
    /// Per-sample SNR per channel, dB (module documentation, step 6).
    pub snr_db: [f64; C],
    /// The total light is at the noise (module documentation, step 7).
    pub dark: bool,
}

impl<const C: usize> ToneEstimate<C> {
    /// The record's SNR: its lowest channel's, dB.
    pub fn min_snr_db(&self) -> f64 {
        self.snr_db.iter().copied().fold(MAX_SNR_DB, f64::min)
    }
}

/// What the demodulation of one record found.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordEstimate<const C: usize> {
    /// One entry per tone, in the order given.
    pub tones: Vec<ToneEstimate<C>>,
    /// The detection window, sample indices in the record.
    pub window: Range<usize>,
    /// Input-equivalent white-noise standard deviation per channel, V.
    pub noise_sigma: [f64; C],
    /// The estimated clock ratio `1 + ρ` (1 when not estimated).
    pub clock_ratio: f64,
}

/// Sums of one detection: the Gram matrix and `Σ y φ` per channel.
struct Detection {
    gram: DMatrix<f64>,
    /// `Σ y φ` per channel (columns).
    b: DMatrix<f64>,
}

impl Detection {
    /// `θ = G⁻¹ b` (columns per channel) and `G⁻¹`; `None` when `G` is not
    /// positive definite (tones not separable in this window).
    fn solve(&self) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let chol = self.gram.clone().cholesky()?;
        let theta = chol.solve(&self.b);
        let inv = chol.inverse();
        theta
            .iter()
            .chain(inv.iter())
            .all(|v| v.is_finite())
            .then_some((theta, inv))
    }
}

/// The sums of the joint fit of `freqs` over `frames` (sample `first` of the
/// record at `frames[0]`): the Gram matrix in closed form, `Σ y φ` in one
/// pass per tone ([`project_frames`]).
fn detect<const C: usize>(
    frames: &[[f64; C]],
    first: usize,
    sample_rate_hz: f64,
    freqs: &[f64],
) -> Detection {
    let p = 2 * freqs.len();
    let gram = closed_form_gram(freqs, sample_rate_hz, first, frames.len());
    let mut b = DMatrix::zeros(p, C);
    for (k, &f) in freqs.iter().enumerate() {
        let [yc, ys] = project_frames(f, sample_rate_hz, first, frames);
        for c in 0..C {
            b[(2 * k, c)] = yc[c];
            b[(2 * k + 1, c)] = ys[c];
        }
    }
    Detection { gram, b }
}

/// `Σ_{n=n0}^{n0+M−1} e^{i 2π r n}` in closed form (the Dirichlet kernel):
/// `e^{i 2π r (n0 + (M−1)/2)} sin(π r M) / sin(π r)`, or `M` when `r` is an
/// integer; every angle reduced to one turn first. Returns (re, im).
fn exp_sum(r: f64, n0: usize, m: usize) -> (f64, f64) {
    use std::f64::consts::PI;
    let r = r - r.round();
    if r == 0.0 {
        return (m as f64, 0.0);
    }
    let centre = n0 as f64 + 0.5 * (m as f64 - 1.0);
    let phase = TAU * (r * centre).rem_euclid(1.0);
    let half_turns = (r * m as f64).rem_euclid(2.0);
    let kernel = (PI * half_turns).sin() / (PI * r).sin();
    (kernel * phase.cos(), kernel * phase.sin())
}

/// The Gram matrix of the basis `(cos 2π f_k n/fs, sin 2π f_k n/fs)_k` over
/// `n = first … first + m − 1`, from the products' sum and difference
/// frequencies in closed form ([`exp_sum`]):
/// `cos a cos b = ½ (cos(a−b) + cos(a+b))`,
/// `sin a sin b = ½ (cos(a−b) − cos(a+b))`,
/// `cos a sin b = ½ (sin(a+b) − sin(a−b))`. `O(K²)` per window instead of
/// `O(K² M)`; equal to the summed products to rounding.
fn closed_form_gram(freqs: &[f64], sample_rate_hz: f64, first: usize, m: usize) -> DMatrix<f64> {
    let p = 2 * freqs.len();
    let mut gram = DMatrix::zeros(p, p);
    for (i, fi) in freqs.iter().enumerate() {
        for (j, fj) in freqs.iter().enumerate().skip(i) {
            let (dr, di) = exp_sum((fi - fj) / sample_rate_hz, first, m);
            let (sr, si) = exp_sum((fi + fj) / sample_rate_hz, first, m);
            let cc = 0.5 * (dr + sr);
            let ss = 0.5 * (dr - sr);
            // cos a_i sin a_j and sin a_i cos a_j.
            let cs = 0.5 * (si - di);
            let sc = 0.5 * (si + di);
            let (ci, sii, cj, sj) = (2 * i, 2 * i + 1, 2 * j, 2 * j + 1);
            gram[(ci, cj)] = cc;
            gram[(cj, ci)] = cc;
            gram[(sii, sj)] = ss;
            gram[(sj, sii)] = ss;
            gram[(ci, sj)] = cs;
            gram[(sj, ci)] = cs;
            gram[(sii, cj)] = sc;
            gram[(cj, sii)] = sc;
        }
    }
    gram
}

/// The relative clock offset `Δρ` seen by `J` sub-windows at `freqs`, with
/// the whole window's `Σ y φ` at `freqs` from the same pass (the sums of the
/// `J` sub-windows and of the `M − J⌊M/J⌋` samples after them); `None` when
/// nothing can be said (no signal, singular sub-fits).
fn clock_offset<const C: usize>(
    window: &[[f64; C]],
    first: usize,
    sample_rate_hz: f64,
    freqs: &[f64],
    subwindows: usize,
) -> Option<(f64, DMatrix<f64>)> {
    let d = window.len() / subwindows;
    let mut previous: Option<DMatrix<f64>> = None;
    // Σ_c Σ_j z_{j+1} z̄_j per tone, as (re, im).
    let mut products = vec![(0.0, 0.0); freqs.len()];
    let rest = subwindows * d;
    let mut whole = detect(&window[rest..], first + rest, sample_rate_hz, freqs).b;
    for j in 0..subwindows {
        let part = &window[j * d..(j + 1) * d];
        let detection = detect(part, first + j * d, sample_rate_hz, freqs);
        whole += &detection.b;
        let (theta, _) = detection.solve()?;
        if let Some(prev) = &previous {
            for (k, acc) in products.iter_mut().enumerate() {
                for c in 0..C {
                    // z = I + iQ; z_{j+1} z̄_j.
                    let (i1, q1) = (theta[(2 * k, c)], theta[(2 * k + 1, c)]);
                    let (i0, q0) = (prev[(2 * k, c)], prev[(2 * k + 1, c)]);
                    acc.0 += i1 * i0 + q1 * q0;
                    acc.1 += q1 * i0 - i1 * q0;
                }
            }
        }
        previous = Some(theta);
    }
    let (mut num, mut den) = (0.0, 0.0);
    for (&(re, im), &f) in products.iter().zip(freqs) {
        let modulus = re.hypot(im);
        if modulus > 0.0 {
            let df = -im.atan2(re) * sample_rate_hz / (std::f64::consts::TAU * d as f64);
            let w = modulus * f * f;
            num += w * df / f;
            den += w;
        }
    }
    (den > 0.0 && num.is_finite()).then(|| (num / den, whole))
}

/// Demodulates one record of `C` channels for the tones `tones_hz` (one
/// tone: time multiplexing; several: frequency multiplexing) sampled at
/// `sample_rate_hz`. See the module documentation for every step.
///
/// Errors: invalid configuration, rate or tones (the band-pass design's
/// errors included); [`SignalError::NoTones`];
/// [`SignalError::NonFiniteSample`]; [`SignalError::Saturated`];
/// [`SignalError::RecordTooShortToDemodulate`];
/// [`SignalError::TonesNotSeparable`].
pub fn demodulate_record<const C: usize>(
    frames: &[[f64; C]],
    sample_rate_hz: f64,
    tones_hz: &[f64],
    config: &DemodConfig,
) -> Result<RecordEstimate<C>, SignalError> {
    config.validate()?;
    let span = ToneSpan::of(tones_hz)?;
    check_separable(tones_hz, sample_rate_hz, f64::INFINITY)?;
    let filter = design_filter(tones_hz, span, sample_rate_hz, config)?;
    let (first, window_len) = window_of(
        frames.len(),
        &filter,
        tones_hz,
        span,
        sample_rate_hz,
        config,
    )?;
    let window_s = window_len as f64 / sample_rate_hz;
    check_separable(tones_hz, sample_rate_hz, window_s)?;
    let filtered = filter_window(frames, filter, first, window_len, config)?;
    let (ratio, settled_sums) = clock_ratio(
        &filtered.window,
        first,
        sample_rate_hz,
        tones_hz,
        span,
        config,
    );
    let freqs: Vec<f64> = tones_hz.iter().map(|f| f * ratio).collect();
    let detection = match settled_sums {
        Some(b) => Detection {
            gram: closed_form_gram(&freqs, sample_rate_hz, first, window_len),
            b,
        },
        None => detect(&filtered.window, first, sample_rate_hz, &freqs),
    };
    let Some((theta, inv)) = detection.solve() else {
        return Err(SignalError::TonesNotSeparable {
            first_hz: span.f_min,
            second_hz: span.f_max,
            spacing_hz: min_spacing(tones_hz),
            window_s,
            minimum_hz: 2.0 / window_s,
        });
    };
    let dof = (window_len - 2 * tones_hz.len()) as f64;
    let noise_sigma = noise_sigma(&filtered, &theta, &detection.b, dof);
    let tones = tone_estimates(
        tones_hz,
        &freqs,
        filtered.stream.filter(),
        &inv,
        &theta,
        &noise_sigma,
        config,
    );
    Ok(RecordEstimate {
        tones,
        window: first..frames.len(),
        noise_sigma,
        clock_ratio: ratio,
    })
}

/// The lowest and highest tone.
#[derive(Debug, Clone, Copy)]
struct ToneSpan {
    f_min: f64,
    f_max: f64,
}

impl ToneSpan {
    /// The span of `tones_hz`; [`SignalError::NoTones`] when empty.
    fn of(tones_hz: &[f64]) -> Result<Self, SignalError> {
        let (f_min, f_max) = tones_hz
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
                (lo.min(f), hi.max(f))
            });
        if tones_hz.is_empty() {
            return Err(SignalError::NoTones);
        }
        Ok(Self { f_min, f_max })
    }
}

/// The band-pass: centred on a single tone, or from the lowest tone's lower
/// edge to the highest's upper edge.
fn design_filter(
    tones_hz: &[f64],
    span: ToneSpan,
    sample_rate_hz: f64,
    config: &DemodConfig,
) -> Result<BandPass, SignalError> {
    if tones_hz.len() == 1 {
        BandPass::centred(
            config.filter_order,
            span.f_min,
            config.bandwidth_hz,
            sample_rate_hz,
        )
    } else {
        BandPass::from_edges(
            config.filter_order,
            span.f_min - 0.5 * config.bandwidth_hz,
            span.f_max + 0.5 * config.bandwidth_hz,
            sample_rate_hz,
        )
    }
}

/// The detection window `(first, length)` of a record of `len` samples:
/// after the filter has settled, whole cycles of a single tone; refused
/// when the record cannot hold the transient and the shortest window.
fn window_of(
    len: usize,
    filter: &BandPass,
    tones_hz: &[f64],
    span: ToneSpan,
    sample_rate_hz: f64,
    config: &DemodConfig,
) -> Result<(usize, usize), SignalError> {
    let settle = (filter.settling_time(config.settle_tolerance) * sample_rate_hz).ceil();
    let min_window = (MIN_WINDOW_CYCLES * sample_rate_hz / span.f_min).ceil();
    let minimum = settle + min_window.max((2 * tones_hz.len() + 2) as f64);
    if (len as f64) < minimum {
        return Err(SignalError::RecordTooShortToDemodulate {
            samples: len,
            minimum: minimum.min(usize::MAX as f64) as usize,
            cycles: MIN_WINDOW_CYCLES,
        });
    }
    let start = settle as usize;
    let window_len = if tones_hz.len() == 1 {
        let cycles = ((len - start) as f64 * span.f_min / sample_rate_hz).floor();
        ((cycles * sample_rate_hz / span.f_min).round() as usize).min(len - start)
    } else {
        len - start
    };
    Ok((len - window_len, window_len))
}

/// A record band-passed from rest: the filter after the record, the
/// filtered window, and `Σ y²` over the window per channel.
struct Filtered<const C: usize> {
    stream: StreamFilter<C>,
    window: Vec<[f64; C]>,
    yy: [f64; C],
}

/// The samples checked and band-passed from rest in chunks that stay in
/// the cache (checked up to the first offender, in sample order), the
/// window from sample `first` kept.
fn filter_window<const C: usize>(
    frames: &[[f64; C]],
    filter: BandPass,
    first: usize,
    window_len: usize,
    config: &DemodConfig,
) -> Result<Filtered<C>, SignalError> {
    let mut stream = StreamFilter::<C>::new(filter);
    let mut scratch_frames = [[0.0; C]; CHUNK];
    let mut window = Vec::with_capacity(window_len);
    // Σ y² over the window per channel, in sample order.
    let mut yy = [0.0; C];
    for (i, chunk) in frames.chunks(CHUNK).enumerate() {
        check_samples(chunk, i * CHUNK, config.full_scale_v)?;
        // The part of the chunk before the window, then the rest.
        let split = first.saturating_sub(i * CHUNK).min(chunk.len());
        let part = &mut scratch_frames[..split];
        part.copy_from_slice(&chunk[..split]);
        stream.process_frames(part);
        let kept = window.len();
        window.extend_from_slice(&chunk[split..]);
        stream.process_frames(&mut window[kept..]);
        for frame in &window[kept..] {
            for c in 0..C {
                yy[c] += frame[c] * frame[c];
            }
        }
    }
    Ok(Filtered { stream, window, yy })
}

/// The clock ratio `1 + ρ` estimated from the phase drift between
/// sub-windows (1 when not estimated or implausible), and the whole
/// window's `Σ y φ` from the last pass when it settled at the frequencies
/// it was run at.
fn clock_ratio<const C: usize>(
    window: &[[f64; C]],
    first: usize,
    sample_rate_hz: f64,
    tones_hz: &[f64],
    span: ToneSpan,
    config: &DemodConfig,
) -> (f64, Option<DMatrix<f64>>) {
    let mut ratio = 1.0;
    let mut settled_sums = None;
    if !config.estimate_frequency {
        return (ratio, settled_sums);
    }
    let window_s = window.len() as f64 / sample_rate_hz;
    let spacing = min_spacing(tones_hz);
    let subwindows = (2..=config.subwindows)
        .rev()
        .find(|&j| spacing >= 2.0 * j as f64 / window_s);
    if let Some(j) = subwindows {
        let mut rho = 0.0;
        for _ in 0..MAX_FREQUENCY_PASSES {
            let freqs: Vec<f64> = tones_hz.iter().map(|f| f * (1.0 + rho)).collect();
            match clock_offset(window, first, sample_rate_hz, &freqs, j) {
                Some((delta, sums)) if delta.abs() <= MAX_CLOCK_OFFSET => {
                    let turns = delta.abs() * span.f_max * window_s;
                    // A step that turns the highest tone by under
                    // SETTLED_TURNS cycles is not taken: the pass's own
                    // frequencies and sums are the result.
                    if turns < SETTLED_TURNS {
                        settled_sums = Some(sums);
                        break;
                    }
                    rho += delta * (1.0 + rho);
                    // Settled when the step turns the highest tone by
                    // under 1e-7 cycles over the window (its effect on an
                    // amplitude is then below 1e-13).
                    if turns < 1e-7 {
                        break;
                    }
                }
                _ => break,
            }
        }
        if rho.abs() <= MAX_CLOCK_OFFSET {
            ratio = 1.0 + rho;
        } else {
            settled_sums = None;
        }
    }
    (ratio, settled_sums)
}

/// The input-equivalent white-noise σ per channel from the fit's residual
/// energy `Σ y² − θᵀb` over `dof` degrees of freedom and the filter's noise
/// gain.
fn noise_sigma<const C: usize>(
    filtered: &Filtered<C>,
    theta: &DMatrix<f64>,
    b: &DMatrix<f64>,
    dof: f64,
) -> [f64; C] {
    let nu = filtered.stream.filter().noise_gain();
    let mut noise_sigma = [0.0; C];
    for (c, sigma) in noise_sigma.iter_mut().enumerate() {
        let fitted: f64 = (0..theta.nrows()).map(|i| theta[(i, c)] * b[(i, c)]).sum();
        *sigma = ((filtered.yy[c] - fitted).max(0.0) / (dof * nu)).sqrt();
    }
    noise_sigma
}

/// Each tone's amplitudes (the fit's quadrature pair through the filter's
/// gain), their σ, SNR and darkness.
fn tone_estimates<const C: usize>(
    tones_hz: &[f64],
    freqs: &[f64],
    filter: &BandPass,
    inv: &DMatrix<f64>,
    theta: &DMatrix<f64>,
    noise_sigma: &[f64; C],
    config: &DemodConfig,
) -> Vec<ToneEstimate<C>> {
    tones_hz
        .iter()
        .zip(freqs)
        .enumerate()
        .map(|(k, (&nominal_hz, &frequency_hz))| {
            let inv_gain = 1.0 / filter.magnitude(frequency_hz);
            let spread = (0.5 * (inv[(2 * k, 2 * k)] + inv[(2 * k + 1, 2 * k + 1)])).sqrt();
            let mut amplitudes = [0.0; C];
            let mut amplitude_std = [0.0; C];
            let mut snr_db = [0.0; C];
            for c in 0..C {
                amplitudes[c] = theta[(2 * k, c)].hypot(theta[(2 * k + 1, c)]) * inv_gain;
                amplitude_std[c] = noise_sigma[c] * spread;
                snr_db[c] = snr(amplitudes[c], noise_sigma[c]);
            }
            let total: f64 = amplitudes.iter().sum();
            let noise: f64 = amplitude_std.iter().sum();
            ToneEstimate {
                nominal_hz,
                frequency_hz,
                amplitudes,
                amplitude_std,
                snr_db,
                dark: total <= config.dark_factor * noise,
            }
        })
        .collect()
}

/// `10 log10((Â²/2) / σ²)` clamped to `±MAX_SNR_DB` (0/0 counts as no
/// signal).
fn snr(amplitude: f64, sigma: f64) -> f64 {
    let value = 10.0 * (amplitude * amplitude / (2.0 * sigma * sigma)).log10();
    if value.is_nan() {
        -MAX_SNR_DB
    } else {
        value.clamp(-MAX_SNR_DB, MAX_SNR_DB)
    }
}

/// The smallest spacing between two tones (infinite for one tone).
fn min_spacing(tones_hz: &[f64]) -> f64 {
    let mut sorted = tones_hz.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min)
}

/// Frames band-passed and checked at a time (8 KiB of 4-channel frames).
const CHUNK: usize = 256;

/// Non-finite samples and samples at the ADC's rails in `frames` (sample
/// `offset` of the record at `frames[0]`): a branch-free scan (`|x| < rail`
/// fails for both), then the first offender located.
fn check_samples<const C: usize>(
    frames: &[[f64; C]],
    offset: usize,
    full_scale_v: f64,
) -> Result<(), SignalError> {
    let rail = full_scale_v * (1.0 - 2f64.powi(-15));
    let mut clean = true;
    for frame in frames {
        for v in frame {
            clean &= v.abs() < rail;
        }
    }
    if clean {
        return Ok(());
    }
    for (i, frame) in frames.iter().enumerate() {
        let sample = offset + i;
        for (channel, &value) in frame.iter().enumerate() {
            if !value.is_finite() {
                return Err(SignalError::NonFiniteSample { channel, sample });
            }
            if value.abs() >= rail {
                return Err(SignalError::Saturated {
                    channel,
                    sample,
                    value,
                    full_scale_v,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form Gram matrix against the summed products of directly
    /// computed sinusoids.
    #[test]
    fn closed_form_gram_equals_the_summed_products() {
        let fs = 20_000.0;
        for (freqs, first, m) in [
            (vec![1000.0], 479, 821),
            (vec![675.0, 725.0, 1000.0, 1325.0], 300, 3700),
            (vec![999.97, 1234.5], 12_345, 999),
        ] {
            let gram = closed_form_gram(&freqs, fs, first, m);
            let basis: Vec<Vec<f64>> = freqs
                .iter()
                .flat_map(|f| {
                    let arg = |n: usize| TAU * f * n as f64 / fs;
                    [
                        (first..first + m).map(|n| arg(n).cos()).collect::<Vec<_>>(),
                        (first..first + m).map(|n| arg(n).sin()).collect(),
                    ]
                })
                .collect();
            for (i, a) in basis.iter().enumerate() {
                for (j, b) in basis.iter().enumerate() {
                    let direct: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
                    assert!(
                        (gram[(i, j)] - direct).abs() < 1e-9 * m as f64 * 1e-3,
                        "{freqs:?} ({i}, {j}): {} vs {direct}",
                        gram[(i, j)]
                    );
                }
            }
        }
    }
}
