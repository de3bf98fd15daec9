//! `psdcal check`: validate a data set and summarise it.

use psdcal::{DataSet, DataSetFiles, LoadOptions};

use crate::messages::print_warnings;
use crate::messages::Output;

/// Runs `check`.
pub fn run(files: &DataSetFiles, load: &LoadOptions, output: Output) -> anyhow::Result<()> {
    let set = DataSet::from_files(files, load)?;
    print_warnings(set.warnings());
    let summary = set.summary();
    let json = serde_json::to_value(&summary)?;
    crate::messages::emit(
        output,
        &psdcal::Summary::new(psdcal::summary_text(&summary), json),
    )
}
