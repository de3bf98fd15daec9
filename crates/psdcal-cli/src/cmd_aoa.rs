//! `psdcal aoa`: angles of arrival of measured points (or electrode
//! amplitudes) with their uncertainty (the library's `aoa_table`).

use crate::cli::Output;
use crate::cli_locate::AoaConfig;
use crate::report::{print_points_answer, PointsSummary};

/// Runs `aoa`.
pub fn run(config: &AoaConfig, output: Output) -> anyhow::Result<()> {
    let table = psdcal::aoa_table(
        &config.calibration,
        &config.points,
        config.point_sigma_mm,
        config.out.as_deref(),
    )?;
    if let Some(w) = psdcal::covariance_warning(&table.sensor) {
        eprintln!("warning: {w}");
    }
    let summary = PointsSummary {
        command: "aoa",
        verb: "aoa:",
        calibration: &config.calibration,
        out: config.out.as_deref(),
        extra: serde_json::json!({ "point_sigma_mm": config.point_sigma_mm }),
        name_columns: false,
    };
    print_points_answer(&table.answer, &summary, output)
}
