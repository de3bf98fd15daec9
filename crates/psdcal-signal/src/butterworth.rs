//! Digital Butterworth band-pass filters (docs/model.md §6: "Butterworth, 600 Hz
//! bandwidth centred on f0"), designed from the analog prototype and realised
//! as cascaded second-order sections.
//!
//! # Conventions
//!
//! Frequencies in Hz, the sample rate `fs` in samples per second, time in
//! seconds; signals in volts or any consistent amplitude unit (the filter is
//! linear and dimensionless). `ω = 2π f / fs` is the digital angular frequency
//! in radians per sample and `z = e^{jω}`.
//!
//! # Design equations
//!
//! 1. **Band edges.** The −3 dB edges `f_lo < f_hi` are given directly
//!    ([`BandPass::from_edges`]) or derived from a centre `f0` and a bandwidth
//!    `B` ([`BandPass::centred`]); see [`BandPlacement`].
//! 2. **Pre-warping.** The bilinear transform used below,
//!    `s = (1 − z⁻¹)/(1 + z⁻¹)`, maps the digital frequency `f` onto the
//!    analog frequency `Ω = tan(π f / fs)` (the usual `2 fs` factor is absorbed
//!    into `Ω`, which leaves the result unchanged). The analog edges are
//!    therefore `Ω_lo = tan(π f_lo / fs)`, `Ω_hi = tan(π f_hi / fs)`, which
//!    puts the digital −3 dB points exactly on `f_lo` and `f_hi`. The analog
//!    band-pass has centre `Ω0 = √(Ω_lo Ω_hi)` and width `W = Ω_hi − Ω_lo`.
//! 3. **Low-pass prototype.** The order-`N` Butterworth low-pass with unit
//!    cut-off, `|H_LP(jΩ)|² = 1 / (1 + Ω^{2N})`, has the `N` left-half-plane
//!    poles `p_k = exp(jπ (2k + N + 1) / (2N))`, `k = 0 … N−1`, and
//!    `H_LP(p) = Π_k 1/(p − p_k)` (so `H_LP(0) = 1`, since `Π(−p_k) = 1`).
//! 4. **Low-pass → band-pass.** Substituting `p = (s² + Ω0²) / (W s)` turns
//!    each prototype factor into `W s / (s² − p_k W s + Ω0²)`: every prototype
//!    pole gives the two band-pass poles `s = (p_k W ± √(p_k² W² − 4 Ω0²)) / 2`,
//!    `N` zeros land at `s = 0` and `N` at `s = ∞` (2N poles in all). Complex
//!    poles are grouped into conjugate pairs, each pair with one factor `W s`
//!    of the numerator, giving `N` real analog sections
//!    `H_i(s) = W s / (s² + c1 s + c0)` with `c1 = −2 Re s_i`, `c0 = |s_i|²`
//!    (for odd `N` the real prototype pole `−1` gives directly
//!    `c1 = W`, `c0 = Ω0²`). The analog response is
//!    `|H(jΩ)|² = 1 / (1 + ((Ω² − Ω0²) / (W Ω))^{2N})`: 1 at `Ω0`, 1/2 at
//!    `Ω_lo` and `Ω_hi`, and the same at `Ω` and `Ω0² / Ω` (geometric
//!    symmetry).
//! 5. **Bilinear transform** of each section, multiplying through by
//!    `(1 + z⁻¹)²`:
//!    `H_i(z) = W (1 − z⁻²) / (d0 + d1 z⁻¹ + d2 z⁻²)` with
//!    `d0 = 1 + c1 + c0`, `d1 = 2 (c0 − 1)`, `d2 = 1 − c1 + c0`; stored
//!    normalised, `b = [W, 0, −W] / d0`, `a = [1, d1/d0, d2/d0]`. The zeros sit
//!    at `z = ±1` (DC and Nyquist are blocked), and the poles inside the unit
//!    circle (the bilinear map sends the open left half-plane into the unit
//!    disc).
//! 6. **Normalisation.** The gain is 1 and the phase 0 at the pre-warped
//!    geometric centre `f_c = (fs/π) atan(Ω0)` in exact arithmetic; the
//!    numerators are still rescaled by `|H(e^{j 2π f_c / fs})|^{−1/N}` each so
//!    that the realised cascade has unit gain there to rounding error.
//! 7. **Filtering**: each section in direct form II transposed, from a zero
//!    state,
//!    `y[n] = b0 x[n] + z1`, `z1 ← b1 x[n] − a1 y[n] + z2`,
//!    `z2 ← b2 x[n] − a2 y[n]`, the sections in cascade.
//!
//! The transient after switching a signal on decays like `|z_max|^n`, `z_max`
//! the pole of largest modulus: [`BandPass::decay_rate`] gives the rate in
//! 1/s — about `π B sin(π / (2N))` for a narrow band of width `B` Hz
//! (`B ≪ f0`); for 600 Hz around 1 kHz the pole pairs split and the slowest
//! decays at 1058 /s for `N = 2` (1333 by the narrow-band estimate) — and
//! [`BandPass::settling_time`] the time to fall below a relative tolerance.

use nalgebra::Complex;
use serde::{Deserialize, Serialize};

use crate::error::SignalError;

/// Largest supported filter order `N` (the cascade has `N` second-order
/// sections, i.e. `2N` poles).
pub const MAX_ORDER: usize = 16;

/// Where the pass band lies relative to a centre `f0` and a bandwidth `B`
/// (both in Hz).
///
/// A Butterworth band-pass is symmetric about the *geometric* centre of its
/// (pre-warped) edges, so "−3 dB edges at exactly `f0 ∓ B/2`" and "unit gain
/// and zero phase at exactly `f0`" cannot both hold; the two placements
/// choose one or the other. The signal chain compensates the gain at `f0`
/// in both cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum BandPlacement {
    /// `f0` is the pre-warped geometric centre of the edges,
    /// `tan(π f_lo/fs) · tan(π f_hi/fs) = tan²(π f0/fs)`, and
    /// `f_hi − f_lo = B` exactly. Unit gain and zero phase at `f0`, the peak
    /// of the response; the edges sit slightly above `f0 ∓ B/2`
    /// (742.6 Hz and 1342.6 Hz for `f0` = 1 kHz, `B` = 600 Hz, `fs` = 20 kHz).
    /// Closed form: with `β = π B / fs` and `θ0 = π f0 / fs`,
    /// `π (f_lo + f_hi) / fs = acos(cos β · cos 2θ0)`.
    #[default]
    Geometric,
    /// The edges are exactly `f0 − B/2` and `f0 + B/2` (what a design from
    /// the two edge frequencies gives). The peak (unit gain) is then at the
    /// pre-warped geometric mean of the edges, below `f0` (955.4 Hz for
    /// 700–1300 Hz at 20 kHz); the gain at `f0` is slightly below 1 (0.98963
    /// for order 1, 0.99978 for order 2).
    Arithmetic,
}

/// One second-order section `H(z) = (b0 + b1 z⁻¹ + b2 z⁻²) / (1 + a1 z⁻¹ + a2 z⁻²)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Biquad {
    /// Numerator `[b0, b1, b2]`.
    pub b: [f64; 3],
    /// Denominator `[1, a1, a2]` (`a[0]` is always 1).
    pub a: [f64; 3],
}

impl Biquad {
    /// One step of direct form II transposed: consumes `x`, updates the two
    /// state variables `z`, returns the output.
    #[inline(always)]
    pub fn step(&self, x: f64, z: &mut [f64; 2]) -> f64 {
        let y = self.b[0] * x + z[0];
        z[0] = self.b[1] * x - self.a[1] * y + z[1];
        z[1] = self.b[2] * x - self.a[2] * y;
        y
    }

    /// Complex gain at `z⁻¹ = z_inv`.
    pub fn response_at(&self, z_inv: Complex<f64>) -> Complex<f64> {
        let z2 = z_inv * z_inv;
        let num = z_inv * self.b[1] + z2 * self.b[2] + self.b[0];
        let den = z_inv * self.a[1] + z2 * self.a[2] + self.a[0];
        num / den
    }

    /// The two poles in the z plane, roots of `z² + a1 z + a2`.
    pub fn poles(&self) -> [Complex<f64>; 2] {
        let disc = Complex::new(self.a[1] * self.a[1] - 4.0 * self.a[2], 0.0).sqrt();
        let half = Complex::new(-0.5 * self.a[1], 0.0);
        [half + disc * 0.5, half - disc * 0.5]
    }
}

/// A digital Butterworth band-pass filter of order `N` (`2N` poles) as `N`
/// cascaded [`Biquad`] sections. See the [module documentation](self) for the
/// design equations. Built only by the validating constructors.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandPass {
    sections: Vec<Biquad>,
    sample_rate_hz: f64,
    low_hz: f64,
    high_hz: f64,
    centre_hz: f64,
}

/// The running state of a [`BandPass`] (two variables per section, no heap
/// allocation), for sample-by-sample filtering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilterState {
    z: [[f64; 2]; MAX_ORDER],
}

impl Default for FilterState {
    fn default() -> Self {
        Self::new()
    }
}

impl FilterState {
    /// The zero state (the filter at rest).
    pub const fn new() -> Self {
        Self {
            z: [[0.0; 2]; MAX_ORDER],
        }
    }

    /// Back to the zero state.
    pub fn reset(&mut self) {
        self.z = [[0.0; 2]; MAX_ORDER];
    }

    /// Filters one sample through every section of `filter`.
    #[inline(always)]
    pub fn process(&mut self, filter: &BandPass, x: f64) -> f64 {
        let mut y = x;
        for (section, z) in filter.sections.iter().zip(self.z.iter_mut()) {
            y = section.step(y, z);
        }
        y
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> SignalError {
    SignalError::InvalidParameter {
        name,
        value,
        reason,
    }
}

fn check_order(order: usize) -> Result<(), SignalError> {
    if order == 0 || order > MAX_ORDER {
        return Err(SignalError::InvalidOrder {
            order,
            max: MAX_ORDER,
        });
    }
    Ok(())
}

fn check_sample_rate(sample_rate_hz: f64) -> Result<(), SignalError> {
    if !sample_rate_hz.is_finite() || sample_rate_hz <= 0.0 {
        return Err(invalid(
            "sample_rate_hz",
            sample_rate_hz,
            "must be finite and positive",
        ));
    }
    Ok(())
}

/// Edges `(f_lo, f_hi)` of the [`BandPlacement::Geometric`] band, Hz.
fn geometric_edges(centre_hz: f64, bandwidth_hz: f64, sample_rate_hz: f64) -> (f64, f64) {
    let beta = std::f64::consts::PI * bandwidth_hz / sample_rate_hz;
    let theta0 = std::f64::consts::PI * centre_hz / sample_rate_hz;
    let sum = (beta.cos() * (2.0 * theta0).cos()).clamp(-1.0, 1.0).acos();
    let scale = sample_rate_hz / std::f64::consts::PI;
    (0.5 * (sum - beta) * scale, 0.5 * (sum + beta) * scale)
}

fn placed_edges(
    centre_hz: f64,
    bandwidth_hz: f64,
    sample_rate_hz: f64,
    placement: BandPlacement,
) -> (f64, f64) {
    match placement {
        BandPlacement::Geometric => geometric_edges(centre_hz, bandwidth_hz, sample_rate_hz),
        BandPlacement::Arithmetic => (
            centre_hz - 0.5 * bandwidth_hz,
            centre_hz + 0.5 * bandwidth_hz,
        ),
    }
}

impl BandPass {
    /// Band-pass of order `order` around `centre_hz` with bandwidth
    /// `bandwidth_hz` (the distance between the −3 dB edges), placed as
    /// [`BandPlacement::Geometric`]: unit gain and zero phase at `centre_hz`.
    pub fn centred(
        order: usize,
        centre_hz: f64,
        bandwidth_hz: f64,
        sample_rate_hz: f64,
    ) -> Result<Self, SignalError> {
        Self::design(
            order,
            centre_hz,
            bandwidth_hz,
            sample_rate_hz,
            BandPlacement::Geometric,
        )
    }

    /// Band-pass of order `order` around `centre_hz` with bandwidth
    /// `bandwidth_hz`, placed as `placement`.
    ///
    /// Errors: order 0 or above [`MAX_ORDER`]; a non-finite or non-positive
    /// frequency; `bandwidth_hz ≥ 2 · centre_hz`; an upper edge at or above
    /// the Nyquist frequency `fs/2`.
    pub fn design(
        order: usize,
        centre_hz: f64,
        bandwidth_hz: f64,
        sample_rate_hz: f64,
        placement: BandPlacement,
    ) -> Result<Self, SignalError> {
        check_order(order)?;
        check_sample_rate(sample_rate_hz)?;
        if !centre_hz.is_finite() || centre_hz <= 0.0 {
            return Err(invalid("f0_hz", centre_hz, "must be finite and positive"));
        }
        if !bandwidth_hz.is_finite() || bandwidth_hz <= 0.0 {
            return Err(invalid(
                "bandwidth_hz",
                bandwidth_hz,
                "must be finite and positive",
            ));
        }
        if bandwidth_hz >= 2.0 * centre_hz {
            return Err(SignalError::BandwidthTooWide {
                bandwidth_hz,
                f0_hz: centre_hz,
            });
        }
        let nyquist_hz = 0.5 * sample_rate_hz;
        // Both placements need the centre and the whole band below Nyquist;
        // checked first so that the closed form below stays in its domain.
        if centre_hz + 0.5 * bandwidth_hz >= nyquist_hz || bandwidth_hz >= nyquist_hz {
            return Err(SignalError::BandAboveNyquist {
                high_hz: centre_hz + 0.5 * bandwidth_hz,
                nyquist_hz,
            });
        }
        let (low, high) = placed_edges(centre_hz, bandwidth_hz, sample_rate_hz, placement);
        Self::from_edges(order, low, high, sample_rate_hz)
    }

    /// [`BandPass::design`] for arguments already validated by the caller
    /// (the signal chain's configuration check implies the filter's).
    pub fn design_valid(
        order: usize,
        centre_hz: f64,
        bandwidth_hz: f64,
        sample_rate_hz: f64,
        placement: BandPlacement,
    ) -> Self {
        let (low, high) = placed_edges(centre_hz, bandwidth_hz, sample_rate_hz, placement);
        Self::from_valid_edges(order, low, high, sample_rate_hz)
    }

    /// Band-pass of order `order` with its −3 dB edges exactly at `low_hz`
    /// and `high_hz`; unit gain at their pre-warped geometric mean
    /// [`BandPass::centre_hz`].
    ///
    /// Errors: order 0 or above [`MAX_ORDER`]; unless
    /// `0 < low_hz < high_hz < fs/2`, all finite.
    pub fn from_edges(
        order: usize,
        low_hz: f64,
        high_hz: f64,
        sample_rate_hz: f64,
    ) -> Result<Self, SignalError> {
        check_order(order)?;
        check_sample_rate(sample_rate_hz)?;
        if !low_hz.is_finite() || low_hz <= 0.0 {
            return Err(invalid(
                "low_hz",
                low_hz,
                "the lower band edge must be finite and positive",
            ));
        }
        if !high_hz.is_finite() || high_hz <= low_hz {
            return Err(invalid(
                "high_hz",
                high_hz,
                "the upper band edge must be finite and above the lower",
            ));
        }
        let nyquist_hz = 0.5 * sample_rate_hz;
        if high_hz >= nyquist_hz {
            return Err(SignalError::BandAboveNyquist {
                high_hz,
                nyquist_hz,
            });
        }
        Ok(Self::from_valid_edges(
            order,
            low_hz,
            high_hz,
            sample_rate_hz,
        ))
    }

    /// The design proper; every argument already validated.
    fn from_valid_edges(order: usize, low_hz: f64, high_hz: f64, sample_rate_hz: f64) -> Self {
        use std::f64::consts::PI;
        let w_lo = (PI * low_hz / sample_rate_hz).tan();
        let w_hi = (PI * high_hz / sample_rate_hz).tan();
        let w0_sq = w_lo * w_hi;
        let w = w_hi - w_lo;
        // Analog sections W s / (s² + c1 s + c0).
        let mut analog: Vec<(f64, f64)> = Vec::with_capacity(order);
        for k in 0..order / 2 {
            // Upper-half-plane prototype poles; their conjugates give the
            // conjugate band-pass poles, paired into the same sections.
            let angle = PI * (2 * k + order + 1) as f64 / (2 * order) as f64;
            let p = Complex::from_polar(1.0, angle);
            let disc = (p * p * (w * w) - Complex::new(4.0 * w0_sq, 0.0)).sqrt();
            for s in [(p * w + disc) * 0.5, (p * w - disc) * 0.5] {
                analog.push((-2.0 * s.re, s.norm_sqr()));
            }
        }
        if order % 2 == 1 {
            analog.push((w, w0_sq));
        }
        let sections: Vec<Biquad> = analog
            .into_iter()
            .map(|(c1, c0)| {
                let d0 = 1.0 + c1 + c0;
                Biquad {
                    b: [w / d0, 0.0, -w / d0],
                    a: [1.0, 2.0 * (c0 - 1.0) / d0, (1.0 - c1 + c0) / d0],
                }
            })
            .collect();
        let centre_hz = sample_rate_hz * w0_sq.sqrt().atan() / PI;
        let mut filter = Self {
            sections,
            sample_rate_hz,
            low_hz,
            high_hz,
            centre_hz,
        };
        let gain = filter.magnitude(centre_hz);
        if gain.is_finite() && gain > 0.0 {
            let scale = gain.powf(-1.0 / order as f64);
            for section in &mut filter.sections {
                section.b[0] *= scale;
                section.b[2] *= scale;
            }
        }
        filter
    }

    /// The second-order sections, in cascade order.
    pub fn sections(&self) -> &[Biquad] {
        &self.sections
    }

    /// Order `N` of the Butterworth prototype (the number of sections).
    pub fn order(&self) -> usize {
        self.sections.len()
    }

    /// Sample rate `fs`, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// The −3 dB edges `(f_lo, f_hi)`, Hz.
    pub fn band_edges_hz(&self) -> (f64, f64) {
        (self.low_hz, self.high_hz)
    }

    /// The pre-warped geometric centre `f_c = (fs/π) atan(√(Ω_lo Ω_hi))`, Hz:
    /// where the gain is 1 and the phase 0.
    pub fn centre_hz(&self) -> f64 {
        self.centre_hz
    }

    /// Complex gain `H(e^{j 2π f / fs})` at `f_hz`.
    pub fn response(&self, f_hz: f64) -> Complex<f64> {
        let omega = 2.0 * std::f64::consts::PI * f_hz / self.sample_rate_hz;
        let z_inv = Complex::from_polar(1.0, -omega);
        self.sections
            .iter()
            .fold(Complex::new(1.0, 0.0), |acc, s| acc * s.response_at(z_inv))
    }

    /// Gain magnitude `|H|` at `f_hz`.
    pub fn magnitude(&self, f_hz: f64) -> f64 {
        self.response(f_hz).norm()
    }

    /// Phase of `H` at `f_hz`, radians in `(−π, π]`.
    pub fn phase(&self, f_hz: f64) -> f64 {
        self.response(f_hz).arg()
    }

    /// The `2N` poles in the z plane (all strictly inside the unit circle).
    pub fn poles(&self) -> Vec<Complex<f64>> {
        self.sections.iter().flat_map(|s| s.poles()).collect()
    }

    /// Slowest decay rate of the transient, 1/s: `−fs · ln |z_max|` over the
    /// poles. A transient falls by `e` every `1 / decay_rate()` seconds.
    pub fn decay_rate(&self) -> f64 {
        let max_modulus = self.poles().iter().map(|p| p.norm()).fold(0.0, f64::max);
        -self.sample_rate_hz * max_modulus.ln()
    }

    /// Time, s, for a transient to fall by the factor `tolerance`
    /// (`ln(1/tolerance) / decay_rate()`); `tolerance` is clamped to
    /// `[1e-300, 1]`.
    pub fn settling_time(&self, tolerance: f64) -> f64 {
        let tol = if tolerance.is_nan() {
            1.0
        } else {
            tolerance.clamp(1e-300, 1.0)
        };
        -tol.ln() / self.decay_rate()
    }

    /// Noise gain `Σ h[n]²` of the impulse response: white noise of variance
    /// `σ²` leaves the filter (in steady state) with variance `σ² Σ h[n]²`.
    /// Summed until the impulse response has decayed by 1e-10 in amplitude
    /// (at most 10⁷ samples).
    pub fn noise_gain(&self) -> f64 {
        let samples = (self.settling_time(1e-10) * self.sample_rate_hz)
            .ceil()
            .clamp(16.0, 1e7) as usize;
        let mut state = FilterState::new();
        let mut sum = 0.0;
        for n in 0..samples {
            let y = state.process(self, if n == 0 { 1.0 } else { 0.0 });
            sum += y * y;
        }
        sum
    }

    /// Equivalent noise bandwidth, Hz: `noise_gain() · fs / 2`, the width of
    /// the rectangular unit-gain band that passes the same white-noise power.
    /// The analog Butterworth band-pass of width `B` has
    /// `B · (π / 2N) / sin(π / 2N)`.
    pub fn equivalent_noise_bandwidth_hz(&self) -> f64 {
        0.5 * self.noise_gain() * self.sample_rate_hz
    }

    /// Filters `data` in place from the zero state (the filter at rest before
    /// the first sample).
    pub fn filter(&self, data: &mut [f64]) {
        for section in &self.sections {
            let mut z = [0.0; 2];
            for x in data.iter_mut() {
                *x = section.step(*x, &mut z);
            }
        }
    }
}
