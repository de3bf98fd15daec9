//! `psdcal calibrate`: read and validate a data set, calibrate, write
//! calibration.json (and the residuals), and summarise.

use psdcal::{calibrate, DataSet, DataSetFiles, FitReport, LoadOptions};

use crate::cli::{CalibrateConfig, Output};
use crate::report::print_warnings;

/// Runs `calibrate`.
pub fn run(config: &CalibrateConfig, output: Output) -> anyhow::Result<()> {
    let files = DataSetFiles {
        template: config.template.clone(),
        points: config.points.clone(),
        gains: config.gains_file.clone(),
    };
    let load = LoadOptions {
        geometry: config.geometry,
        strict: config.strict,
    };
    let set = DataSet::from_files(&files, &load)?;
    print_warnings(set.warnings());
    let mut calibrated = calibrate(&set, &config.options)?;
    let argv: Vec<String> = std::env::args().collect();
    calibrated.set_command(&argv.join(" "));
    calibrated.write(&set, &config.out, config.residuals.as_deref())?;
    for warning in &calibrated.report.warnings {
        eprintln!("warning: {warning}");
    }
    for diagnostic in &calibrated.report.diagnostics {
        eprintln!("warning: {}", diagnostic.message);
    }
    match output {
        Output::Quiet => {}
        Output::Json => println!("{}", calibrated.summary_json()?),
        Output::Text => print!("{}", render(&calibrated.report, config)),
    }
    Ok(())
}

/// The human-readable summary.
fn render(report: &FitReport, config: &CalibrateConfig) -> String {
    let mut out = report.to_string();
    out.push_str(&format!("wrote {}\n", config.out.display()));
    if let Some(path) = &config.residuals {
        out.push_str(&format!("wrote {}\n", path.display()));
    }
    out
}
