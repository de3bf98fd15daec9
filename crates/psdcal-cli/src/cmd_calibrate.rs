//! `psdcal calibrate`: read and validate a data set, calibrate, write
//! calibration.json (and the residuals), and summarise.

use psdcal::{calibrate, DataSet};

use crate::args::CalibrateConfig;
use crate::messages::Output;
use crate::messages::{emit, print_warnings};

/// Runs `calibrate`.
pub fn run(config: &CalibrateConfig, output: Output) -> anyhow::Result<()> {
    let set = DataSet::from_files(&config.files, &config.load)?;
    print_warnings(set.warnings());
    let mut calibrated = calibrate(&set, &config.options)?;
    let argv: Vec<String> = std::env::args().collect();
    calibrated.set_command(&argv.join(" "));
    let residuals = config.residuals.as_deref();
    calibrated.write(&set, &config.out, residuals)?;
    if matches!(output, Output::Quiet) {
        print_warnings(&calibrated.warnings());
        return Ok(());
    }
    emit(output, &calibrated.summary(&config.out, residuals)?)
}
