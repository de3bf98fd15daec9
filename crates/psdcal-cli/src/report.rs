//! How failures and warnings reach the user: one `error: <what happened>;
//! <what to do>` line, and `warning: ...` lines, on standard error.

use psdcal_io::{IoError, Warning};

/// At most this many warnings are printed one by one.
const MAX_WARNINGS: usize = 50;

/// The error the library wrapped, so that its message and hint are the
/// lower crate's own.
pub fn lower(error: anyhow::Error) -> anyhow::Error {
    match error.downcast::<psdcal::Error>() {
        Ok(psdcal::Error::Io(e)) => e.into(),
        Ok(psdcal::Error::Estimate(e)) => e.into(),
        Ok(psdcal::Error::Locate(e)) => e.into(),
        Ok(psdcal::Error::Calibrate(e)) => anyhow::Error::new(e).context("calibration failed"),
        Ok(other) => other.into(),
        Err(error) => error,
    }
}

/// Prints the failure as one line on standard error.
pub fn print_error(error: &anyhow::Error) {
    // psdcal-io's messages already include their causes; other errors get
    // their chain of causes joined with ": ".
    let what = if error.is::<IoError>() {
        error.to_string()
    } else {
        format!("{error:#}")
    };
    let what = what.replace('\n', " ");
    eprintln!("error: {what}; {}", hint(error));
}

/// Prints warnings on standard error, at most [`MAX_WARNINGS`] of them.
pub fn print_warnings(warnings: &[Warning]) {
    for warning in warnings.iter().take(MAX_WARNINGS) {
        eprintln!("warning: {warning}");
    }
    if warnings.len() > MAX_WARNINGS {
        eprintln!(
            "warning: {} more warnings not shown (--json lists them all)",
            warnings.len() - MAX_WARNINGS
        );
    }
}

/// What the user can do about an error.
fn hint(error: &anyhow::Error) -> &'static str {
    if let Some(e) = error.downcast_ref::<psdcal::LocateError>() {
        return match e {
            psdcal::LocateError::InvalidInput { .. } | psdcal::LocateError::NonFinite { .. } => {
                "change the options or the data as the message says"
            }
            psdcal::LocateError::InvalidCovariance { .. } => {
                "write the calibration again with psdcal"
            }
            _ => "see 'psdcal locate --help'",
        };
    }
    if let Some(calib) = error.downcast_ref::<psdcal::CalibError>() {
        return match calib {
            psdcal::CalibError::TooFewImages { .. } | psdcal::CalibError::TooFewPoints { .. } => {
                "add template poses (images) with at least 4 LEDs each"
            }
            psdcal::CalibError::Degenerate { .. } => {
                "vary the template's tilt and position between images, or fix the parameters the data cannot determine"
            }
            psdcal::CalibError::InvalidInput { .. } => "change the options or the data as the message says",
            psdcal::CalibError::Model(_) => "check the data and the fixed values (--set)",
            psdcal::CalibError::NotConverged { .. } => {
                "give --focal-guess, free fewer parameters (--fit), or add images"
            }
            _ => "check the data with 'psdcal check', or give --focal-guess",
        };
    }
    let Some(io) = error.downcast_ref::<IoError>() else {
        return "see 'psdcal --help'";
    };
    match io {
        IoError::Field { .. } => {
            "correct that field of the rig file (format: docs/formats.md, 'rig.json')"
        }
        IoError::Read { .. } => "check the path and that the file is readable",
        IoError::Write { .. } => "check that the destination folder exists and is writable",
        IoError::Encoding { .. } => "save the file as UTF-8 text (CSV or JSON)",
        IoError::Structure { .. } => "fix the file's header or rows (formats: docs/formats.md)",
        IoError::Value { .. } => "correct the value on that line",
        IoError::UnknownLed { .. } => "add the LED to the template or correct its identifier",
        IoError::Duplicate { .. } => "keep only one of the two rows",
        IoError::Invalid { .. } => "correct the data (formats: docs/formats.md)",
        IoError::Amplitudes { .. } => {
            "check that row's amplitudes (no light reached the sensor, or a channel is broken)"
        }
        IoError::Json { file, .. } => json_hint(file),
        IoError::TooLarge { .. } => {
            "give a smaller file, or raise the limit with --max-input-mb (docs/formats.md, 'Limits')"
        }
        IoError::OutputIsInput { .. } => "write the output to another file",
        IoError::NewerVersion { .. } => "upgrade psdcal to read this file",
        IoError::Strict { .. } => "fix the data, or run without --strict to drop it with a warning",
        _ => "see 'psdcal --help'",
    }
}

/// What to do about a JSON file that does not parse, by its kind.
fn json_hint(file: &str) -> &'static str {
    let name = std::path::Path::new(file)
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.contains("rig") {
        "correct the rig file at that line and column (format: docs/formats.md, 'rig.json')"
    } else if name.contains("gain") {
        "correct the gains file at that line and column, or write it again with 'psdcal gains'"
    } else if name.contains("truth") {
        "correct the truth file at that line and column, or write it again with 'psdcal simulate'"
    } else {
        "correct the JSON file at that line and column, or write it again with psdcal (formats: docs/formats.md)"
    }
}

/// Prints the warnings kept for the table rows that are not `ok` (the
/// first [`psdcal::MAX_ROW_WARNINGS`]) and how many more there are.
pub fn print_row_warnings(count: &psdcal::StatusCount) {
    for w in &count.warnings {
        eprintln!("warning: {w}");
    }
    let more = count.not_ok().saturating_sub(count.warnings.len());
    if more > 0 {
        eprintln!("warning: {more} more rows with a status other than ok (see the status column)");
    }
}

/// What a points command (`aoa`, `correct`) answered, and how to say it.
pub struct PointsSummary<'a> {
    /// The command's name (`aoa`, `correct`).
    pub command: &'a str,
    /// The summary line's opening (`aoa:`, `corrected`).
    pub verb: &'a str,
    /// The calibration file.
    pub calibration: &'a std::path::Path,
    /// Where the table went (`None`: standard output).
    pub out: Option<&'a std::path::Path>,
    /// Command-specific JSON fields.
    pub extra: serde_json::Value,
    /// Whether the text summary names the added columns.
    pub name_columns: bool,
}

/// Prints the row warnings and the summary of a points command: one line
/// (on standard error when the table is on standard output) or JSON.
pub fn print_points_answer(
    answer: &psdcal::PointsAnswer,
    summary: &PointsSummary<'_>,
    output: crate::cli::Output,
) -> anyhow::Result<()> {
    use crate::cli::Output;
    print_row_warnings(&answer.count);
    let line = format!(
        "{} {} point{} of {} with {}: {}",
        summary.verb,
        answer.rows,
        if answer.rows == 1 { "" } else { "s" },
        answer.source,
        summary.calibration.display(),
        answer.count.summary()
    );
    match (output, summary.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let mut json = serde_json::json!({
                "command": summary.command,
                "calibration": summary.calibration.display().to_string(),
                "points": answer.source,
                "out": out.map(|p| p.display().to_string()),
                "from_amplitudes": answer.amplitudes,
                "added_columns": answer.added,
                "rows": answer.count.to_json(),
            });
            if let (Some(map), Some(extra)) = (json.as_object_mut(), summary.extra.as_object()) {
                map.extend(extra.clone());
            }
            println!("{}", serde_json::to_string_pretty(&json)?);
        }
        (Output::Text, Some(out)) if summary.name_columns => println!(
            "{line}; wrote {} (added {})",
            out.display(),
            answer.added.join(", ")
        ),
        (Output::Text, Some(out)) => println!("{line}; wrote {}", out.display()),
        // The table is on standard output: the summary goes to standard error.
        (Output::Text, None) => eprintln!("{line}"),
    }
    Ok(())
}
