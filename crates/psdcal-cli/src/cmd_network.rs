//! `psdcal calibrate-network` and `psdcal simulate-network` (the work is
//! the facade's `calibrate_network_files` and `simulate_network`).

use crate::messages::{emit, Output};
use anyhow::Result;
use psdcal::{NetworkRequest, NetworkSimRequest, ReadLimits};

/// Runs `calibrate-network`.
pub fn run(
    request: &NetworkRequest,
    output: Output,
    limits: ReadLimits,
    force: bool,
) -> Result<()> {
    let request = NetworkRequest {
        force,
        ..request.clone()
    };
    let calibrated = psdcal::calibrate_network_files(&request, limits)?;
    calibrated.write(&std::env::args().collect::<Vec<_>>().join(" "))?;
    if let Some(dir) = &request.report {
        psdcal::network_page(&calibrated, dir)?;
    }
    emit(output, &calibrated.summary())
}

/// Runs `simulate-network`.
pub fn simulate(request: &NetworkSimRequest, output: Output, force: bool) -> Result<()> {
    let request = NetworkSimRequest {
        force,
        ..request.clone()
    };
    emit(output, &psdcal::simulate_network(&request)?)
}
