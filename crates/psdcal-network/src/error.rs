//! The errors of a network calibration.

/// Why a network calibration could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NetworkError {
    /// The input is inconsistent (sizes, indices, values).
    #[error("{0}")]
    Input(String),
    /// A sensor shares too few wand sightings with the others to be placed.
    #[error(
        "sensor '{sensor}' is not connected to the network: it shares {shared} wand \
         sightings with the others (at least {needed} needed); wave the wand where it and \
         another sensor both see it"
    )]
    Disconnected {
        /// The sensor's id.
        sensor: String,
        /// Its largest count of shared sightings with a placed sensor.
        shared: usize,
        /// The least count that places a sensor.
        needed: usize,
    },
    /// Too few frames to calibrate.
    #[error(
        "too few frames: {usable} frames are seen by at least two sensors (at least {needed} \
         needed); wave the wand longer through the sensors' shared views"
    )]
    TooFewFrames {
        /// Frames usable for the start.
        usable: usize,
        /// Frames needed.
        needed: usize,
    },
    /// Nothing fixes the scale.
    #[error("no scale: {0}")]
    NoScale(String),
    /// A numerical step failed.
    #[error("{stage}: {reason}")]
    Numerical {
        /// Which step.
        stage: &'static str,
        /// What happened.
        reason: String,
    },
}
