//! Arguments of `psdcal gains` (the electrical calibration of the channel
//! gains).

use std::path::PathBuf;

use clap::Args;

use crate::choice::GainsMethodArg;

pub const GAINS_EXAMPLES: &str = include_str!("../help/gains.txt");

/// Arguments of `psdcal gains`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct GainsArgs {
    /// Equal-current records: vx1, vx2, vy1, vy2
    #[arg(long, short = 's', value_name = "FILE")]
    pub signals: PathBuf,
    /// Estimation method (equal-current: all four channels carry the same current)
    #[arg(long, value_name = "METHOD", value_enum, default_value_t = GainsMethodArg::EqualCurrent)]
    pub method: GainsMethodArg,
    /// Where to write gains.json (atomically); standard output when absent
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}
