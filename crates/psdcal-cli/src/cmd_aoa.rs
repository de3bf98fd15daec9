//! `psdcal aoa`: angles of arrival of measured points (or electrode
//! amplitudes) with their uncertainty (the library's `aoa_table`).

use crate::cli::Output;
use crate::cli_locate::AoaConfig;
use crate::report::print_row_warnings;

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
    let answer = &table.answer;
    print_row_warnings(&answer.count);
    let summary = format!(
        "aoa: {} point{} of {} with {}: {}",
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
                "command": "aoa",
                "calibration": config.calibration.display().to_string(),
                "points": answer.source,
                "out": out.as_ref().map(|p| p.display().to_string()),
                "from_amplitudes": answer.amplitudes,
                "point_sigma_mm": config.point_sigma_mm,
                "added_columns": answer.added,
                "rows": answer.count.to_json(),
            });
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, Some(out)) => println!("{summary}; wrote {}", out.display()),
        // The table is on standard output: the summary goes to standard error.
        (Output::Text, None) => eprintln!("{summary}"),
    }
    Ok(())
}
