//! The paper's Monte Carlo study and its page.

pub(crate) mod monte_carlo;
pub(crate) mod study_page;
pub(crate) mod study_psd_map;
#[cfg(feature = "testing")]
pub(crate) mod testing;
