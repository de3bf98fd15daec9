//! `psdcal calibrate-in-situ`: the sensor mounted in the room, emitters at
//! surveyed positions (template.csv with `Z_mm`), one or several
//! orientations; writes calibration.json and the sensor's poses (the work
//! is `psdcal::calibrate_in_situ`).

use std::path::PathBuf;

use clap::Args;
use psdcal::option_text::non_negative_mm;
use psdcal::{DataSet, DataSetFiles, LoadOptions, PointSource};
use psdcal_model::PsdGeometry;

use crate::cli::Output;

/// Arguments of `psdcal calibrate-in-situ`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct InSituArgs {
    /// Surveyed emitters: led, X_mm, Y_mm, Z_mm (room frame, mm)
    #[arg(long, short = 't', value_name = "FILE")]
    pub template: PathBuf,
    /// Measured points: image (one per sensor orientation), led, x_mm, y_mm
    #[arg(long, short = 'o', value_name = "FILE")]
    pub observations: PathBuf,
    /// The survey's standard deviation per coordinate, mm
    #[arg(long, value_name = "MM", default_value_t = 0.0, value_parser = non_negative_mm, allow_negative_numbers = true)]
    pub survey_sigma: f64,
    /// Output calibration.json (written atomically)
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write the sensor's poses in the room as rig.json sensor entries
    #[arg(long, value_name = "FILE")]
    pub poses_out: Option<PathBuf>,
    /// Active-area side along x, mm
    #[arg(long, default_value_t = 9.0)]
    pub lx: f64,
    /// Active-area side along y, mm
    #[arg(long, default_value_t = 9.0)]
    pub ly: f64,
}

/// Runs `calibrate-in-situ`.
pub fn run(args: &InSituArgs, output: Output) -> anyhow::Result<()> {
    let files = DataSetFiles {
        template: args.template.clone(),
        points: PointSource::Observations(args.observations.clone()),
        gains: None,
    };
    let load = LoadOptions {
        geometry: PsdGeometry {
            lx: args.lx,
            ly: args.ly,
        },
        strict: false,
    };
    let set = DataSet::from_files(&files, &load)?;
    let mut result = psdcal::calibrate_in_situ(&set, args.survey_sigma)?;
    let argv: Vec<String> = std::env::args().collect();
    result.set_command(&argv.join(" "));
    result.write(&args.out, args.poses_out.as_deref())?;
    let summary = psdcal::Summary::new(result.text(), result.json());
    crate::report::emit(output, &summary.wrote([args.out.as_path()]))
}
