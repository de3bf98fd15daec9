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
    eprintln!("error: {what}; {}", psdcal::advice(&**error));
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
    let line = answer.summary_line(summary.verb, summary.calibration);
    match (output, summary.out) {
        (Output::Quiet, _) => {}
        (Output::Json, out) => {
            let json =
                answer.summary_json(summary.command, summary.calibration, out, &summary.extra);
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
