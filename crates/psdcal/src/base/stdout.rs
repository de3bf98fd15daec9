//! Standard output, written through fallible calls only (`print!` panics
//! when the output is closed or full), and the closed-output case told
//! apart so that the command line can end quietly when its reader went
//! away (`psdcal … | head -1`; docs/formats.md, "Outputs").

use std::io::{self, Write};

use psdcal_io::IoError;

/// The name standard output goes by in an [`IoError::Write`].
pub const STANDARD_OUTPUT: &str = "standard output";

/// Runs `write` on the locked standard output and flushes it; an error is
/// the write error of [`STANDARD_OUTPUT`].
pub fn write_stdout(write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<(), IoError> {
    let mut stdout = io::stdout().lock();
    write(&mut stdout)
        .and_then(|()| stdout.flush())
        .map_err(|source| IoError::Write {
            file: STANDARD_OUTPUT.to_string(),
            source,
        })
}

/// Prints `text` on standard output (no newline added).
pub fn print_text(text: &str) -> Result<(), IoError> {
    write_stdout(|out| out.write_all(text.as_bytes()))
}

/// Whether `error`, or an error it was caused by, is the output pipe
/// closed by its reader (`BrokenPipe`), looking into the errors an
/// `io::Error` or a CSV writer's error wraps too.
pub fn is_closed_output(error: &(dyn std::error::Error + 'static)) -> bool {
    if let Some(io) = error.downcast_ref::<io::Error>() {
        if io.kind() == io::ErrorKind::BrokenPipe
            || io.get_ref().is_some_and(|e| is_closed_output(e))
        {
            return true;
        }
    }
    if let Some(csv::ErrorKind::Io(io)) = error.downcast_ref::<csv::Error>().map(csv::Error::kind) {
        return is_closed_output(io);
    }
    error.source().is_some_and(is_closed_output)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_pipe_is_found_under_the_errors_wrapping_it() {
        let closed = IoError::Write {
            file: STANDARD_OUTPUT.to_string(),
            source: io::Error::from(io::ErrorKind::BrokenPipe),
        };
        assert!(is_closed_output(&closed));
        let wrapped = crate::Error::Io(closed);
        assert!(is_closed_output(&wrapped));
        let full = IoError::Write {
            file: STANDARD_OUTPUT.to_string(),
            source: io::Error::from(io::ErrorKind::StorageFull),
        };
        assert!(!is_closed_output(&full));
        // A CSV writer's error, turned into an io::Error of kind Other.
        let mut writer = csv::Writer::from_writer(Closed);
        let csv = writer
            .write_record(["a"])
            .and_then(|()| Ok(writer.flush()?));
        let other = io::Error::from(csv.unwrap_err());
        assert_eq!(other.kind(), io::ErrorKind::Other);
        assert!(is_closed_output(&other));
    }

    /// A writer whose reader went away.
    struct Closed;

    impl Write for Closed {
        fn write(&mut self, _: &[u8]) -> io::Result<usize> {
            Err(io::Error::from(io::ErrorKind::BrokenPipe))
        }
        fn flush(&mut self) -> io::Result<()> {
            Err(io::Error::from(io::ErrorKind::BrokenPipe))
        }
    }
}
