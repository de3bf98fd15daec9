//! The stages of the standard model (docs/model.md §2–3, §8), one file each:
//! [`PsdRadial`] (P14)–(P16), [`Lens`] (P7)–(P13), [`Pinhole`] (P4), and the
//! channel gains on the amplitudes (P1)–(P2), (P43) in [`gains`]; and the
//! PSD's own non-linearity map (docs/model.md §8.3) in [`psd_map`]; the y axis's
//! own scale (docs/model.md §3.3) in [`aspect`].

pub mod aspect;
pub mod gains;
pub mod lens;
pub mod pinhole;
pub mod psd_map;
pub mod psd_radial;

pub use aspect::{with_aspect, Aspect};
pub use gains::Gains;
pub use lens::Lens;
pub use pinhole::Pinhole;
pub use psd_map::{MapBasis, MapFrame, PsdMap};
pub use psd_radial::PsdRadial;

use crate::stage::Stage;

/// A stage of a standard kind by its identifier (`psd_radial`, `lens`,
/// `pinhole`, `aspect`); `None` for any other kind.
pub fn standard_stage(kind: &str) -> Option<Box<dyn Stage>> {
    match kind {
        "psd_radial" => Some(Box::new(PsdRadial::new())),
        "lens" => Some(Box::new(Lens::new())),
        "pinhole" => Some(Box::new(Pinhole::new())),
        "aspect" => Some(Box::new(Aspect::new())),
        _ => None,
    }
}
