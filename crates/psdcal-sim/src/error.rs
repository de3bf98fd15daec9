//! The error type of the simulation crate.

use psdcal_model::ModelError;
use thiserror::Error;

use crate::signal::SignalError;

/// Everything that can stop a simulation or a study.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SimError {
    /// The options cannot be simulated (the text says which and why).
    #[error("invalid simulation options: {0}")]
    Options(String),
    /// The signal chain refused its parameters or input.
    #[error(transparent)]
    Signal(#[from] SignalError),
    /// The sensor model could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The study was interrupted.
    #[error("the study was interrupted")]
    Cancelled,
}
