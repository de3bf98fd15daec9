//! `psdcal correct`: measured points (or amplitudes) → ideal points.

use crate::cli::{CorrectConfig, Output};
use crate::report::print_warnings;

/// Runs `correct`.
pub fn run(config: &CorrectConfig, output: Output) -> anyhow::Result<()> {
    let corrected = psdcal::correct(&config.calibration, &config.points)?;
    let (points, correction) = (&corrected.points, &corrected.correction);
    print_warnings(&correction.warnings);
    corrected.write_to(config.out.as_deref())?;
    let Some(out) = &config.out else {
        return Ok(());
    };
    let columns = correction.added_columns();
    match output {
        Output::Quiet => {}
        Output::Json => {
            let summary = serde_json::json!({
                "calibration": config.calibration.display().to_string(),
                "points": points.source,
                "out": out.display().to_string(),
                "rows": points.rows.len(),
                "from_amplitudes": correction.from_amplitudes,
                "added_columns": columns,
                "warnings": correction.warnings,
            });
            println!("{}", serde_json::to_string_pretty(&summary)?);
        }
        Output::Text => println!(
            "corrected {} point{} of {} with {}: wrote {} (added {})",
            points.rows.len(),
            if points.rows.len() == 1 { "" } else { "s" },
            points.source,
            config.calibration.display(),
            out.display(),
            columns.join(", ")
        ),
    }
    Ok(())
}
