//! Where a problem sits in a file: the place named by every error and
//! warning.

use std::fmt;

/// A place in a file: its name as given by the user and, when the problem
/// sits on a line, the 1-based physical line number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// File name or path, as shown to the user.
    pub file: String,
    /// 1-based physical line, if the problem is on one line.
    pub line: Option<usize>,
}

impl Location {
    /// A location on a line of a file.
    pub fn line(file: &str, line: usize) -> Self {
        Self {
            file: file.to_string(),
            line: Some(line),
        }
    }

    /// A location for a whole file.
    pub fn file(file: &str) -> Self {
        Self {
            file: file.to_string(),
            line: None,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}", self.file, line),
            None => f.write_str(&self.file),
        }
    }
}
