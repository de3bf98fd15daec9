//! `psdcal correct`: measured points (or amplitudes) → ideal points.

use std::io::{self, Write};

use psdcal_io::{correct_points, read_calibration, write_atomic, IoError, Points};

use crate::cli::{CorrectConfig, Output};
use crate::report::print_warnings;

/// Runs `correct`.
pub fn run(config: &CorrectConfig, output: Output) -> anyhow::Result<()> {
    let calibration = read_calibration(&config.calibration)?;
    let points = Points::read(&config.points)?;
    let correction = correct_points(&points, &calibration)?;
    print_warnings(&correction.warnings);
    let Some(out) = &config.out else {
        let mut stdout = io::stdout().lock();
        return correction
            .write_csv(&points, &mut stdout)
            .and_then(|()| stdout.flush())
            .map_err(|source| {
                IoError::Write {
                    file: "standard output".to_string(),
                    source,
                }
                .into()
            });
    };
    write_atomic(out, |w| correction.write_csv(&points, w))?;
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
