//! calibration.json's `valid_region` (version 2; docs/formats.md, docs/model.md
//! §8.2): where the measured → ideal map is one-to-one.
//!
//! ```text
//! "valid_region": {"centre_mm": [0.5, -0.7], "rays": 90,
//!                  "radius_mm": [6.25, 6.2509, ...], "whole_active_area": true}
//! ```
//!
//! Ray `i` leaves `centre_mm` (the optical centre) in the direction
//! `θ_i = 2π i / rays` (from +x towards +y); `radius_mm[i]` is how far along
//! it the correction stays one-to-one: the first fold, or the edge of the
//! checked zone (the active area scaled by 1.5 about the electrical centre)
//! when there is none. `whole_active_area` is true when every point of the
//! active area is inside; it is derived from the radii, and a file whose
//! flag disagrees with them is refused.

use nalgebra::Vector2;
use psdcal_model::{ModelError, PsdGeometry, ValidRegion};
use serde::{Deserialize, Serialize};

/// The `valid_region` field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidRegionRecord {
    /// The centre the rays start from (the optical centre), mm.
    pub centre_mm: [f64; 2],
    /// Number of rays.
    pub rays: usize,
    /// Radius of each ray, mm.
    pub radius_mm: Vec<f64>,
    /// Whether the whole active area is inside.
    pub whole_active_area: bool,
}

impl ValidRegionRecord {
    /// The record of a region.
    pub fn from_region(region: &ValidRegion) -> Self {
        let c = region.centre();
        Self {
            centre_mm: [c.x, c.y],
            rays: region.rays(),
            radius_mm: region.radii().to_vec(),
            whole_active_area: region.whole_active_area(),
        }
    }

    /// The region over `geometry`'s active area; the message names the
    /// field that is wrong.
    pub fn to_region(&self, geometry: &PsdGeometry) -> Result<ValidRegion, String> {
        if self.rays != self.radius_mm.len() {
            return Err(format!(
                "valid_region.rays is {} but valid_region.radius_mm has {} values; expected one \
                 radius per ray",
                self.rays,
                self.radius_mm.len()
            ));
        }
        let centre = Vector2::new(self.centre_mm[0], self.centre_mm[1]);
        let region = ValidRegion::from_radii(centre, self.radius_mm.clone(), geometry).map_err(
            |e| match e {
                ModelError::InvalidModel { reason } => format!("valid_region: {reason}"),
                other => format!("valid_region: {other}"),
            },
        )?;
        if region.whole_active_area() != self.whole_active_area {
            return Err(format!(
                "valid_region.whole_active_area is {} but its radii say {}; expected the flag \
                 its radii give",
                self.whole_active_area,
                region.whole_active_area()
            ));
        }
        Ok(region)
    }
}
