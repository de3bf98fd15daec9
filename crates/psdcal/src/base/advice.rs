//! What a user can do about an error: one short piece of advice per kind of
//! failure, the same from every front end (the command line prints it after
//! the message: `error: <what happened>; <what to do>`).

use std::error::Error as StdError;
use std::path::Path;

use psdcal_calib::CalibError;
use psdcal_io::IoError;
use psdcal_locate::LocateError;

use crate::base::error::Error;

/// The advice for `error`: that of the first error along its chain of
/// causes that psdcal knows, else a pointer to the help.
pub fn advice(error: &(dyn StdError + 'static)) -> &'static str {
    let mut current = Some(error);
    while let Some(e) = current {
        if let Some(advice) = advice_of(e) {
            return advice;
        }
        current = e.source();
    }
    "see 'psdcal --help'"
}

/// The one line a front end shows for `error` (the command line prints it
/// after `error: `; the Python package raises it): what happened — a file
/// error's own message, else the error and its causes joined by `: ` — then
/// `; ` and the [`advice`].
pub fn error_text(error: &Error) -> String {
    let what = match error {
        Error::Io(e) => e.to_string(),
        _ => {
            let mut parts = vec![error.to_string()];
            let mut current = error.source();
            while let Some(e) = current {
                parts.push(e.to_string());
                current = e.source();
            }
            parts.join(": ")
        }
    };
    format!("{}; {}", what.replace('\n', " "), advice(error))
}

fn advice_of(error: &(dyn StdError + 'static)) -> Option<&'static str> {
    if let Some(e) = error.downcast_ref::<Error>() {
        return match e {
            Error::Io(e) => Some(io_advice(e)),
            Error::Calibrate(e) | Error::Estimate(e) => Some(calib_advice(e)),
            Error::CalibrateData { source, .. } => Some(calib_advice(source)),
            Error::Locate(e) => Some(locate_advice(e)),
            Error::MisplacedLed { .. } => Some("correct that LED's row and calibrate again"),
            Error::Input(_) | Error::Options(_) => {
                Some("change the options or the data as the message says")
            }
            _ => None,
        };
    }
    if let Some(e) = error.downcast_ref::<IoError>() {
        return Some(io_advice(e));
    }
    if let Some(e) = error.downcast_ref::<CalibError>() {
        return Some(calib_advice(e));
    }
    error.downcast_ref::<LocateError>().map(locate_advice)
}

fn locate_advice(e: &LocateError) -> &'static str {
    match e {
        LocateError::InvalidInput { .. } | LocateError::NonFinite { .. } => {
            "change the options or the data as the message says"
        }
        LocateError::InvalidCovariance { .. } => "write the calibration again with psdcal",
        _ => "see 'psdcal locate --help'",
    }
}

fn calib_advice(calib: &CalibError) -> &'static str {
    match calib {
        CalibError::TooFewImages { .. } | CalibError::TooFewPoints { .. } => {
            "add template poses (images) with at least 4 LEDs each"
        }
        CalibError::Degenerate { .. } => {
            "vary the template's tilt and position between images, or fix the parameters the data \
             cannot determine"
        }
        CalibError::FocalOutsideSearch { guess: Some(_), .. } => {
            "give a --focal-guess nearer the lens's focal length in mm (or none: the search then \
             covers 1–1000 mm)"
        }
        CalibError::FocalOutsideSearch { guess: None, .. } => {
            "give --focal-guess with the lens's focal length in mm"
        }
        CalibError::InvalidInput { .. } => "change the options or the data as the message says",
        CalibError::Model(_) => "check the data and the fixed values (--set)",
        CalibError::NotConverged { .. } => {
            "give --focal-guess, free fewer parameters (--fit), or add images"
        }
        _ => "check the data with 'psdcal check', or give --focal-guess",
    }
}

fn io_advice(io: &IoError) -> &'static str {
    match io {
        IoError::Field { .. } => {
            "correct that field of the rig file (format: docs/formats.md, 'rig.json')"
        }
        IoError::Read { .. } => "check the path and that the file is readable",
        IoError::Write { file, .. } if file == crate::base::stdout::STANDARD_OUTPUT => {
            "check where standard output goes (a full disk, or a closed pipe)"
        }
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
        IoError::NotOurs { .. } => "give --force to replace it, or --out another folder",
        IoError::NewerVersion { .. } => "upgrade psdcal to read this file",
        IoError::Strict { .. } => "fix the data, or run without --strict to drop it with a warning",
        _ => "see 'psdcal --help'",
    }
}

/// What to do about a JSON file that does not parse, by its kind.
fn json_hint(file: &str) -> &'static str {
    let name = Path::new(file)
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
