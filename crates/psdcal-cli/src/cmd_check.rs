//! `psdcal check`: validate a data set and summarise it.

use psdcal::{DataSet, DataSetFiles, LoadOptions};

use crate::messages::print_warnings;
use crate::messages::Output;

/// Runs `check`: observations are checked as they are read, and the
/// summary written straight from its fields (no JSON tree of a data set
/// with hundreds of thousands of images).
pub fn run(files: &DataSetFiles, load: &LoadOptions, output: Output) -> anyhow::Result<()> {
    let summary = DataSet::from_files(files, load)?.summary();
    print_warnings(&summary.warnings);
    match output {
        Output::Quiet => {}
        Output::Json => psdcal::print_text(&(serde_json::to_string_pretty(&summary)? + "\n"))?,
        Output::Text => psdcal::print_text(&psdcal::summary_text(&summary))?,
    }
    Ok(())
}
