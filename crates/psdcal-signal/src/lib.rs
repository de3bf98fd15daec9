//! # psdcal-signal
//!
//! Signal processing for the four electrode channels of a PSD (docs/model.md
//! §6 and §8 "Demodulation"): the Butterworth band-pass ([`butterworth`]),
//! filters that stream over chunks ([`stream`]), lock-in I/Q detection
//! ([`lockin`]), and the demodulation of one record — amplitudes, their noise
//! and SNR, the modulation frequency when the clocks differ, one LED at a
//! time or several tones at once ([`record`], [`tones`]). No CLI, file or
//! plotting dependency: the simulator (psdcal-sim) and the `demodulate`
//! facade both sit on it.
#![warn(missing_docs)]

pub mod butterworth;
mod error;
pub mod lockin;
pub mod record;
mod record_buffer;
pub mod stream;
pub mod tones;
mod windows;

pub use error::SignalError;
pub use record::{demodulate_record, DemodConfig, RecordEstimate, ToneEstimate};
pub use record_buffer::RecordBuffer;
pub use stream::StreamFilter;
pub use windows::{Window, Windows};
