//! Arguments of `psdcal report`.

use std::path::PathBuf;

use clap::Args;

pub const REPORT_EXAMPLES: &str = include_str!("../help/report.txt");

/// Arguments of `psdcal report`.
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
