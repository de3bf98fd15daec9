//! What a finished job says: a few lines for people, one JSON value for
//! scripts, and its warnings. Every front end (the CLI's text, `--json`,
//! the Python package) shows the same [`Summary`]; none rebuilds it.

use std::path::Path;

/// The summary of one job.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Human-readable lines, each ending in a newline.
    pub text: String,
    /// The same facts for scripts (`--json`).
    pub json: serde_json::Value,
    /// Warnings, one sentence each, without a `warning:` prefix.
    pub warnings: Vec<String>,
    /// Whether the job's table went to standard output, so that the text
    /// belongs on standard error.
    pub table_on_stdout: bool,
}

impl Summary {
    /// A summary of `text` (a newline is added when missing) and `json`.
    pub fn new(text: impl Into<String>, json: serde_json::Value) -> Self {
        let mut text = text.into();
        if !text.is_empty() && !text.ends_with('\n') {
            text.push('\n');
        }
        Summary {
            text,
            json,
            warnings: Vec::new(),
            table_on_stdout: false,
        }
    }

    /// With `warnings` added (anything that displays).
    pub fn warn<W: std::fmt::Display>(mut self, warnings: impl IntoIterator<Item = W>) -> Self {
        self.warnings
            .extend(warnings.into_iter().map(|w| w.to_string()));
        self
    }

    /// With the line `wrote <path>` for each path given.
    pub fn wrote<'a>(mut self, paths: impl IntoIterator<Item = &'a Path>) -> Self {
        for path in paths {
            self.text.push_str(&format!("wrote {}\n", path.display()));
        }
        self
    }

    /// Where the job's table went: `None` is standard output (the text then
    /// goes to standard error); a file adds `; wrote <file>` to the text's
    /// last line.
    pub fn table_at(mut self, out: Option<&Path>) -> Self {
        match out {
            None => self.table_on_stdout = true,
            Some(path) => {
                let line = self.text.trim_end_matches('\n').to_string();
                self.text = format!("{line}; wrote {}\n", path.display());
            }
        }
        self
    }
}

/// A path as JSON text (`null` when absent).
pub(crate) fn path_json(path: Option<&Path>) -> serde_json::Value {
    path.map_or(serde_json::Value::Null, |p| p.display().to_string().into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_on_a_file_ends_the_last_line_and_on_stdout_moves_the_text() {
        let s = Summary::new("a\nb", serde_json::json!({})).table_at(Some(Path::new("t.csv")));
        assert_eq!(s.text, "a\nb; wrote t.csv\n");
        assert!(!s.table_on_stdout);
        let s = Summary::new("a", serde_json::json!({})).table_at(None);
        assert_eq!(s.text, "a\n");
        assert!(s.table_on_stdout);
        let s = Summary::new("", serde_json::json!(1))
            .wrote([Path::new("x")])
            .warn(["w"]);
        assert_eq!(
            (s.text.as_str(), s.warnings.as_slice()),
            ("wrote x\n", &["w".to_string()][..])
        );
    }
}
