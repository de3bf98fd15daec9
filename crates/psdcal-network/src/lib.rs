//! # psdcal-network
//!
//! A room of PSD sensors calibrated by waving a wand (docs/network.md):
//! every sensor's pose in the world and its refined lens, from what each
//! sensor measured of a rigid wand's LEDs at each instant, each sensor's lab
//! calibration as a Gaussian prior, and optionally a static frame of LEDs at
//! known world positions.
//!
//! - [`data`]: the input (sensors with priors, wand, static frame,
//!   observations);
//! - [`view_graph`], [`essential`], [`geometry`], [`start`]: the start
//!   without a guess (essential matrices over the view graph's maximum
//!   spanning tree, scaled by the wand);
//! - [`problem`], [`adjust`]: the bundle adjustment on the one solver, wand
//!   poses eliminated (Schur), robust passes, dropped frames, covariance;
//! - [`diagnose`]: wand-length residuals, coverage, weak links, advice;
//! - [`calibrate`]: the whole run.
#![warn(missing_docs)]

pub mod adjust;
pub mod calibrate;
pub mod data;
pub mod diagnose;
mod error;
pub mod essential;
pub mod estimate;
pub mod geometry;
pub mod problem;
pub mod start;
pub mod view_graph;

pub use adjust::{AdjustOptions, DropReason};
pub use calibrate::{
    calibrate_network, Gauge, MinFrames, NetworkOptions, NetworkResult, SensorEstimate,
};
pub use data::{Led, NetworkData, NetworkObservation, NetworkSensor};
pub use diagnose::{Coverage, NetworkDiagnostic, NetworkDiagnostics};
pub use error::NetworkError;
pub use start::StartOptions;
