//! poses.csv: template poses, planned (`psdcal plan`) or to simulate
//! (`psdcal simulate --poses`). Columns `image` (identifier), `rx`, `ry`,
//! `rz` (Rodrigues vector of `sensor_from_template`, rad), `tx_mm`,
//! `ty_mm`, `tz_mm` (its translation, mm); `#` comments. Errors name the
//! file and line: a missing column, a value that is not a finite number,
//! an image twice, a template behind the sensor (`tz_mm ≤ 0`).

use std::io::Write;
use std::path::Path;

use crate::atomic::write_atomic;
use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::location::Location;

const COLUMNS: &str = "image, rx, ry, rz, tx_mm, ty_mm, tz_mm";

/// One pose.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseRow {
    /// Physical line, 1-based (0 for rows built in memory).
    pub line_no: usize,
    /// Image identifier.
    pub image: String,
    /// Rodrigues vector of `sensor_from_template`, rad.
    pub rvec: [f64; 3],
    /// Translation of `sensor_from_template`, mm.
    pub t_mm: [f64; 3],
}

/// poses.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct Poses {
    /// File name, for messages.
    pub source: String,
    /// The rows, in file order.
    pub rows: Vec<PoseRow>,
}

impl Poses {
    /// Reads poses.csv.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        let table = CsvTable::read_path(path.as_ref(), COLUMNS, limits)?;
        table.require_rows()?;
        let image = table.column("image")?;
        let cols = ["rx", "ry", "rz", "tx_mm", "ty_mm", "tz_mm"]
            .map(|name| table.column(name))
            .into_iter()
            .collect::<Result<Vec<_>, _>>()?;
        let mut rows: Vec<PoseRow> = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            let id = table.identifier(row, &image, "image")?;
            if let Some(first) = rows.iter().find(|r| r.image == id) {
                return Err(IoError::Duplicate {
                    at: table.at(row.line),
                    first_line: first.line_no,
                    what: format!("image '{id}'"),
                });
            }
            let mut v = [0.0; 6];
            for (x, c) in v.iter_mut().zip(&cols) {
                *x = table.number(row, c)?;
            }
            if v[5] <= 0.0 {
                return Err(IoError::Invalid {
                    at: table.at(row.line),
                    message: format!(
                        "image '{id}': tz_mm = {} puts the template behind the sensor; \
                         the translation is the template's origin in the sensor frame (z forward)",
                        v[5]
                    ),
                });
            }
            rows.push(PoseRow {
                line_no: row.line,
                image: id,
                rvec: [v[0], v[1], v[2]],
                t_mm: [v[3], v[4], v[5]],
            });
        }
        Ok(Self {
            source: table.source.clone(),
            rows,
        })
    }

    /// A location on a line of this file.
    pub fn at(&self, line: usize) -> Location {
        Location::line(&self.source, line)
    }
}

/// Writes poses.csv atomically, with a leading comment.
pub fn write_poses(path: impl AsRef<Path>, comment: &str, rows: &[PoseRow]) -> Result<(), IoError> {
    write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        writeln!(w, "image,rx,ry,rz,tx_mm,ty_mm,tz_mm")?;
        for r in rows {
            writeln!(
                w,
                "{},{},{},{},{},{},{}",
                r.image, r.rvec[0], r.rvec[1], r.rvec[2], r.t_mm[0], r.t_mm[1], r.t_mm[2]
            )?;
        }
        Ok(())
    })
}
