//! `psdcal gains`: relative channel gains from equal-current records.

use crate::messages::Output;
use clap::Args;
use std::path::PathBuf;

/// Estimate the amplifier gains from equal-current records (electrical calibration)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct GainsArgs {
    /// Equal-current records: vx1, vx2, vy1, vy2
    #[arg(long, short = 's', value_name = "FILE")]
    pub signals: PathBuf,
    /// Estimation method (equal-current: all four channels carry the same current)
    #[arg(long, value_name = "METHOD", value_enum, default_value_t = psdcal::GainsMethod::EqualCurrent)]
    pub method: psdcal::GainsMethod,
    /// Where to write gains.json (atomically); standard output when absent
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// Runs `gains` (without `--out`, gains.json goes to standard output).
pub fn run(args: &GainsArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let file = psdcal::estimate_gains(&args.signals, args.method, limits)?;
    match &args.out {
        Some(path) => psdcal_io::write_gains(path, &file)?,
        None if output != Output::Json => {
            psdcal::print_text(&(serde_json::to_string_pretty(&file)? + "\n"))?;
            return Ok(());
        }
        None => {}
    }
    let summary = psdcal::gains_summary(&file, &args.signals, args.out.as_deref())?;
    crate::messages::emit(output, &summary)
}
