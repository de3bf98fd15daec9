//! `psdcal diff`: two calibrations compared in angles of arrival over the
//! active area (the work is `psdcal::diff`).

use std::path::PathBuf;

use clap::Args;

use crate::messages::Output;
use anyhow::Result;
use psdcal::ReadLimits;

/// Two calibrations of one sensor compared in angles over the active area (did it drift?)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct DiffArgs {
    /// Calibration A, the reference (calibration.json)
    #[arg(value_name = "A.json")]
    pub a: PathBuf,
    /// Calibration B, compared with A
    #[arg(value_name = "B.json")]
    pub b: PathBuf,
    /// Grid points per side over the active area
    #[arg(long, value_name = "N", default_value_t = psdcal::DEFAULT_DIFF_GRID)]
    pub grid: usize,
    /// Write every grid point's difference to this CSV (atomically)
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Folder (created if missing) for diff.html and its heat maps (SVG)
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Runs `diff`.
pub fn run(args: &DiffArgs, output: Output, limits: ReadLimits, force: bool) -> Result<()> {
    let done = psdcal::diff(&psdcal::DiffRequest {
        a: args.a.clone(),
        b: args.b.clone(),
        grid: args.grid,
        out: args.out.clone(),
        report: args.report.clone(),
        limits,
        force,
    })?;
    let summary = psdcal::Summary::new(done.summary(), done.to_json());
    crate::messages::emit(output, &summary.warn(&done.warnings))
}
