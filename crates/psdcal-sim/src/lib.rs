//! # psdcal-sim
//!
//! Simulation of a PSD sensor's whole signal chain (MODEL.md §6: modulated
//! LEDs, noise at a given SNR, Butterworth band-pass, demodulation, amplifier
//! gain imbalance (P43), PSD distortion) and the Monte Carlo studies that
//! reproduce and extend the paper's evaluation (its Section 4, Tables 1–10
//! and Figure 9).
#![warn(missing_docs)]

pub mod butterworth;
mod error;
pub mod fig9;
pub mod paper;
pub mod render;
pub mod scenario;
pub mod signal;
pub mod simulate;
pub mod study;

pub use error::SimError;
pub use scenario::{Lens, TemplateKind};
pub use signal::{ChainConfig, SignalChain};
pub use simulate::{simulate, Simulation, SimulationOptions};
pub use study::{
    run_tables, table_spec, Condition, Method, Quantity, StudyOptions, TableResult, TableSpec,
    TABLE_IDS,
};
