//! Cautions: results that are given, but with a reason to doubt them (a
//! point off the active area, a plane met at a grazing angle, nearly
//! parallel rays). Batch commands write their [`Caution::status`] code in
//! the `status` column instead of `ok`.

use std::fmt;

/// Why an answered result deserves care.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Caution {
    /// The measured point is off the PSD's active area, where the model was
    /// not fitted.
    OffActiveArea {
        /// Measured x, mm.
        x_mm: f64,
        /// Measured y, mm.
        y_mm: f64,
    },
    /// The ray meets the plane at a grazing angle: a small angular error
    /// moves the position a lot.
    GrazingPlane {
        /// Angle between the ray and the plane, degrees.
        angle_deg: f64,
    },
    /// The rays of a triangulation are nearly parallel: the position along
    /// them is poorly determined.
    NearlyParallelRays {
        /// Largest angle between two rays, degrees.
        angle_deg: f64,
    },
}

impl Caution {
    /// Short code for a `status` column.
    pub fn status(&self) -> &'static str {
        match self {
            Caution::OffActiveArea { .. } => "off_active_area",
            Caution::GrazingPlane { .. } => "grazing_plane",
            Caution::NearlyParallelRays { .. } => "nearly_parallel_rays",
        }
    }
}

impl fmt::Display for Caution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Caution::OffActiveArea { x_mm, y_mm } => write!(
                f,
                "point ({x_mm:?}, {y_mm:?}) mm is off the active area, where the model was not fitted"
            ),
            Caution::GrazingPlane { angle_deg } => write!(
                f,
                "the ray meets the plane at a grazing {angle_deg:.2}°: the position is sensitive \
                 to angular errors"
            ),
            Caution::NearlyParallelRays { angle_deg } => write!(
                f,
                "the rays are nearly parallel (largest angle {angle_deg:.3}°): the position along \
                 them is poorly determined"
            ),
        }
    }
}

/// The `status` text of a result: `ok`, or its cautions' codes joined by
/// `;`.
pub fn status_of(cautions: &[Caution]) -> String {
    if cautions.is_empty() {
        "ok".to_string()
    } else {
        cautions
            .iter()
            .map(Caution::status)
            .collect::<Vec<_>>()
            .join(";")
    }
}
