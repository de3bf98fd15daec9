//! The files `calibrate-network` names itself, checked before anything is
//! written (psdcal-io's `OutputFolder`: absent, or psdcal wrote them and
//! nobody changed them since, unless `force`): the refined calibrations
//! beside rig.json and the report page.

use std::path::{Path, PathBuf};

use psdcal_io::OutputFolder;

use crate::base::error::Result;

/// The report page's file in its folder.
pub(crate) const PAGE: &str = "index.html";

/// The folder of the refined calibrations beside `out`, checked.
pub(crate) fn claim_calibrations(
    out: &Path,
    calibrations: &[PathBuf],
    force: bool,
) -> Result<OutputFolder> {
    let dir = out.parent().unwrap_or_else(|| Path::new(""));
    let names: Vec<String> = calibrations
        .iter()
        .filter_map(|c| c.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    Ok(OutputFolder::claim(dir, &names, force)?)
}

/// The report folder, checked: its page.
pub(crate) fn claim_page(dir: &Path, force: bool) -> Result<OutputFolder> {
    Ok(OutputFolder::claim(dir, &[PAGE.to_string()], force)?)
}
