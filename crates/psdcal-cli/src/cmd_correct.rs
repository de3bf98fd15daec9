//! `psdcal correct`: measured points (or amplitudes) → ideal points, with
//! a status per row.

use crate::cli::{CorrectConfig, Output};
use crate::report::{print_points_answer, PointsSummary};

/// Runs `correct`.
pub fn run(config: &CorrectConfig, output: Output) -> anyhow::Result<()> {
    let corrected = psdcal::correct(&config.calibration, &config.points, config.out.as_deref())?;
    let summary = PointsSummary {
        command: "correct",
        verb: "corrected",
        calibration: &config.calibration,
        out: config.out.as_deref(),
        extra: serde_json::json!({}),
        name_columns: true,
    };
    print_points_answer(&corrected.answer, &summary, output)
}
