//! The parts calibration.json version 2 adds beside the model: where a
//! calibration came from (`provenance`) and what the fit noticed
//! (`diagnostics`).

use serde::{Deserialize, Serialize};

/// Where a calibration came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Version of the psdcal that wrote the file.
    pub psdcal_version: String,
    /// The command line that produced it (arguments joined by spaces).
    pub command: String,
    /// The calibration options, by name.
    pub options: serde_json::Value,
    /// The input files with their SHA-256.
    pub inputs: Vec<InputFile>,
    /// When it was written, UTC, ISO 8601 (`2024-05-01T12:34:56Z`).
    pub created_utc: String,
}

/// An input file of a calibration.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFile {
    /// The path as given.
    pub path: String,
    /// SHA-256 of its bytes, lower-case hexadecimal.
    pub sha256: String,
}

/// Something the fit noticed (docs/formats.md lists the stable codes): the
/// one definition, psdcal-model's.
pub use psdcal_model::diagnostic::Diagnostic;
