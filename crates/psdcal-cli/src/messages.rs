//! How failures and warnings reach the user: one `error: <what happened>;
//! <what to do>` line, and `warning: ...` lines, on standard error.

use psdcal_io::IoError;

/// How results are shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// Human-readable summary on standard output.
    Text,
    /// No summary.
    Quiet,
    /// JSON on standard output.
    Json,
}

/// At most this many warnings are printed one by one.
pub const MAX_WARNINGS: usize = 50;

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
    say(&format!("error: {what}; {}\n", psdcal::advice(&**error)));
}

/// Writes `text` on standard error as it is; a closed or full standard
/// error is ignored (`eprint!` would panic), there being nowhere left to
/// say anything.
pub fn say(text: &str) {
    use std::io::Write;
    let mut stderr = std::io::stderr().lock();
    let _ = stderr
        .write_all(text.as_bytes())
        .and_then(|()| stderr.flush());
}

/// Prints warnings on standard error, at most [`MAX_WARNINGS`] of them.
pub fn print_warnings<W: std::fmt::Display>(warnings: &[W]) {
    for warning in warnings.iter().take(MAX_WARNINGS) {
        say(&format!("warning: {warning}\n"));
    }
    if warnings.len() > MAX_WARNINGS {
        say(&format!(
            "warning: {} more warnings not shown (--json lists them all)\n",
            warnings.len() - MAX_WARNINGS
        ));
    }
}

/// Shows a job's summary: its warnings on standard error, then its text
/// (on standard error when the job's table is on standard output) or its
/// JSON.
pub fn emit(output: Output, summary: &psdcal::Summary) -> anyhow::Result<()> {
    print_warnings(&summary.warnings);
    match output {
        Output::Quiet => {}
        Output::Json => psdcal::print_text(&(serde_json::to_string_pretty(&summary.json)? + "\n"))?,
        Output::Text if summary.table_on_stdout => say(&summary.text),
        Output::Text => psdcal::print_text(&summary.text)?,
    }
    Ok(())
}
