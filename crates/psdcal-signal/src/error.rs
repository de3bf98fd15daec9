//! The error type of the signal-processing crate: every parameter, record
//! and recording the filters and detectors refuse, with the offending
//! numbers. Nothing here returns a NaN or a silently wrong amplitude.

use psdcal_model::ModelError;
use thiserror::Error;

/// Everything the signal chain refuses. Every variant carries the offending
/// numbers; the chain never returns a NaN or a silently wrong amplitude.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SignalError {
    /// The record is too short to skip the filter's transient and keep a
    /// detection window of a few cycles.
    #[error(
        "the record has {samples} samples; demodulating it needs at least {minimum} \
         (the filter's transient plus {cycles} cycles of the lowest tone)"
    )]
    RecordTooShortToDemodulate {
        /// Samples in the record.
        samples: usize,
        /// Fewest samples that can be demodulated.
        minimum: usize,
        /// Cycles the detection window must hold at least.
        cycles: f64,
    },
    /// A sample sits at the ADC's range (clipped): the amplitude would be
    /// wrong.
    #[error(
        "channel {channel} is saturated at sample {sample} of the record ({value} V, full scale ±{full_scale_v} V)"
    )]
    Saturated {
        /// Channel index (0 = vx1, 1 = vx2, 2 = vy1, 3 = vy2).
        channel: usize,
        /// Sample index in the record, 0-based.
        sample: usize,
        /// The sample, V.
        value: f64,
        /// The ADC's full scale, V.
        full_scale_v: f64,
    },
    /// A sample is NaN or infinite.
    #[error("channel {channel} has a non-finite sample at {sample} of the record")]
    NonFiniteSample {
        /// Channel index.
        channel: usize,
        /// Sample index in the record, 0-based.
        sample: usize,
    },
    /// No tone was given.
    #[error("no tone to detect")]
    NoTones,
    /// Tones closer than the detection window can separate
    /// (spacing below `2 / window`, docs/model.md §8).
    #[error(
        "tones {first_hz} Hz and {second_hz} Hz are {spacing_hz} Hz apart: a window of {window_s} s \
         separates tones at least {minimum_hz} Hz apart (2 / window); lengthen the records or space the tones"
    )]
    TonesNotSeparable {
        /// Lower tone, Hz.
        first_hz: f64,
        /// Upper tone, Hz.
        second_hz: f64,
        /// Their spacing, Hz.
        spacing_hz: f64,
        /// The detection window, s.
        window_s: f64,
        /// `2 / window_s`, Hz.
        minimum_hz: f64,
    },

    /// A parameter is non-finite or outside its domain (e.g. `f0 ≤ 0`).
    #[error("invalid signal-chain parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// The filter order is 0 or above the supported maximum.
    #[error("filter order {order} is not supported (1 to {max})")]
    InvalidOrder {
        /// The order asked for.
        order: usize,
        /// The largest supported order.
        max: usize,
    },
    /// The bandwidth reaches down to 0 Hz (`B ≥ 2 f0`).
    #[error("bandwidth {bandwidth_hz} Hz must be below twice the centre frequency {f0_hz} Hz")]
    BandwidthTooWide {
        /// Bandwidth, Hz.
        bandwidth_hz: f64,
        /// Centre frequency, Hz.
        f0_hz: f64,
    },
    /// The pass band reaches the Nyquist frequency.
    #[error(
        "the pass band reaches {high_hz} Hz, at or above the Nyquist frequency {nyquist_hz} Hz"
    )]
    BandAboveNyquist {
        /// Upper band edge, Hz.
        high_hz: f64,
        /// Half the sample rate, Hz.
        nyquist_hz: f64,
    },
    /// The sample rate is below `4 · (f0 + B/2)`.
    #[error("sample rate {sample_rate_hz} Hz is below the minimum {minimum_hz} Hz = 4·(f0 + B/2)")]
    SampleRateTooLow {
        /// Sample rate, Hz.
        sample_rate_hz: f64,
        /// `4 · (f0 + B/2)`, Hz.
        minimum_hz: f64,
    },
    /// No whole cycle is left after the transient.
    #[error(
        "a record of {record_cycles} cycles leaves no whole cycle after a transient of \
         {transient_cycles} cycles"
    )]
    RecordTooShort {
        /// Record length, cycles of f0.
        record_cycles: usize,
        /// Transient skipped, cycles of f0.
        transient_cycles: usize,
    },
    /// The record would exceed the chain's maximum record length.
    #[error("a record of {samples} samples exceeds the maximum of {max}")]
    RecordTooLong {
        /// Samples asked for.
        samples: f64,
        /// the chain's maximum record length.
        max: usize,
    },
    /// The SNR is NaN or infinite.
    #[error("SNR must be finite, got {snr_db} dB (use no noise for an infinite SNR)")]
    NonFiniteSnr {
        /// The SNR asked for, dB.
        snr_db: f64,
    },
    /// A channel amplitude is negative, non-finite or above 1e100.
    #[error(
        "amplitude of channel {channel} is {value}: must be finite, non-negative and at most 1e100"
    )]
    InvalidAmplitude {
        /// Channel name (`x1`, `x2`, `y1`, `y2`, or `channel` for a single record).
        channel: &'static str,
        /// The amplitude.
        value: f64,
    },
    /// The noise standard deviation implied by the SNR exceeds 1e100.
    #[error("noise standard deviation {sigma} exceeds the maximum 1e100 (SNR too low for this amplitude)")]
    NoiseTooLarge {
        /// `σ` implied by the amplitude and SNR.
        sigma: f64,
    },
    /// A record handed to a demodulator has the wrong length.
    #[error("record has {found} samples, the chain expects {expected}")]
    RecordLength {
        /// The expected length.
        expected: usize,
        /// Length handed in.
        found: usize,
    },
    /// The impact point lies off the PSD's active area (negative electrode
    /// currents in the forward model).
    #[error("impact point ({x_mm}, {y_mm}) mm is off the active area")]
    OffActiveArea {
        /// x, mm.
        x_mm: f64,
        /// y, mm.
        y_mm: f64,
    },
    /// The measured amplitudes sum to zero or less: no light (docs/model.md §1).
    #[error("measured amplitudes sum to {total}: no usable light spot")]
    NonPositiveTotal {
        /// `Vx1 + Vx2 + Vy1 + Vy2` as measured.
        total: f64,
    },
    /// The sensor model refused an input (e.g. a non-positive channel gain).
    #[error(transparent)]
    Model(ModelError),
}

impl From<ModelError> for SignalError {
    fn from(e: ModelError) -> Self {
        match e {
            ModelError::NonPositiveTotal { total } => SignalError::NonPositiveTotal { total },
            other => SignalError::Model(other),
        }
    }
}

impl SignalError {
    /// The status code of a record or window this error stops: `saturated`,
    /// `too_short`, `tone_collision`, or `invalid_input` for the rest.
    pub fn status(&self) -> &'static str {
        match self {
            SignalError::Saturated { .. } => "saturated",
            SignalError::RecordTooShortToDemodulate { .. } => "too_short",
            SignalError::TonesNotSeparable { .. } => "tone_collision",
            _ => "invalid_input",
        }
    }
}
