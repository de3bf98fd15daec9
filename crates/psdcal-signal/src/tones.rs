//! Tones: the reference sinusoids of the detection and the rules a set of
//! tones must follow to be separated in one window (frequency multiplexing,
//! docs/model.md §8).
//!
//! # Reference values
//!
//! `c_n = cos(2π f n / fs)`, `s_n = sin(2π f n / fs)` with `n` counted from the
//! record's first sample. At the start of every block of [`RESYNC`] samples
//! four values are computed directly (the argument `n f / fs` reduced to one
//! turn first); the others by rotation from the value four samples earlier,
//! `(c, s) ← (c cos 4ω − s sin 4ω, s cos 4ω + c sin 4ω)`, `ω = 2π f/fs` (four
//! independent recursions the processor overlaps). Each recursion runs
//! `RESYNC/4` = 32 steps and its rounding grows by about 1e-16 a step, so the
//! values stay within ~1e-14 of the direct ones, at a fraction of the cost.
//!
//! # Separability
//!
//! Over a window of `T` seconds the least-squares detector resolves two tones
//! when they are at least `2 / T` Hz apart (twice the width of the
//! rectangular window's main lobe half-width `1/T`): closer tones make the
//! joint normal equations nearly singular and amplify the noise.
//! [`check_separable`] refuses such sets, naming the closest pair.

use std::f64::consts::TAU;

use crate::error::SignalError;

/// Every this many samples the reference is recomputed directly.
pub const RESYNC: usize = 128;

/// Fills `cos[i]`, `sin[i]` with the reference of the tone `frequency_hz` at
/// sample `first + i` (sample rate `sample_rate_hz`); the two slices are
/// filled over their common length.
pub fn fill_reference(
    frequency_hz: f64,
    sample_rate_hz: f64,
    first: usize,
    cos: &mut [f64],
    sin: &mut [f64],
) {
    let ratio = frequency_hz / sample_rate_hz;
    // Four interleaved rotations by 4ω: independent recursions, so the
    // processor overlaps them.
    let (sw, cw) = (TAU * 4.0 * ratio).sin_cos();
    let len = cos.len().min(sin.len());
    let (cos, sin) = (&mut cos[..len], &mut sin[..len]);
    let mut start = 0;
    while start < len {
        let end = (start + RESYNC).min(len);
        let (mut c, mut s) = lane_phases(first + start, ratio);
        let mut i = start;
        while i + LANES <= end {
            for lane in 0..LANES {
                cos[i + lane] = c[lane];
                sin[i + lane] = s[lane];
                let next_c = c[lane] * cw - s[lane] * sw;
                s[lane] = s[lane] * cw + c[lane] * sw;
                c[lane] = next_c;
            }
            i += LANES;
        }
        let rest = end - i;
        cos[i..end].copy_from_slice(&c[..rest]);
        sin[i..end].copy_from_slice(&s[..rest]);
        start = end;
    }
}

/// Interleaved rotations in [`fill_reference`].
const LANES: usize = 4;

/// `(sin, cos)` of the reference's phase `2π · ratio · n` at the frames
/// `n = first .. first + LANES`, each computed afresh (the recursions
/// restart from these every `RESYNC` frames, so rounding cannot build up).
#[inline]
fn lane_phases(first: usize, ratio: f64) -> ([f64; LANES], [f64; LANES]) {
    let (mut s, mut c) = ([0.0; LANES], [0.0; LANES]);
    for lane in 0..LANES {
        let arg = TAU * (((first + lane) as f64) * ratio).fract();
        (s[lane], c[lane]) = arg.sin_cos();
    }
    (c, s)
}

/// The projections `(Σ_i y_i[c] c_{first+i}, Σ_i y_i[c] s_{first+i})` of every
/// channel `c` of `frames` on the reference of the tone `frequency_hz`, the
/// reference generated on the fly exactly as [`fill_reference`] fills it
/// (the same values) and never stored: one pass over the frames for both
/// quadratures and every channel. The products are summed in four
/// interleaved partial sums by frame index modulo 4 (independent additions
/// the processor overlaps), the last `len mod 4` frames in a fifth, added
/// first: `tail + ((p₀ + p₁) + (p₂ + p₃))`.
pub fn project_frames<const C: usize>(
    frequency_hz: f64,
    sample_rate_hz: f64,
    first: usize,
    frames: &[[f64; C]],
) -> [[f64; C]; 2] {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked just above).
        return unsafe { project_frames_avx2(frequency_hz, sample_rate_hz, first, frames) };
    }
    project_frames_plain(frequency_hz, sample_rate_hz, first, frames)
}

/// [`project_frames`] compiled for AVX2 (four channels in one register; no
/// fused multiply-add, so the same operations and the same results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn project_frames_avx2<const C: usize>(
    frequency_hz: f64,
    sample_rate_hz: f64,
    first: usize,
    frames: &[[f64; C]],
) -> [[f64; C]; 2] {
    project_frames_plain(frequency_hz, sample_rate_hz, first, frames)
}

/// The body of [`project_frames`].
#[inline(always)]
fn project_frames_plain<const C: usize>(
    frequency_hz: f64,
    sample_rate_hz: f64,
    first: usize,
    frames: &[[f64; C]],
) -> [[f64; C]; 2] {
    let ratio = frequency_hz / sample_rate_hz;
    let (sw, cw) = (TAU * 4.0 * ratio).sin_cos();
    let len = frames.len();
    let mut acc_c = [[0.0; C]; LANES];
    let mut acc_s = [[0.0; C]; LANES];
    let mut tail_c = [0.0; C];
    let mut tail_s = [0.0; C];
    let mut start = 0;
    while start < len {
        let end = (start + RESYNC).min(len);
        let (mut c, mut s) = lane_phases(first + start, ratio);
        let body = start + (end - start) / LANES * LANES;
        for group in frames[start..body].chunks_exact(LANES) {
            for lane in 0..LANES {
                let frame = &group[lane];
                for ch in 0..C {
                    acc_c[lane][ch] += frame[ch] * c[lane];
                    acc_s[lane][ch] += frame[ch] * s[lane];
                }
                let next_c = c[lane] * cw - s[lane] * sw;
                s[lane] = s[lane] * cw + c[lane] * sw;
                c[lane] = next_c;
            }
        }
        for (k, frame) in frames[body..end].iter().enumerate() {
            for ch in 0..C {
                tail_c[ch] += frame[ch] * c[k];
                tail_s[ch] += frame[ch] * s[k];
            }
        }
        start = end;
    }
    let mut out = [tail_c, tail_s];
    for (sums, acc) in out.iter_mut().zip([&acc_c, &acc_s]) {
        for ch in 0..C {
            sums[ch] += (acc[0][ch] + acc[1][ch]) + (acc[2][ch] + acc[3][ch]);
        }
    }
    out
}

/// Checks that the tones `frequencies_hz` are finite, positive, below the
/// Nyquist frequency and pairwise at least `2 / window_s` apart.
///
/// Errors: [`SignalError::InvalidParameter`] for a bad tone,
/// [`SignalError::BandAboveNyquist`], or [`SignalError::TonesNotSeparable`]
/// with the closest pair.
pub fn check_separable(
    frequencies_hz: &[f64],
    sample_rate_hz: f64,
    window_s: f64,
) -> Result<(), SignalError> {
    for &f in frequencies_hz {
        if !f.is_finite() || f <= 0.0 {
            return Err(SignalError::InvalidParameter {
                name: "frequency_hz",
                value: f,
                reason: "a tone must be finite and positive",
            });
        }
        if f >= 0.5 * sample_rate_hz {
            return Err(SignalError::BandAboveNyquist {
                high_hz: f,
                nyquist_hz: 0.5 * sample_rate_hz,
            });
        }
    }
    let mut sorted = frequencies_hz.to_vec();
    sorted.sort_by(f64::total_cmp);
    let minimum_hz = 2.0 / window_s;
    let closest = sorted
        .windows(2)
        .map(|w| (w[0], w[1]))
        .min_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)));
    match closest {
        Some((first_hz, second_hz))
            if (second_hz - first_hz) < minimum_hz || minimum_hz.is_nan() =>
        {
            Err(SignalError::TonesNotSeparable {
                first_hz,
                second_hz,
                spacing_hz: second_hz - first_hz,
                window_s,
                minimum_hz,
            })
        }
        _ => Ok(()),
    }
}
