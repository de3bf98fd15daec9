//! `psdcal report`: a self-contained HTML page of a calibration with its
//! plots (the library's `write_report`, drawn by psdcal-report).

use anyhow::Result;
use clap::Args;
use psdcal::{ReadLimits, ReportRequest};
use std::path::PathBuf;

use crate::messages::Output;

/// A self-contained HTML report of a calibration with its plots (SVG and PNG)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct ReportArgs {
    /// Calibration written by psdcal (calibration.json)
    #[arg(long, short = 'c', value_name = "FILE")]
    pub calibration: PathBuf,
    /// Template of the calibration data (with --observations: coverage and residual plots)
    #[arg(long, short = 't', value_name = "FILE", requires = "observations")]
    pub template: Option<PathBuf>,
    /// Measured impact points of the calibration data: image, led, x_mm, y_mm
    #[arg(long, short = 'o', value_name = "FILE", requires = "template")]
    pub observations: Option<PathBuf>,
    /// Output folder (created if missing) for report.html and the plots
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs `report`.
pub fn run(args: &ReportArgs, output: Output, limits: ReadLimits, force: bool) -> Result<()> {
    let written = psdcal::write_report(&ReportRequest {
        calibration: args.calibration.clone(),
        data: args.template.clone().zip(args.observations.clone()),
        out: args.out.clone(),
        limits,
        force,
    })?;
    crate::messages::emit(output, &written.summary(&args.out))
}
