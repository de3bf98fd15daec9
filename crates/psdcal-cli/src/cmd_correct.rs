//! `psdcal correct`: measured points (or amplitudes) → ideal points, with
//! a status per row.

use crate::cli::{CorrectConfig, Output};
use crate::report::print_row_warnings;

/// Runs `correct`.
pub fn run(config: &CorrectConfig, output: Output) -> anyhow::Result<()> {
    let corrected = psdcal::correct(&config.calibration, &config.points, config.out.as_deref())?;
    let answer = &corrected.answer;
    print_row_warnings(&answer.count);
    let summary = format!(
        "corrected {} point{} of {} with {}: {}",
        answer.rows,
        if answer.rows == 1 { "" } else { "s" },
        answer.source,
        config.calibration.display(),
        answer.count.summary()
    );
    match (output, &config.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let json = serde_json::json!({
                "command": "correct",
                "calibration": config.calibration.display().to_string(),
                "points": answer.source,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "from_amplitudes": answer.amplitudes,
                "added_columns": answer.added,
                "rows": answer.count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, Some(out)) => println!(
            "{summary}; wrote {} (added {})",
            out.display(),
            answer.added.join(", ")
        ),
        (Output::Text, None) => eprintln!("{summary}"),
    }
    Ok(())
}
