//! The error type of the map fit.

use thiserror::Error;

/// Why a scan cannot give a map.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum PsdMapError {
    /// Too few scan points for the requested model.
    #[error(
        "{points} scan points are too few for {model} ({coefficients} coefficients per axis); \
         expected at least {needed} points (scan more positions or choose a smaller model)"
    )]
    TooFewPoints {
        /// Points in the scan (after rejecting outliers).
        points: usize,
        /// The model, e.g. `poly:5`.
        model: String,
        /// Coefficients per axis.
        coefficients: usize,
        /// The fewest points the model needs.
        needed: usize,
    },
    /// The normal equations are singular: the scan does not determine the model.
    #[error(
        "the scan does not determine {model} (its normal equations are singular); expected \
         positions spread over the sensor, or a smaller model"
    )]
    Singular {
        /// The model.
        model: String,
    },
    /// A point or position is not finite, or the points span no area.
    #[error("the scan is unusable: {reason}")]
    Unusable {
        /// What is wrong.
        reason: String,
    },
    /// No candidate of `auto` can be fitted.
    #[error("no model can be fitted to {points} scan points; expected at least {needed}")]
    NoCandidate {
        /// Points in the scan.
        points: usize,
        /// The fewest points the smallest candidate needs.
        needed: usize,
    },
}
