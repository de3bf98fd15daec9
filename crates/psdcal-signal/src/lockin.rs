//! Synchronous (lock-in) I/Q detection of one tone over a fixed window of a
//! record: the least-squares fit of a sinusoid at a known frequency.
//!
//! # Conventions
//!
//! Sample `n = 0 … L−1` at `t = n / fs`; the reference tables are
//! `c_n = cos(2π f n / fs)`, `s_n = sin(2π f n / fs)` (the argument reduced
//! to one turn before scaling, so long records keep full accuracy). The
//! window is `W = [n_s, L)`, `M = L − n_s` samples.
//!
//! # Equations
//!
//! The fit `y[n] ≈ I c_n + Q s_n` over `W` solves the normal equations
//! `G (I, Q)ᵀ = Σ_W y[n] (c_n, s_n)ᵀ` with the Gram matrix
//! `G = Σ_W (c_n, s_n)ᵀ (c_n, s_n)`; `(I, Q)ᵀ = G⁻¹ Σ_W y (c, s)ᵀ`. When the
//! window holds whole cycles of an integer number of samples each,
//! `G = (M/2)·1` and the fit is the textbook `I = (2/M) Σ y c`,
//! `Q = (2/M) Σ y s`; otherwise `G⁻¹` removes the cross-talk between the two
//! quadratures exactly. A pure `A sin(2π f n/fs + φ)` gives
//! `(I, Q) = A (sin φ, cos φ)` and the amplitude is `√(I² + Q²)`.
//! [`IqSums`] also keeps `Σ_W y²` (the RMS estimate `√(2 Σ y² / M)`).

use std::f64::consts::TAU;

use crate::error::SignalError;

/// The window sums `Σ y c`, `Σ y s`, `Σ y²` of a lock-in detection.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct IqSums {
    /// `Σ_W y[n] c_n`.
    pub yc: f64,
    /// `Σ_W y[n] s_n`.
    pub ys: f64,
    /// `Σ_W y[n]²`.
    pub yy: f64,
}

impl IqSums {
    /// Adds one sample `y` with its reference values `c`, `s`.
    #[inline(always)]
    pub fn add(&mut self, y: f64, c: f64, s: f64) {
        self.yc += y * c;
        self.ys += y * s;
        self.yy += y * y;
    }
}

/// A lock-in detector for one tone over the window `[n_s, L)` of records of
/// `L` samples: the reference tables and the inverse Gram matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct LockIn {
    cos: Vec<f64>,
    sin: Vec<f64>,
    window_start: usize,
    gram_inv: [[f64; 2]; 2],
}

impl LockIn {
    /// The detector of the tone `frequency_hz` sampled at `sample_rate_hz`
    /// over `[window_start, record_len)`.
    ///
    /// Errors: a non-finite or non-positive frequency or rate, a tone at or
    /// above Nyquist, a window of fewer than 3 samples (the Gram matrix is
    /// then singular or nearly so).
    pub fn new(
        frequency_hz: f64,
        sample_rate_hz: f64,
        record_len: usize,
        window_start: usize,
    ) -> Result<Self, SignalError> {
        for (name, value) in [
            ("frequency_hz", frequency_hz),
            ("sample_rate_hz", sample_rate_hz),
        ] {
            if !value.is_finite() || value <= 0.0 {
                return Err(SignalError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and positive",
                });
            }
        }
        if frequency_hz >= 0.5 * sample_rate_hz {
            return Err(SignalError::BandAboveNyquist {
                high_hz: frequency_hz,
                nyquist_hz: 0.5 * sample_rate_hz,
            });
        }
        if record_len < window_start.saturating_add(3) {
            return Err(SignalError::InvalidParameter {
                name: "window",
                value: record_len.saturating_sub(window_start) as f64,
                reason: "the detection window needs at least 3 samples",
            });
        }
        Ok(Self::new_valid(
            frequency_hz,
            sample_rate_hz,
            record_len,
            window_start,
        ))
    }

    /// [`LockIn::new`] for arguments the caller has validated (a finite
    /// tone strictly between 0 and Nyquist, a window of a few samples at
    /// least); other arguments give a meaningless detector, never a panic.
    pub fn new_valid(
        frequency_hz: f64,
        sample_rate_hz: f64,
        record_len: usize,
        window_start: usize,
    ) -> Self {
        let ratio = frequency_hz / sample_rate_hz;
        let (mut cos, mut sin) = (
            Vec::with_capacity(record_len),
            Vec::with_capacity(record_len),
        );
        for n in 0..record_len {
            // Reduce n·f/fs to [0, 1) before scaling: accurate for long records.
            let arg = TAU * (n as f64 * ratio).fract();
            cos.push(arg.cos());
            sin.push(arg.sin());
        }
        let (mut gcc, mut gcs, mut gss) = (0.0, 0.0, 0.0);
        for n in window_start.min(record_len)..record_len {
            gcc += cos[n] * cos[n];
            gcs += cos[n] * sin[n];
            gss += sin[n] * sin[n];
        }
        let det = gcc * gss - gcs * gcs;
        let gram_inv = [[gss / det, -gcs / det], [-gcs / det, gcc / det]];
        Self {
            cos,
            sin,
            window_start,
            gram_inv,
        }
    }

    /// `c_n`, `n = 0 … L−1`.
    pub fn cos(&self) -> &[f64] {
        &self.cos
    }

    /// `s_n`, `n = 0 … L−1`.
    pub fn sin(&self) -> &[f64] {
        &self.sin
    }

    /// `L`.
    pub fn record_len(&self) -> usize {
        self.cos.len()
    }

    /// The window `n_s .. L`.
    pub fn window(&self) -> std::ops::Range<usize> {
        self.window_start..self.cos.len()
    }

    /// `G⁻¹`, row-major.
    pub fn gram_inv(&self) -> &[[f64; 2]; 2] {
        &self.gram_inv
    }

    /// The window sums of a filtered record (its samples before `n_s` are
    /// skipped; a record longer than `L` is cut at `L`).
    pub fn sums(&self, filtered: &[f64]) -> IqSums {
        let mut acc = IqSums::default();
        let end = filtered.len().min(self.cos.len());
        let start = self.window_start.min(end);
        let window = filtered[start..end]
            .iter()
            .zip(&self.cos[start..end])
            .zip(&self.sin[start..end]);
        for ((&y, &c), &s) in window {
            acc.add(y, c, s);
        }
        acc
    }

    /// `(I, Q) = G⁻¹ (Σ y c, Σ y s)`.
    #[inline]
    pub fn iq(&self, acc: &IqSums) -> (f64, f64) {
        let g = &self.gram_inv;
        (
            g[0][0] * acc.yc + g[0][1] * acc.ys,
            g[1][0] * acc.yc + g[1][1] * acc.ys,
        )
    }
}

/// The sums `Σ y c`, `Σ y s`, `Σ y²` over the common length of the three
/// slices (the reference already aligned with `y`), accumulated in four
/// interleaved partial sums (independent additions the processor
/// overlaps; the order of the additions differs from a plain loop by
/// rounding only).
pub fn window_sums(y: &[f64], cos: &[f64], sin: &[f64]) -> IqSums {
    let len = y.len().min(cos.len()).min(sin.len());
    let (y, cos, sin) = (&y[..len], &cos[..len], &sin[..len]);
    let mut acc = [IqSums::default(); 4];
    let body = len - len % 4;
    for ((y4, c4), s4) in y[..body]
        .chunks_exact(4)
        .zip(cos[..body].chunks_exact(4))
        .zip(sin[..body].chunks_exact(4))
    {
        for lane in 0..4 {
            acc[lane].add(y4[lane], c4[lane], s4[lane]);
        }
    }
    for n in body..len {
        acc[n - body].add(y[n], cos[n], sin[n]);
    }
    IqSums {
        yc: (acc[0].yc + acc[1].yc) + (acc[2].yc + acc[3].yc),
        ys: (acc[0].ys + acc[1].ys) + (acc[2].ys + acc[3].ys),
        yy: (acc[0].yy + acc[1].yy) + (acc[2].yy + acc[3].yy),
    }
}
