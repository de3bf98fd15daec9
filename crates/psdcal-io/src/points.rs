//! points.csv: measured points to convert (docs/formats.md).
//!
//! | column | meaning |
//! | --- | --- |
//! | `x_mm`, `y_mm` | measured impact points, mm, sensor frame |
//!
//! or, instead, the four electrode amplitudes `vx1`, `vx2`, `vy1`, `vy2`
//! (when the file has both `x_mm` and `y_mm`, they are used). Every other column is
//! kept: the reader stores the header and every field's text exactly as
//! written so that the answer can repeat them in their original order, then
//! append its own columns ([`Points::write_csv`]).

use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Write};
use std::path::Path;

use nalgebra::Vector2;
use psdcal_model::{Amplitudes, ChannelGains, PsdGeometry};

use crate::csv_table::{parse_number, Col, CsvRow, CsvStream, CsvTable};
use crate::error::{ColumnRef, IoError};
use crate::limits::ReadLimits;
use crate::location::Location;
use crate::number_text::number_text;
use crate::signals::impact_point_at;

const EXPECTED_COLUMNS: &str = "x_mm, y_mm (or vx1, vx2, vy1, vy2)";

/// What a row gives: a measured point, the amplitudes to compute it from,
/// or a cell without a finite number (the row gets the status
/// `non_finite_input`, the batch goes on).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum PointInput {
    /// A measured impact point, mm.
    Position(Vector2<f64>),
    /// Electrode amplitudes (docs/model.md §1).
    Amplitudes(Amplitudes),
    /// A needed cell is empty, NaN, infinite or beyond the `f64` range.
    NonFinite {
        /// The first such column.
        column: ColumnRef,
        /// What it holds (e.g. `an empty field`).
        message: String,
    },
}

/// One row of points.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct PointRow {
    /// Physical line of the row, 1-based.
    pub line_no: usize,
    /// Every field's text as written, one per header column.
    pub fields: Vec<String>,
    /// The parsed input.
    pub input: PointInput,
}

/// A points file.
#[derive(Debug, Clone, PartialEq)]
pub struct Points {
    /// File name, for messages.
    pub source: String,
    /// Header fields as written.
    pub header: Vec<String>,
    /// Physical line of the header, 1-based.
    pub header_line: usize,
    /// Whether the rows give amplitudes rather than positions.
    pub amplitudes: bool,
    /// The rows, in file order.
    pub rows: Vec<PointRow>,
}

/// A column to append when writing points back.
#[derive(Debug, Clone, Copy)]
pub struct AddedColumn<'a> {
    /// Header name.
    pub name: &'a str,
    /// One value per row (`None`: the row has no answer, the field is
    /// written empty).
    pub values: &'a [Option<f64>],
}

impl Points {
    /// Reads points.csv from a file (whole, within the size limit).
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        Self::collect(PointStream::from_table(CsvTable::read_path(
            path.as_ref(),
            EXPECTED_COLUMNS,
            limits,
        )?)?)
    }

    /// Reads points.csv from a reader; `source` names it in messages.
    pub fn from_reader(source: &str, reader: impl Read) -> Result<Self, IoError> {
        Self::from_reader_with(source, reader, ReadLimits::default())
    }

    /// [`Self::from_reader`] within `limits` (docs/formats.md, "Limits").
    pub fn from_reader_with(
        source: &str,
        reader: impl Read,
        limits: ReadLimits,
    ) -> Result<Self, IoError> {
        Self::collect(PointStream::from_table(CsvTable::from_reader(
            source,
            reader,
            EXPECTED_COLUMNS,
            limits,
        )?)?)
    }

    /// Parses points.csv text; `source` names it in messages.
    pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
        Self::collect(PointStream::from_table(CsvTable::parse(
            source,
            text.as_bytes(),
            EXPECTED_COLUMNS,
        )?)?)
    }

    fn collect<R: BufRead>(mut stream: PointStream<R>) -> Result<Self, IoError> {
        let mut rows = Vec::new();
        while let Some(row) = stream.next_row()? {
            rows.push(row);
        }
        if rows.is_empty() {
            stream.head.require_rows()?;
        }
        Ok(Self {
            source: stream.head.source.clone(),
            header: stream.head.header.clone(),
            header_line: stream.head.header_line,
            amplitudes: stream.amplitudes,
            rows,
        })
    }

    /// Whether the header has a column called `name` (ignoring surrounding
    /// blanks and ASCII case, as column lookup does).
    pub fn has_column(&self, name: &str) -> bool {
        self.header
            .iter()
            .any(|h| h.trim().eq_ignore_ascii_case(name))
    }

    /// The measured point of every row; amplitudes are converted with
    /// docs/model.md §1 after dividing out `gains` ([`ChannelGains::UNIT`] for
    /// none). A row whose amplitudes sum to zero or less is an error naming
    /// its line.
    pub fn measured(
        &self,
        geometry: &PsdGeometry,
        gains: &ChannelGains,
    ) -> Result<Vec<Vector2<f64>>, IoError> {
        self.rows
            .iter()
            .map(|row| match &row.input {
                PointInput::Position(p) => Ok(*p),
                PointInput::Amplitudes(a) => impact_point_at(geometry, a, gains, || {
                    Location::line(&self.source, row.line_no)
                }),
                PointInput::NonFinite { column, message } => Err(IoError::Value {
                    at: Location::line(&self.source, row.line_no),
                    column: column.clone(),
                    message: message.clone(),
                }),
            })
            .collect()
    }

    /// Writes the table back as CSV: every input column in its original
    /// order and text, then the `added` columns, numbers in Rust's shortest
    /// round-trip form, a missing value as an empty field. Fails (before
    /// writing anything) if an added column does not have one value per row
    /// or a value is not finite.
    pub fn write_csv<W: Write>(&self, out: W, added: &[AddedColumn<'_>]) -> io::Result<()> {
        for column in added {
            if column.values.len() != self.rows.len() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "column '{}' has {} values for {} rows",
                        column.name,
                        column.values.len(),
                        self.rows.len()
                    ),
                ));
            }
            if let Some(row) = column
                .values
                .iter()
                .position(|v| v.is_some_and(|v| !v.is_finite()))
            {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "column '{}' holds a non-finite value in row {}",
                        column.name,
                        row + 1
                    ),
                ));
            }
        }
        let mut writer = csv::WriterBuilder::new().flexible(true).from_writer(out);
        let names = self.header.iter().map(String::as_str);
        writer.write_record(names.chain(added.iter().map(|c| c.name)))?;
        for (i, row) in self.rows.iter().enumerate() {
            let values: Vec<String> = added
                .iter()
                .map(|c| {
                    c.values
                        .get(i)
                        .copied()
                        .flatten()
                        .map_or_else(String::new, number_text)
                })
                .collect();
            let fields = row.fields.iter().map(String::as_str);
            writer.write_record(fields.chain(values.iter().map(String::as_str)))?;
        }
        writer.flush()
    }
}

/// points.csv read row by row in constant memory (no size limit): what
/// `correct`, `aoa` and `locate` on a plane stream through.
pub struct PointStream<R> {
    head: CsvTable,
    rows: Option<CsvStream<R>>,
    next: usize,
    columns: Vec<Col>,
    /// Whether the rows give amplitudes rather than positions.
    pub amplitudes: bool,
}

impl PointStream<BufReader<File>> {
    /// Opens points.csv and reads its header.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, IoError> {
        let stream = CsvStream::open(path.as_ref(), EXPECTED_COLUMNS, None)?;
        let head = stream.head.clone();
        Self::with(head, Some(stream))
    }
}

impl PointStream<&'static [u8]> {
    /// The rows of a table already read.
    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        Self::with(table, None)
    }
}

impl<R: BufRead> PointStream<R> {
    fn with(head: CsvTable, rows: Option<CsvStream<R>>) -> Result<Self, IoError> {
        let (columns, amplitudes) = point_columns(&head)?;
        Ok(Self {
            head,
            rows,
            next: 0,
            columns,
            amplitudes,
        })
    }

    /// File name, for messages.
    pub fn source(&self) -> &str {
        &self.head.source
    }

    /// Header fields as written.
    pub fn header(&self) -> &[String] {
        &self.head.header
    }

    /// Physical line of the header, 1-based.
    pub fn header_line(&self) -> usize {
        self.head.header_line
    }

    /// Whether the header has a column called `name` (ignoring surrounding
    /// blanks and ASCII case, as column lookup does).
    pub fn has_column(&self, name: &str) -> bool {
        self.head
            .header
            .iter()
            .any(|h| h.trim().eq_ignore_ascii_case(name))
    }

    /// The next row, or `None` at the end. A cell that is not a number is
    /// an error; an empty or non-finite one gives [`PointInput::NonFinite`].
    pub fn next_row(&mut self) -> Result<Option<PointRow>, IoError> {
        let row = match &mut self.rows {
            Some(stream) => stream.next_row()?,
            None => {
                let row = self.head.rows.get(self.next).cloned();
                self.next += 1;
                row
            }
        };
        let Some(row) = row else {
            return Ok(None);
        };
        let input = self.input(&row)?;
        Ok(Some(PointRow {
            line_no: row.line,
            fields: row.fields,
            input,
        }))
    }

    fn input(&self, row: &CsvRow) -> Result<PointInput, IoError> {
        point_input(&self.head, row, &self.columns, self.amplitudes)
    }
}

/// The columns of a row's point: `x_mm, y_mm`, or, when either is missing
/// and `vx1` is there, `vx1, vx2, vy1, vy2` (then `true`, amplitudes).
pub(crate) fn point_columns(head: &CsvTable) -> Result<(Vec<Col>, bool), IoError> {
    let x = head.find_column("x_mm")?;
    let y = head.find_column("y_mm")?;
    let amplitudes = (x.is_none() || y.is_none()) && head.find_column("vx1")?.is_some();
    let columns = if amplitudes {
        vec![
            head.column("vx1")?,
            head.column("vx2")?,
            head.column("vy1")?,
            head.column("vy2")?,
        ]
    } else {
        vec![
            x.ok_or_else(|| head.missing_column("x_mm"))?,
            y.ok_or_else(|| head.missing_column("y_mm"))?,
        ]
    };
    Ok((columns, amplitudes))
}

/// Whether a cell that is not a finite number is empty or a number that is
/// not finite (NaN, an infinity, beyond the `f64` range), rather than text.
/// The point or amplitudes of a row from its `columns` (`x_mm, y_mm`, or
/// `vx1 … vy2` with `amplitudes`): a field that is not a number is an error;
/// an empty or non-finite one gives [`PointInput::NonFinite`] (the row is
/// answered with a status, the others go on).
pub(crate) fn point_input(
    head: &CsvTable,
    row: &CsvRow,
    columns: &[Col],
    amplitudes: bool,
) -> Result<PointInput, IoError> {
    let mut values = [0.0; 4];
    for (k, col) in columns.iter().enumerate() {
        let text = head.text(row, col);
        match parse_number(text) {
            Ok(v) => values[k] = v,
            Err(message) if is_non_finite(text) => {
                return Ok(PointInput::NonFinite {
                    column: col.to_ref(),
                    message,
                })
            }
            Err(message) => {
                return Err(IoError::Value {
                    at: head.at(row.line),
                    column: col.to_ref(),
                    message,
                })
            }
        }
    }
    Ok(if amplitudes {
        PointInput::Amplitudes(Amplitudes {
            vx1: values[0],
            vx2: values[1],
            vy1: values[2],
            vy2: values[3],
        })
    } else {
        PointInput::Position(Vector2::new(values[0], values[1]))
    })
}

fn is_non_finite(text: &str) -> bool {
    let text = text.trim();
    text.is_empty() || text.parse::<f64>().is_ok()
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;
    use psdcal_model::psd::electrode_currents;

    use super::*;

    #[test]
    fn reads_positions_keeping_every_field() {
        let text =
            "\u{feff}# points\r\nid, note ,y_mm,x_mm\r\n\r\n7,\"a, b\",-1.5, 2e-1 \r\n8,,0,0\r\n";
        let p = Points::from_str("points.csv", text).unwrap();
        assert!(!p.amplitudes);
        assert_eq!(p.header, vec!["id", " note ", "y_mm", "x_mm"]);
        assert_eq!(p.rows.len(), 2);
        assert_eq!(p.rows[0].line_no, 4);
        assert_eq!(p.rows[0].fields, vec!["7", "a, b", "-1.5", " 2e-1 "]);
        assert_eq!(
            p.rows[0].input,
            PointInput::Position(Vector2::new(0.2, -1.5))
        );
        assert_eq!(p.rows[1].line_no, 5);
        assert!(p.has_column("NOTE"));
        assert!(!p.has_column("x_ideal_mm"));
        assert_eq!(
            Points::from_reader("points.csv", text.as_bytes()).unwrap(),
            p
        );
    }

    #[test]
    fn reads_amplitudes_and_converts_them() {
        let geometry = PsdGeometry::default();
        let gains = ChannelGains {
            x2: 1.02,
            y1: 0.97,
            y2: 1.01,
        };
        let a = electrode_currents(&geometry, &Vector2::new(-3.0, 0.75), 1.0).apply_gains(&gains);
        let text = format!(
            "vx1,vx2,vy1,vy2,tag\n{},{},{},{},t\n",
            a.vx1, a.vx2, a.vy1, a.vy2
        );
        let p = Points::from_str("points.csv", &text).unwrap();
        assert!(p.amplitudes);
        let m = p.measured(&geometry, &gains).unwrap();
        assert_relative_eq!(m[0].x, -3.0, epsilon = 1e-12);
        assert_relative_eq!(m[0].y, 0.75, epsilon = 1e-12);
    }

    #[test]
    fn positions_win_over_amplitudes() {
        let p = Points::from_str("p.csv", "vx1,x_mm,y_mm\n0,1,2\n").unwrap();
        assert!(!p.amplitudes);
        assert_eq!(
            p.rows[0].input,
            PointInput::Position(Vector2::new(1.0, 2.0))
        );
    }

    #[test]
    fn missing_and_bad_columns() {
        let e = Points::from_str("points.csv", "id,x_mm\n1,2\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "points.csv:1: missing column 'y_mm'; expected the columns x_mm, y_mm (or vx1, vx2, \
             vy1, vy2) (the header has: id, x_mm)"
        );
        let e = Points::from_str("points.csv", "id\n1\n").unwrap_err();
        assert!(e.to_string().contains("missing column 'x_mm'"), "{e}");
        let e = Points::from_str("points.csv", "vx1,vx2,vy1\n1,2,3\n").unwrap_err();
        assert!(e.to_string().contains("missing column 'vy2'"), "{e}");
        let e = Points::from_str("points.csv", "x_mm,y_mm\n1,2\n1,abc\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "points.csv:3: column 'y_mm' (2): expected a number, found 'abc'"
        );
        // Empty and non-finite cells are rows of their own, not errors.
        let p = Points::from_str("points.csv", "x_mm,y_mm\n1,\nnan,2\n1e999,0\n3,4\n").unwrap();
        assert_eq!(p.rows.len(), 4);
        for (row, column) in p.rows[..3].iter().zip(["y_mm", "x_mm", "x_mm"]) {
            assert!(
                matches!(&row.input, PointInput::NonFinite { column: c, .. } if c.name == column),
                "{row:?}"
            );
        }
        assert_eq!(
            p.rows[3].input,
            PointInput::Position(Vector2::new(3.0, 4.0))
        );
    }

    #[test]
    fn zero_total_amplitudes_error_on_their_line() {
        let p = Points::from_str("points.csv", "vx1,vx2,vy1,vy2\n1,1,1,1\n0,0,0,0\n").unwrap();
        let e = p
            .measured(&PsdGeometry::default(), &ChannelGains::UNIT)
            .unwrap_err();
        assert_eq!(e.line(), Some(3));
    }

    #[test]
    fn writes_original_text_then_added_columns() {
        let text = "id, note ,y_mm,x_mm\n7,\"a, b\",-1.5, 2e-1 \n8,,0,0\n";
        let p = Points::from_str("points.csv", text).unwrap();
        let mut out = Vec::new();
        p.write_csv(
            &mut out,
            &[
                AddedColumn {
                    name: "x_ideal_mm",
                    values: &[Some(0.1), Some(-2.0)],
                },
                AddedColumn {
                    name: "y_ideal_mm",
                    values: &[Some(1.0 / 3.0), None],
                },
            ],
        )
        .unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "id, note ,y_mm,x_mm,x_ideal_mm,y_ideal_mm\n\
             7,\"a, b\",-1.5, 2e-1 ,0.1,0.3333333333333333\n\
             8,,0,0,-2,\n"
        );
    }

    #[test]
    fn write_refuses_wrong_lengths_and_non_finite_values() {
        let p = Points::from_str("points.csv", "x_mm,y_mm\n1,2\n").unwrap();
        let mut out = Vec::new();
        let e = p
            .write_csv(
                &mut out,
                &[AddedColumn {
                    name: "a",
                    values: &[],
                }],
            )
            .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        let e = p
            .write_csv(
                &mut out,
                &[AddedColumn {
                    name: "a",
                    values: &[Some(f64::NAN)],
                }],
            )
            .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(out.is_empty());
    }
}
