//! `psdcal report`: a self-contained HTML page of a calibration with its
//! plots (the library's `write_report`, drawn by psdcal-report).

use psdcal::ReportRequest;

use crate::cli::Output;
use crate::cli_report::ReportArgs;

/// Runs `report`.
pub fn run(args: &ReportArgs, output: Output) -> anyhow::Result<()> {
    let written = psdcal::write_report(&ReportRequest {
        calibration: args.calibration.clone(),
        data: args.template.clone().zip(args.observations.clone()),
        out: args.out.clone(),
    })?;
    crate::report::emit(output, &written.summary(&args.out))
}
