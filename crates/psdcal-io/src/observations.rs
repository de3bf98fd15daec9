//! observations.csv: measured impact points, one row per LED per image
//! (docs/formats.md).
//!
//! | column | meaning |
//! | --- | --- |
//! | `image` | image (template pose) identifier, text |
//! | `led` | LED identifier, must exist in the template |
//! | `x_mm`, `y_mm` | measured impact point on the PSD, mm, sensor frame |
//!
//! Reading checks each row on its own (non-empty identifiers, finite
//! numbers); checks against the template (unknown LEDs, duplicates, points
//! off the sensor) are [`crate::validate_data_set`]'s.

use crate::csv_table::{Col, CsvRow, CsvStream, CsvTable};
use crate::error::IoError;
use crate::limits::ReadLimits;

const EXPECTED_COLUMNS: &str = "image, led, x_mm, y_mm";

/// One measured impact point.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Image identifier.
    pub image: String,
    /// LED identifier.
    pub led: String,
    /// Measured impact point, mm, sensor frame.
    pub x_mm: f64,
    /// Measured impact point, mm, sensor frame.
    pub y_mm: f64,
    /// Physical line of the row, 1-based.
    pub line_no: usize,
}

/// The rows of an observations file (or of a signals file converted to
/// impact points).
#[derive(Debug, Clone, PartialEq)]
pub struct Observations {
    /// File name, for messages.
    pub source: String,
    /// The rows, in file order.
    pub rows: Vec<Observation>,
}

/// One row of observations.csv as read, before its identifiers are
/// copied: what [`crate::DataSetValidator`] checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObservationText<'a> {
    /// Image identifier.
    pub image: &'a str,
    /// LED identifier.
    pub led: &'a str,
    /// Measured impact point, mm, sensor frame.
    pub x_mm: f64,
    /// Measured impact point, mm, sensor frame.
    pub y_mm: f64,
    /// Physical line of the row, 1-based.
    pub line_no: usize,
}

impl Observations {
    csv_table_readers!(streamed "observations.csv");

    fn from_stream<R: std::io::BufRead>(stream: CsvStream<R>) -> Result<Self, IoError> {
        let columns = Columns::of(&stream.head)?;
        let (table, rows) = stream.map_rows(|table, row| {
            let row = columns.row(table, row)?;
            Ok(Observation {
                image: row.image.to_string(),
                led: row.led.to_string(),
                x_mm: row.x_mm,
                y_mm: row.y_mm,
                line_no: row.line_no,
            })
        })?;
        if rows.is_empty() {
            table.require_rows()?;
        }
        Ok(Self {
            source: table.source,
            rows,
        })
    }

    /// Reads observations.csv from `reader` row by row, handing each row to
    /// `each` as it is read and keeping none: memory stays constant
    /// whatever the file's size (within `limits`). Returns the number of
    /// rows.
    pub fn for_each_row(
        source: &str,
        reader: impl std::io::Read,
        limits: ReadLimits,
        mut each: impl FnMut(&ObservationText<'_>) -> Result<(), IoError>,
    ) -> Result<usize, IoError> {
        let mut stream = CsvStream::new(
            source,
            std::io::BufReader::new(reader),
            EXPECTED_COLUMNS,
            Some(limits.max_file_bytes),
        )?;
        let columns = Columns::of(&stream.head)?;
        let mut rows = 0;
        while let Some(row) = stream.next_row()? {
            each(&columns.row(&stream.head, &row)?)?;
            rows += 1;
        }
        if rows == 0 {
            stream.head.require_rows()?;
        }
        Ok(rows)
    }
}

/// The columns of observations.csv in a file's header.
struct Columns {
    image: Col,
    led: Col,
    x: Col,
    y: Col,
}

impl Columns {
    fn of(head: &CsvTable) -> Result<Self, IoError> {
        Ok(Self {
            image: head.column("image")?,
            led: head.column("led")?,
            x: head.column("x_mm")?,
            y: head.column("y_mm")?,
        })
    }

    /// One record's values, checked on their own.
    fn row<'r>(&self, table: &CsvTable, row: &'r CsvRow) -> Result<ObservationText<'r>, IoError> {
        Ok(ObservationText {
            image: table.identifier_text(row, &self.image, "an image identifier")?,
            led: table.identifier_text(row, &self.led, "an LED identifier")?,
            x_mm: table.number(row, &self.x)?,
            y_mm: table.number(row, &self.y)?,
            line_no: row.line,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(image: &str, led: &str, x_mm: f64, y_mm: f64, line_no: usize) -> Observation {
        Observation {
            image: image.into(),
            led: led.into(),
            x_mm,
            y_mm,
            line_no,
        }
    }

    #[test]
    fn reads_comments_blank_lines_reordered_and_extra_columns() {
        let text = "\
# exported by the rig
y_mm,quality,led,image,x_mm

-0.5,good,3,A,1.25
# second image
2e-1,bad, 4 ,B,-3
";
        let o = Observations::from_str("observations.csv", text).unwrap();
        assert_eq!(o.source, "observations.csv");
        assert_eq!(
            o.rows,
            vec![obs("A", "3", 1.25, -0.5, 4), obs("B", "4", -3.0, 0.2, 6)]
        );
    }

    #[test]
    fn reads_crlf_and_bom() {
        let text = "\u{feff}image,led,x_mm,y_mm\r\n1,1,0.5,0.25\r\n\r\n1,2,-1,1\r\n";
        let o = Observations::from_str("o.csv", text).unwrap();
        assert_eq!(
            o.rows,
            vec![obs("1", "1", 0.5, 0.25, 2), obs("1", "2", -1.0, 1.0, 4)]
        );
        let r = Observations::from_reader("o.csv", text.as_bytes()).unwrap();
        assert_eq!(r, o);
    }

    #[test]
    fn reads_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("observations.csv");
        std::fs::write(&path, "image,led,x_mm,y_mm\n1,1,0,0\n").unwrap();
        let o = Observations::read(&path).unwrap();
        assert_eq!(o.rows, vec![obs("1", "1", 0.0, 0.0, 2)]);
    }

    #[test]
    fn bad_values_name_file_line_and_column() {
        let text = "image,led,x_mm,y_mm\n1,1,0,0\n\n1,2,abc,0\n";
        let e = Observations::from_str("observations.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations.csv:4: column 'x_mm' (3): expected a number, found 'abc'"
        );
        let text = "image,led,x_mm,y_mm\n1,1,0,NaN\n";
        let e = Observations::from_str("observations.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations.csv:2: column 'y_mm' (4): expected a finite number, found a \
             not-a-number value"
        );
        let text = "image,led,x_mm,y_mm\n,1,0,0\n";
        let e = Observations::from_str("observations.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations.csv:2: column 'image' (1): expected an image identifier, found an \
             empty field"
        );
    }

    #[test]
    fn missing_column_is_reported_on_the_header_line() {
        let text = "# c\n# c\nimage,led,x_mm\n1,1,0\n";
        let e = Observations::from_str("observations.csv", text).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(e.to_string().contains("missing column 'y_mm'"), "{e}");
    }
}
