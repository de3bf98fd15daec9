//! `psdcal locate`: emitter positions with their 3-D covariance, on a plane
//! in the sensor frame or from a rig of sensors (the library's
//! `locate_table`).

use crate::cli_locate::LocateConfig;
use crate::messages::Output;
use psdcal::ReadLimits;

/// Runs `locate`.
pub fn run(config: &LocateConfig, output: Output, limits: ReadLimits) -> anyhow::Result<()> {
    let out = config.out.as_deref();
    let answer =
        psdcal::locate_table(&config.target, &config.points, &config.options, out, limits)?;
    let sigma = config
        .point_sigma_given
        .then_some(config.options.point_sigma_mm);
    let summary = answer.summary(&config.target, &config.points, out, &config.options, sigma);
    crate::messages::emit(output, &summary)
}
