//! Arguments of `psdcal gains` (the electrical calibration of the channel
//! gains).

use std::path::PathBuf;

use clap::Args;

use crate::choice::GainsMethodArg;

pub const GAINS_EXAMPLES: &str = "\
Example:
  psdcal gains --signals equal.csv --method equal-current --out gains.json
  psdcal calibrate -t template.csv -s signals.csv --gains gains.json --out cal.json

  equal.csv holds records (columns vx1, vx2, vy1, vy2; image and led optional) in which
  all four channels carry the same current: a test current injected into every
  channel, or a light spot centred on the PSD. Each gain relative to x1 is the mean
  of its amplitude ratio, with its standard deviation. calibrate --gains divides them
  out of the amplitudes and keeps them fixed (--fit ...,gains estimates them instead).";

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
