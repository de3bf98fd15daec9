//! `psdcal calibrate-in-situ`: the sensor mounted in the room, emitters at
//! surveyed positions (template.csv with `Z_mm`), one or several
//! orientations; writes calibration.json and the sensor's poses (the work
//! is `psdcal::calibrate_in_situ`).

use std::path::PathBuf;

use clap::Args;
use psdcal::option_text::non_negative_mm;
use psdcal::DataSet;

use crate::messages::Output;

/// Calibrate a mounted sensor in situ from emitters at surveyed 3-D positions (its pose in the room too)
#[derive(Debug, Clone, PartialEq, Args)]
pub struct InSituArgs {
    /// The surveyed emitters (template.csv with Z_mm, room frame) and the
    /// measured points, one image per sensor orientation
    #[command(flatten)]
    pub data: crate::args::DataSetArgs,
    /// The survey's standard deviation per coordinate, mm
    #[arg(long, value_name = "MM", default_value_t = 0.0, value_parser = non_negative_mm, allow_negative_numbers = true)]
    pub survey_sigma: f64,
    /// Channel gains from `psdcal gains` (gains.json), divided out of the amplitudes (needs --signals)
    #[arg(long, value_name = "FILE")]
    pub gains: Option<PathBuf>,
    /// Output calibration.json (written atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write the sensor's poses in the room as rig.json sensor entries
    #[arg(long, value_name = "FILE")]
    pub poses_out: Option<PathBuf>,
}

/// Runs `calibrate-in-situ`.
pub fn run(config: &InSituArgs, output: Output, limits: psdcal::ReadLimits) -> anyhow::Result<()> {
    let gains = config.gains.clone();
    let (files, load) = config.data.clone().into_files(gains, limits)?;
    let set = DataSet::from_files(&files, &load)?;
    crate::messages::print_warnings(set.warnings());
    let mut result = psdcal::calibrate_in_situ(&set, config.survey_sigma)?;
    let argv: Vec<String> = std::env::args().collect();
    result.set_command(&argv.join(" "));
    result.write(&config.out, config.poses_out.as_deref())?;
    let summary = result.summary(&config.out, config.poses_out.as_deref());
    crate::messages::emit(output, &summary)
}
