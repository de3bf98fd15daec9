//! `psdcal check`: validate a data set and summarise it.

use psdcal::{DataSet, DataSetFiles, LoadOptions};

use crate::cli::{CheckConfig, Output};
use crate::report::print_warnings;

/// Runs `check`.
pub fn run(config: &CheckConfig, output: Output) -> anyhow::Result<()> {
    let files = DataSetFiles {
        template: config.template.clone(),
        points: config.points.clone(),
        gains: None,
    };
    let options = LoadOptions {
        geometry: config.geometry,
        strict: config.strict,
    };
    let set = DataSet::from_files(&files, &options)?;
    print_warnings(set.warnings());
    let summary = set.summary();
    match output {
        Output::Quiet => {}
        Output::Json => println!("{}", serde_json::to_string_pretty(&summary)?),
        Output::Text => print!("{}", psdcal::summary_text(&summary)),
    }
    Ok(())
}
