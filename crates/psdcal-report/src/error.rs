//! The error of every plot and page function.

use std::path::PathBuf;

/// Why a plot or a page could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// The data cannot be plotted (empty, not finite, inconsistent sizes).
    #[error("cannot plot {what}: {reason}")]
    InvalidData {
        /// Which plot.
        what: &'static str,
        /// What is wrong with its data.
        reason: String,
    },
    /// The drawing backend failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// The bundled font could not be loaded.
    #[error("the bundled font could not be loaded")]
    Font,
    /// A PNG file could not be written.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// A drawing error of any backend.
pub(crate) fn draw_err<E: std::fmt::Display>(error: E) -> ReportError {
    ReportError::Draw(error.to_string())
}
