//! # psdcal-sim
//!
//! Simulation of a PSD sensor's whole signal chain (docs/model.md §6: modulated
//! LEDs, noise at a given SNR, Butterworth band-pass, demodulation, amplifier
//! gain imbalance (P43), PSD distortion), seeded scenarios, and whole
//! simulated data sets with their truth; a room of sensors and emitters
//! for positioning ([`room`]); in-situ calibration scenes ([`insitu`]); raw recordings as a card records them
//! (`raw`: sampled channels with a card's impairments). The Monte Carlo studies that
//! calibrate them live in psdcal-study.
#![warn(missing_docs)]

/// The Butterworth band-pass, now in psdcal-signal (re-exported so that
/// `psdcal_sim::butterworth` keeps its paths).
pub use psdcal_signal::butterworth;
pub mod chain_config;
mod error;
pub mod insitu;
pub mod moving;
pub mod network_room;
pub mod nonlinearity;
pub mod raw;
pub mod room;
pub mod scan;
pub mod scenario;
pub mod signal;
pub mod simulate;

pub use error::SimError;
pub use insitu::{InSituOptions, InSituScene};
pub use nonlinearity::PsdNonlinearity;
pub use raw::{Impairment, Impairments, RawPlan, RawRecord};
pub use scan::{simulate_scan, ScanOptions, ScanSample};
pub use scenario::{Lens, TemplateKind};
pub use signal::{ChainConfig, SignalChain};
pub use simulate::{simulate, simulate_at, Simulation, SimulationOptions};
