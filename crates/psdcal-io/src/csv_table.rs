//! Shared CSV reading for every psdcal table (docs/formats.md, "All CSV files").
//!
//! The format: UTF-8 text (a leading byte-order mark is accepted), fields
//! separated by commas, one header row naming the columns, then one record
//! per line. Lines that are blank (or hold only empty fields, as spreadsheets
//! export them) and lines whose first non-blank character is `#` are
//! skipped, but still counted: every line number reported is the physical
//! line in the file, 1-based, whatever the line endings (`\n` or `\r\n`).
//!
//! Columns are found by name, so their order is free and extra columns are
//! ignored. A name is matched exactly first, then ignoring ASCII case (so
//! `x_mm` finds `X_mm`); a name that matches two header fields is an error.
//! Fields may be quoted with `"` (a doubled `""` is a literal quote); a quoted
//! field cannot span lines. Every record must have as many fields as the
//! header (trailing empty fields beyond it are tolerated).
//!
//! Files that are not CSV text get a precise error instead of a confusing
//! one: binary data (NUL or other control bytes), bytes that are not UTF-8,
//! and a header that is separated by `;` or tabs instead of commas.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::csv_fields::split_fields;
use crate::csv_lines::LineReader;
use crate::error::{quoted, ColumnRef, IoError};
use crate::limits::{excerpt, ReadLimits};
use crate::location::Location;

/// The readers of a CSV table type that has `fn from_table(CsvTable) ->
/// Result<Self, IoError>` and a `EXPECTED_COLUMNS` in scope: from a path, a
/// reader or text, with the default [`ReadLimits`] or given ones. `$file`
/// names the file in the docs. With `streamed`, the type has
/// `fn from_stream<R: BufRead>(CsvStream<R>) -> Result<Self, IoError>`
/// instead, which converts each record as it is read
/// ([`CsvStream::map_rows`]): no record is kept as text, so memory follows
/// the rows' values, not the file's fields.
macro_rules! csv_table_readers {
    ($file:literal) => {
        #[doc = concat!("Reads ", $file, " from a file.")]
        pub fn read(path: impl AsRef<std::path::Path>) -> Result<Self, IoError> {
            Self::read_with(path, ReadLimits::default())
        }

        /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
        pub fn read_with(
            path: impl AsRef<std::path::Path>,
            limits: ReadLimits,
        ) -> Result<Self, IoError> {
            Self::from_table($crate::csv_table::CsvTable::read_path(
                path.as_ref(),
                EXPECTED_COLUMNS,
                limits,
            )?)
        }

        #[doc = concat!("Reads ", $file, " from a reader; `source` names it in messages.")]
        pub fn from_reader(source: &str, reader: impl std::io::Read) -> Result<Self, IoError> {
            Self::from_reader_with(source, reader, ReadLimits::default())
        }

        /// [`Self::from_reader`] within `limits` (docs/formats.md, "Limits").
        pub fn from_reader_with(
            source: &str,
            reader: impl std::io::Read,
            limits: ReadLimits,
        ) -> Result<Self, IoError> {
            Self::from_table($crate::csv_table::CsvTable::from_reader(
                source,
                reader,
                EXPECTED_COLUMNS,
                limits,
            )?)
        }

        #[doc = concat!("Parses ", $file, " text; `source` names it in messages.")]
        pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
            Self::from_table($crate::csv_table::CsvTable::parse(
                source,
                text.as_bytes(),
                EXPECTED_COLUMNS,
            )?)
        }
    };
    (streamed $file:literal) => {
        #[doc = concat!("Reads ", $file, " from a file.")]
        pub fn read(path: impl AsRef<std::path::Path>) -> Result<Self, IoError> {
            Self::read_with(path, ReadLimits::default())
        }

        /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
        pub fn read_with(
            path: impl AsRef<std::path::Path>,
            limits: ReadLimits,
        ) -> Result<Self, IoError> {
            Self::from_stream($crate::csv_table::CsvStream::open(
                path.as_ref(),
                EXPECTED_COLUMNS,
                Some(limits.max_file_bytes),
            )?)
        }

        #[doc = concat!("Reads ", $file, " from a reader; `source` names it in messages.")]
        pub fn from_reader(source: &str, reader: impl std::io::Read) -> Result<Self, IoError> {
            Self::from_reader_with(source, reader, ReadLimits::default())
        }

        /// [`Self::from_reader`] within `limits` (docs/formats.md, "Limits").
        pub fn from_reader_with(
            source: &str,
            reader: impl std::io::Read,
            limits: ReadLimits,
        ) -> Result<Self, IoError> {
            Self::from_stream($crate::csv_table::CsvStream::new(
                source,
                std::io::BufReader::new(reader),
                EXPECTED_COLUMNS,
                Some(limits.max_file_bytes),
            )?)
        }

        #[doc = concat!("Parses ", $file, " text; `source` names it in messages.")]
        pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
            Self::from_stream($crate::csv_table::CsvStream::new(
                source,
                text.as_bytes(),
                EXPECTED_COLUMNS,
                None,
            )?)
        }
    };
}

/// A parsed CSV file: its header and its data records, with line numbers.
#[derive(Debug, Clone)]
pub(crate) struct CsvTable {
    /// File name for messages.
    pub source: String,
    /// Header fields, as written (unquoted, not trimmed).
    pub header: Vec<String>,
    /// Physical line of the header.
    pub header_line: usize,
    /// Data records.
    pub rows: Vec<CsvRow>,
    /// The columns the format expects, for messages (e.g. `image, led, x_mm, y_mm`).
    expected: &'static str,
}

/// One data record.
#[derive(Debug, Clone)]
pub(crate) struct CsvRow {
    /// Physical line, 1-based.
    pub line: usize,
    /// Fields as written (unquoted, not trimmed); exactly as many as the header.
    pub fields: Vec<String>,
}

/// A located column.
#[derive(Debug, Clone)]
pub(crate) struct Col {
    /// 0-based index into the fields.
    pub index: usize,
    /// Header name (trimmed).
    pub name: String,
}

impl Col {
    /// The column as reported in errors.
    pub fn to_ref(&self) -> ColumnRef {
        ColumnRef {
            name: self.name.clone(),
            number: self.index + 1,
        }
    }
}

impl CsvTable {
    /// Reads and parses a file (within `limits`); `expected` lists the
    /// format's columns for messages.
    pub fn read_path(
        path: &Path,
        expected: &'static str,
        limits: ReadLimits,
    ) -> Result<Self, IoError> {
        let stream = CsvStream::open(path, expected, Some(limits.max_file_bytes))?;
        stream.collect_rows()
    }

    /// Reads everything from `reader` (within `limits`) and parses it;
    /// `source` names it in messages.
    pub fn from_reader(
        source: &str,
        reader: impl Read,
        expected: &'static str,
        limits: ReadLimits,
    ) -> Result<Self, IoError> {
        let stream = CsvStream::new(
            source,
            BufReader::new(reader),
            expected,
            Some(limits.max_file_bytes),
        )?;
        stream.collect_rows()
    }

    /// Parses the bytes of a CSV file.
    pub fn parse(source: &str, bytes: &[u8], expected: &'static str) -> Result<Self, IoError> {
        CsvStream::new(source, bytes, expected, None)?.collect_rows()
    }

    /// A location on a line of this file.
    pub fn at(&self, line: usize) -> Location {
        Location::line(&self.source, line)
    }

    /// Fails when the file has a header but no data records.
    pub fn require_rows(&self) -> Result<(), IoError> {
        if self.rows.is_empty() {
            return Err(IoError::Structure {
                at: self.at(self.header_line),
                message: "the file has a header but no data rows; expected at least one row \
                          after it"
                    .to_string(),
            });
        }
        Ok(())
    }

    /// The column called `name`, if the header has it (exact match first,
    /// then ignoring ASCII case); two matching header fields are an error.
    pub fn find_column(&self, name: &str) -> Result<Option<Col>, IoError> {
        let names: Vec<&str> = self.header.iter().map(|h| h.trim()).collect();
        let exact: Vec<usize> = (0..names.len()).filter(|&i| names[i] == name).collect();
        let matches = if exact.is_empty() {
            (0..names.len())
                .filter(|&i| names[i].eq_ignore_ascii_case(name))
                .collect()
        } else {
            exact
        };
        match matches.as_slice() {
            [] => Ok(None),
            [index] => Ok(Some(Col {
                index: *index,
                name: names[*index].to_string(),
            })),
            [first, second, ..] => Err(IoError::Structure {
                at: self.at(self.header_line),
                message: format!(
                    "the header names column '{name}' twice (columns {} and {}); expected each \
                     column once",
                    first + 1,
                    second + 1
                ),
            }),
        }
    }

    /// The column called `name`; its absence is an error naming the header line.
    pub fn column(&self, name: &str) -> Result<Col, IoError> {
        self.find_column(name)?
            .ok_or_else(|| self.missing_column(name))
    }

    /// The error for a missing column.
    pub fn missing_column(&self, name: &str) -> IoError {
        let found: Vec<&str> = self
            .header
            .iter()
            .map(|h| h.trim())
            .filter(|h| !h.is_empty())
            .collect();
        IoError::Structure {
            at: self.at(self.header_line),
            message: format!(
                "missing column '{name}'; expected the columns {} (the header has: {})",
                self.expected,
                excerpt(&found.join(", "))
            ),
        }
    }

    /// The trimmed text of a field.
    pub fn text<'r>(&self, row: &'r CsvRow, col: &Col) -> &'r str {
        row.fields.get(col.index).map_or("", |f| f.trim())
    }

    /// A finite number from a field.
    pub fn number(&self, row: &CsvRow, col: &Col) -> Result<f64, IoError> {
        parse_number(self.text(row, col)).map_err(|message| IoError::Value {
            at: self.at(row.line),
            column: col.to_ref(),
            message,
        })
    }

    /// A non-empty identifier (LED, image) from a field; `what` names it.
    pub fn identifier(&self, row: &CsvRow, col: &Col, what: &str) -> Result<String, IoError> {
        self.identifier_text(row, col, what).map(str::to_string)
    }

    /// [`Self::identifier`] without copying it.
    pub fn identifier_text<'r>(
        &self,
        row: &'r CsvRow,
        col: &Col,
        what: &str,
    ) -> Result<&'r str, IoError> {
        let text = self.text(row, col);
        if text.is_empty() {
            return Err(IoError::Value {
                at: self.at(row.line),
                column: col.to_ref(),
                message: format!("expected {what}, found an empty field"),
            });
        }
        Ok(text)
    }
}

/// A CSV file read row by row in constant memory: the header (with the
/// column lookups of [`CsvTable`], whose `rows` stay empty), then each record
/// on demand.
pub(crate) struct CsvStream<R> {
    /// The header, as a table without rows.
    pub head: CsvTable,
    lines: LineReader<R>,
}

impl CsvStream<BufReader<File>> {
    /// Opens a file and reads up to its header; `limit` bounds its size.
    pub fn open(path: &Path, expected: &'static str, limit: Option<u64>) -> Result<Self, IoError> {
        let source = path.display().to_string();
        let file = File::open(path).map_err(|e| IoError::Read {
            file: source.clone(),
            source: e,
        })?;
        Self::new(&source, BufReader::new(file), expected, limit)
    }
}

impl<R: BufRead> CsvStream<R> {
    /// Reads up to the header of `reader`; `source` names it in messages.
    pub fn new(
        source: &str,
        reader: R,
        expected: &'static str,
        limit: Option<u64>,
    ) -> Result<Self, IoError> {
        let mut lines = LineReader::new(source, reader, limit);
        let mut seen_text = false;
        loop {
            let Some((line, content)) = lines.next_line()? else {
                let message = if seen_text {
                    format!(
                        "the file holds only comments and blank lines; expected a header row \
                         with the columns {expected}"
                    )
                } else {
                    format!("the file is empty; expected a header row with the columns {expected}")
                };
                return Err(IoError::Structure {
                    at: Location::file(source),
                    message,
                });
            };
            let Some(fields) = significant_fields(source, line, content, &mut seen_text)? else {
                continue;
            };
            check_delimiter(source, line, content, &fields, expected)?;
            let head = CsvTable {
                source: source.to_string(),
                header: fields,
                header_line: line,
                rows: Vec::new(),
                expected,
            };
            return Ok(Self { head, lines });
        }
    }

    /// The next data record, or `None` at the end of the file.
    pub fn next_row(&mut self) -> Result<Option<CsvRow>, IoError> {
        let mut seen_text = true;
        loop {
            let Some((line, content)) = self.lines.next_line()? else {
                return Ok(None);
            };
            let source = &self.head.source;
            let Some(fields) = significant_fields(source, line, content, &mut seen_text)? else {
                continue;
            };
            let fields = fit_to_header(
                source,
                line,
                fields,
                self.head.header.len(),
                self.head.header_line,
            )?;
            return Ok(Some(CsvRow { line, fields }));
        }
    }

    /// The underlying lines, for a reader that takes plain lines itself
    /// (`csv_numeric`) and leaves the others to [`next_row`](Self::next_row).
    pub fn lines(&mut self) -> &mut LineReader<R> {
        &mut self.lines
    }

    /// Every remaining record converted by `convert` as soon as it is read
    /// (its text dropped at once); the header and the values.
    pub fn map_rows<T>(
        mut self,
        mut convert: impl FnMut(&CsvTable, &CsvRow) -> Result<T, IoError>,
    ) -> Result<(CsvTable, Vec<T>), IoError> {
        let mut values = Vec::new();
        while let Some(row) = self.next_row()? {
            values.push(convert(&self.head, &row)?);
        }
        values.shrink_to_fit();
        Ok((self.head, values))
    }

    /// Every remaining record, as a table.
    pub fn collect_rows(mut self) -> Result<CsvTable, IoError> {
        while let Some(row) = self.next_row()? {
            self.head.rows.push(row);
        }
        Ok(self.head)
    }
}

/// The fields of a line, or `None` for a line that is skipped (blank, a
/// comment, only empty fields); `seen_text` records whether any non-blank
/// line was seen.
fn significant_fields(
    source: &str,
    line: usize,
    content: &str,
    seen_text: &mut bool,
) -> Result<Option<Vec<String>>, IoError> {
    let trimmed = content.trim();
    if trimmed.is_empty() {
        return Ok(None);
    }
    *seen_text = true;
    if trimmed.starts_with('#') {
        return Ok(None);
    }
    let fields = split_fields(content).map_err(|message| IoError::Structure {
        at: Location::line(source, line),
        message,
    })?;
    if fields.iter().all(|f| f.trim().is_empty()) {
        return Ok(None);
    }
    Ok(Some(fields))
}

/// Parses a finite decimal or scientific number; the error says what was
/// found (never echoing a NaN spelling back).
pub(crate) fn parse_number(text: &str) -> Result<f64, String> {
    let text = text.trim();
    if text.is_empty() {
        return Err("expected a number, found an empty field".to_string());
    }
    match text.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(value),
        Ok(value) if value.is_nan() => {
            Err("expected a finite number, found a not-a-number value".to_string())
        }
        Ok(_) => {
            let lower = text.to_ascii_lowercase();
            if lower.contains("inf") {
                Err(format!(
                    "expected a finite number, found an infinite value {}",
                    quoted(text)
                ))
            } else {
                Err(format!(
                    "expected a finite number, found {}, which is beyond the range of 64-bit \
                     floating point",
                    quoted(text)
                ))
            }
        }
        Err(_) => Err(format!("expected a number, found {}", quoted(text))),
    }
}

/// A header that is one field containing `;` or a tab is a file with the
/// wrong delimiter.
fn check_delimiter(
    source: &str,
    line: usize,
    content: &str,
    fields: &[String],
    expected: &str,
) -> Result<(), IoError> {
    if fields.len() != 1 {
        return Ok(());
    }
    let found = if content.contains(';') {
        "semicolons (;)"
    } else if content.contains('\t') {
        "tabs"
    } else {
        return Ok(());
    };
    Err(IoError::Structure {
        at: Location::line(source, line),
        message: format!(
            "the header is separated by {found}; expected comma-separated columns \
             {expected}"
        ),
    })
}

/// Checks a record's field count against the header's.
fn fit_to_header(
    source: &str,
    line: usize,
    mut fields: Vec<String>,
    expected: usize,
    header_line: usize,
) -> Result<Vec<String>, IoError> {
    let found = fields.len();
    if found > expected && fields[expected..].iter().all(|f| f.trim().is_empty()) {
        fields.truncate(expected);
    }
    if fields.len() == expected {
        return Ok(fields);
    }
    let hint = match fields.as_slice() {
        [only] if only.contains(';') => " (the row looks separated by semicolons; use commas)",
        [only] if only.contains('\t') => " (the row looks separated by tabs; use commas)",
        _ => "",
    };
    Err(IoError::Structure {
        at: Location::line(source, line),
        message: format!(
            "expected {expected} fields as in the header on line {header_line}, found \
             {found}{hint}"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const EXPECTED: &str = "a, b";

    fn parse(text: &str) -> Result<CsvTable, IoError> {
        CsvTable::parse("t.csv", text.as_bytes(), EXPECTED)
    }

    fn lines(table: &CsvTable) -> Vec<usize> {
        table.rows.iter().map(|r| r.line).collect()
    }

    #[test]
    fn physical_lines_count_comments_blanks_and_crlf() {
        let text = "# comment\r\n\r\na,b\r\n   \r\n# x, \"y\r\n1,2\r\n  # indented\r\n,\r\n3,4";
        let t = parse(text).unwrap();
        assert_eq!(t.header_line, 3);
        assert_eq!(t.header, vec!["a", "b"]);
        assert_eq!(lines(&t), vec![6, 9]);
        assert_eq!(t.rows[1].fields, vec!["3", "4"]);
    }

    #[test]
    fn bom_is_dropped() {
        let t = CsvTable::parse("t.csv", b"\xEF\xBB\xBFa,b\n1,2\n", EXPECTED).unwrap();
        assert_eq!(t.header, vec!["a", "b"]);
        assert_eq!(t.column("a").unwrap().index, 0);
    }

    #[test]
    fn unterminated_quote_names_the_line() {
        let e = parse("a,b\n1,2\n3,\"4\n").unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(matches!(e, IoError::Structure { .. }), "{e}");
    }

    #[test]
    fn column_lookup_exact_then_case_insensitive() {
        let t = parse("X_mm,x_mm,Y_MM\n1,2,3\n").unwrap();
        assert_eq!(t.column("x_mm").unwrap().index, 1);
        assert_eq!(t.column("X_mm").unwrap().index, 0);
        assert_eq!(t.column("y_mm").unwrap().index, 2);
        assert_eq!(t.column("y_mm").unwrap().name, "Y_MM");
    }

    #[test]
    fn ambiguous_and_missing_columns() {
        let t = parse("# c\nx, X ,y\n1,2,3\n").unwrap();
        let e = t.column("X_").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:2: missing column 'X_'; expected the columns a, b (the header has: x, X, y)"
        );
        let t = parse("x,y, x\n1,2,3\n").unwrap();
        let e = t.column("x").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:1: the header names column 'x' twice (columns 1 and 3); expected each column \
             once"
        );
    }

    #[test]
    fn field_count_is_checked() {
        let e = parse("a,b,c\n1,2,3\n\n1,2\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:4: expected 3 fields as in the header on line 1, found 2"
        );
        let e = parse("a,b\n1,2,3\n").unwrap_err();
        assert_eq!(e.line(), Some(2));
        // Trailing empty fields beyond the header are tolerated.
        let t = parse("a,b\n1,2,,\n").unwrap();
        assert_eq!(t.rows[0].fields, vec!["1", "2"]);
        let e = parse("a,b\n1;2\n").unwrap_err();
        assert!(e
            .to_string()
            .ends_with("(the row looks separated by semicolons; use commas)"));
    }

    #[test]
    fn wrong_delimiters() {
        let e = parse("# data\na;b\n1;2\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:2: the header is separated by semicolons (;); expected comma-separated columns \
             a, b"
        );
        let e = parse("a\tb\n1\t2\n").unwrap_err();
        assert_eq!(e.line(), Some(1));
        assert!(e.to_string().contains("separated by tabs"));
    }

    #[test]
    fn empty_comment_only_and_header_only() {
        let e = parse("").unwrap_err();
        assert_eq!(e.line(), None);
        assert_eq!(
            e.to_string(),
            "t.csv: the file is empty; expected a header row with the columns a, b"
        );
        let e = parse("# only\n\n").unwrap_err();
        assert!(e.to_string().contains("only comments and blank lines"));
        let t = parse("\n# c\na,b\n\n").unwrap();
        let e = t.require_rows().unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(e.to_string().contains("header but no data rows"));
    }

    #[test]
    fn binary_and_non_utf8() {
        let e = CsvTable::parse("t.csv", b"a,b\n1,2\n\x00\x01\x02", EXPECTED).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(matches!(e, IoError::Encoding { .. }));
        assert!(e.to_string().contains("binary data (control byte 0x00"));
        let e = CsvTable::parse("t.csv", b"a,b\n1,2\n3,caf\xe9\n", EXPECTED).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert_eq!(
            e.to_string(),
            "t.csv:3: byte 0xe9 at byte offset 13 is not UTF-8; expected UTF-8 text"
        );
    }

    #[test]
    fn numbers() {
        assert_eq!(parse_number(" 1.5e-3 "), Ok(1.5e-3));
        assert_eq!(parse_number("-2"), Ok(-2.0));
        assert_eq!(
            parse_number("abc"),
            Err("expected a number, found 'abc'".to_string())
        );
        assert_eq!(
            parse_number(""),
            Err("expected a number, found an empty field".to_string())
        );
        assert_eq!(
            parse_number("NaN"),
            Err("expected a finite number, found a not-a-number value".to_string())
        );
        assert_eq!(
            parse_number("-inf"),
            Err("expected a finite number, found an infinite value '-inf'".to_string())
        );
        assert_eq!(
            parse_number("1e400"),
            Err(
                "expected a finite number, found '1e400', which is beyond the range of 64-bit \
                 floating point"
                    .to_string()
            )
        );
    }

    #[test]
    fn value_errors_name_line_and_column() {
        let t = parse("a,b\n\n1,x\n").unwrap();
        let col = t.column("b").unwrap();
        let e = t.number(&t.rows[0], &col).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:3: column 'b' (2): expected a number, found 'x'"
        );
        let t = parse("a,b\n ,1\n").unwrap();
        let col = t.column("a").unwrap();
        let e = t
            .identifier(&t.rows[0], &col, "an LED identifier")
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:2: column 'a' (1): expected an LED identifier, found an empty field"
        );
    }
}
