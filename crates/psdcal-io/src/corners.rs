//! The corners of `psdcal focal-check` (docs/formats.md, "corners.csv"): the
//! measured impact points of the four corners of a square in the scene, in
//! order around it. Columns `corner` (identifier), `x_mm`, `y_mm` (measured
//! point on the sensor, mm) and optionally `sigma_mm` (the standard
//! deviation of each coordinate of that point, mm); `#` comments. Exactly
//! four rows; errors name the file and line.

use std::path::Path;

use nalgebra::Vector2;

use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::location::Location;

const COLUMNS: &str = "corner, x_mm, y_mm (optional sigma_mm)";

/// One measured corner.
#[derive(Debug, Clone, PartialEq)]
pub struct Corner {
    /// Physical line, 1-based.
    pub line_no: usize,
    /// Identifier.
    pub id: String,
    /// Measured point, mm.
    pub measured: Vector2<f64>,
    /// Standard deviation of each coordinate, mm, when given.
    pub sigma_mm: Option<f64>,
}

/// The four corners, in order around the square.
#[derive(Debug, Clone, PartialEq)]
pub struct Corners {
    /// File name, for messages.
    pub source: String,
    /// The corners.
    pub corners: Vec<Corner>,
}

impl Corners {
    /// Reads the corners file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        let table = CsvTable::read_path(path.as_ref(), COLUMNS, limits)?;
        table.require_rows()?;
        let (id, x, y) = (
            table.column("corner")?,
            table.column("x_mm")?,
            table.column("y_mm")?,
        );
        let sigma = table.find_column("sigma_mm")?;
        let mut corners: Vec<Corner> = Vec::with_capacity(4);
        for row in &table.rows {
            let name = table.identifier(row, &id, "corner")?;
            if let Some(first) = corners.iter().find(|c| c.id == name) {
                return Err(IoError::Duplicate {
                    at: table.at(row.line),
                    first_line: first.line_no,
                    what: format!("corner '{name}'"),
                });
            }
            let sigma_mm = match &sigma {
                Some(c) => {
                    let s = table.number(row, c)?;
                    if s < 0.0 {
                        return Err(IoError::Invalid {
                            at: table.at(row.line),
                            message: format!("sigma_mm = {s} is negative; give the standard deviation (≥ 0) in mm"),
                        });
                    }
                    Some(s)
                }
                None => None,
            };
            corners.push(Corner {
                line_no: row.line,
                id: name,
                measured: Vector2::new(table.number(row, &x)?, table.number(row, &y)?),
                sigma_mm,
            });
        }
        if corners.len() != 4 {
            return Err(IoError::Invalid {
                at: Location::file(&table.source),
                message: format!(
                    "{} corner(s); give the four corners of the square, in order around it",
                    corners.len()
                ),
            });
        }
        Ok(Self {
            source: table.source.clone(),
            corners,
        })
    }
}
