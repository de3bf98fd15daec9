//! The start of the refinement (docs/model.md §4.1–4.5): a rough preliminary
//! radial correction ([`preliminary`], with the line-straightness cost in
//! [`straightness`]), one homography per image by the normalised DLT
//! ([`homography`]), the adapted Zhang closed form and a pose per homography
//! ([`zhang`]), and the focal-length search that stands in when the closed
//! form gives no plausible start ([`initialize`]). [`misplaced`] reuses the
//! homographies to name an LED whose template coordinates are wrong.
//!
//! Everything here works on the measured points before any refinement; the
//! cost it compares starts with is the calibration problem's
//! ([`crate::problem`]).

pub(crate) mod correction_cost;
mod focal_profile;
pub mod homography;
pub mod initialize;
pub mod misplaced;
pub mod preliminary;
pub mod straightness;
pub mod zhang;
