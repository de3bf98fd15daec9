//! What every fit of the model to a calibration data set shares, defined
//! once for the calibration, the file formats and the facade
//! (docs/model.md §4): which error a fit minimises ([`CostKind`]) and the
//! fewest data it needs ([`MIN_IMAGES`], [`MIN_POINTS_PER_IMAGE`]).

use serde::{Deserialize, Serialize};

/// Fewest points an image needs (a homography has 8 degrees of freedom).
pub const MIN_POINTS_PER_IMAGE: usize = 4;
/// Mean squared residual per point (mm², both coordinates) at or below
/// which a fit is exact, rounding only (RMS 1e-10 mm): the solver stops
/// there and no uncertainty is checked. One definition for every fit.
pub const EXACT_FIT_MEAN_SQUARE_MM2: f64 = 1e-20;
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

impl CostKind {
    /// Every cost, in the order the command line lists them.
    pub const ALL: [CostKind; 2] = [CostKind::Template, CostKind::Image];

    /// The name on the command line and in calibration.json.
    pub fn name(self) -> &'static str {
        match self {
            CostKind::Template => "template",
            CostKind::Image => "image",
        }
    }
}

impl std::str::FromStr for CostKind {
    type Err = String;

    /// `template` or `image` (any case).
    fn from_str(text: &str) -> Result<Self, String> {
        let wanted = text.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|c| c.name() == wanted)
            .ok_or_else(|| format!("expected template or image, found '{text}'"))
    }
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for CostKind {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}
