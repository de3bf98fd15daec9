//! The facade's error: every failure of the lower crates, and the few of
//! its own, each with a message that says what happened.

use std::path::PathBuf;

use psdcal_calib::CalibError;
use psdcal_io::IoError;
use psdcal_locate::LocateError;
use psdcal_model::ModelError;
use psdcal_report::ReportError;
use psdcal_sim::SimError;
use thiserror::Error;

/// Everything that can stop a psdcal job.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read, parsed, validated or written (the message
    /// names file, line and column).
    #[error(transparent)]
    Io(#[from] IoError),
    /// The calibration itself failed (no convergence, degenerate data).
    #[error("calibration failed")]
    Calibrate(#[source] CalibError),
    /// Another estimation failed (e.g. the electrical gains).
    #[error(transparent)]
    Estimate(#[from] CalibError),
    /// Angles of arrival, positions or maps could not be computed.
    #[error(transparent)]
    Locate(#[from] LocateError),
    /// The sensor model could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A simulation could not run.
    #[error(transparent)]
    Simulation(#[from] SimError),
    /// A plot or page could not be drawn.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// Options that cannot work together or values out of range.
    #[error("{0}")]
    Options(String),
    /// The input has nothing this job can use (the text says what).
    #[error("{0}")]
    Input(String),
    /// An output folder cannot be created or written.
    #[error("{message}")]
    OutputFolder {
        /// The folder.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A long job was interrupted before it wrote anything.
    #[error("the study was interrupted; nothing was written")]
    Interrupted,
}

/// The facade's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;
