//! `psdcal calibrate-network` and `psdcal simulate-network` (the work is
//! the facade's `calibrate_network_files` and `simulate_network`).

use crate::messages::Output;

/// Runs `calibrate-network`.
pub fn run(
    request: &psdcal::NetworkRequest,
    output: Output,
    limits: psdcal::ReadLimits,
    force: bool,
) -> anyhow::Result<()> {
    let request = psdcal::NetworkRequest {
        force,
        ..request.clone()
    };
    let calibrated = psdcal::calibrate_network_files(&request, limits)?;
    let argv: Vec<String> = std::env::args().collect();
    calibrated.write(&argv.join(" "))?;
    if let Some(dir) = &request.report {
        psdcal::network_page(&calibrated, dir)?;
    }
    crate::messages::emit(output, &calibrated.summary())
}

/// Runs `simulate-network`.
pub fn simulate(
    request: &psdcal::NetworkSimRequest,
    output: Output,
    force: bool,
) -> anyhow::Result<()> {
    let request = psdcal::NetworkSimRequest {
        force,
        ..request.clone()
    };
    crate::messages::emit(output, &psdcal::simulate_network(&request)?)
}
