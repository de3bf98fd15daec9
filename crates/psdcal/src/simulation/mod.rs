//! Simulated data sets, raw recordings, scans and rigs, the demo, and pose planning.

pub(crate) mod demo;
pub(crate) mod plan;
pub(crate) mod simulate;
pub(crate) mod simulate_moving;
pub(crate) mod simulate_positioning;
pub(crate) mod simulate_raw;
pub(crate) mod simulate_scan;
