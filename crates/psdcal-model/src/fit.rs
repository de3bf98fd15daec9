//! What every fit of the model to a calibration data set shares, defined
//! once for the calibration, the file formats and the facade
//! (docs/model.md §4): which error a fit minimises ([`CostKind`]) and the
//! fewest data it needs ([`MIN_IMAGES`], [`MIN_POINTS_PER_IMAGE`]).

use serde::{Deserialize, Serialize};

/// Fewest points an image needs (a homography has 8 degrees of freedom).
pub const MIN_POINTS_PER_IMAGE: usize = 4;
/// Fewest images a calibration needs (docs/model.md §4).
pub const MIN_IMAGES: usize = 3;

/// Which error a fit minimises (docs/model.md §4.6); calibration.json's
/// `fit.cost` (`"template"` or `"image"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CostKind {
    /// Template-plane error (P29), mm on the template: the paper's choice
    /// and its residual.
    Template,
    /// Image-plane reprojection error, mm on the sensor.
    Image,
}
