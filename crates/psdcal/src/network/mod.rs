//! A room of sensors calibrated by waving a wand (docs/network.md): the
//! files in and out of `calibrate-network`, its report page, and
//! `simulate-network`.

pub(crate) mod calibrate_network;
pub(crate) mod network_input;
pub(crate) mod network_outputs;
pub(crate) mod network_page;
pub(crate) mod simulate_network;
