//! The inputs of a network calibration (docs/formats.md, "Network
//! calibration"):
//!
//! | file | columns |
//! | --- | --- |
//! | sensors.csv | `sensor`, `calibration` (a lab calibration.json, relative to this file's folder) |
//! | wand.csv, frame.csv | `led`, `X_mm`, `Y_mm`, `Z_mm` (the wand's frame; the world for the static frame) |
//! | network_points.csv | `frame`, `sensor`, `led`, `x_mm`, `y_mm` (or `vx1`, `vx2`, `vy1`, `vy2`) |
//!
//! Identifiers are text; duplicates (a sensor or LED listed twice, one
//! sensor seeing one LED twice in one frame) are errors naming the line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::points::PointInput;

/// One row of sensors.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkSensorRow {
    /// Physical line.
    pub line_no: usize,
    /// Sensor identifier.
    pub sensor: String,
    /// The calibration path as written.
    pub calibration: String,
    /// Resolved against the file's folder.
    pub calibration_path: PathBuf,
}

/// sensors.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkSensors {
    /// File name, for messages.
    pub source: String,
    /// The rows.
    pub rows: Vec<NetworkSensorRow>,
}

impl NetworkSensors {
    /// Reads sensors.csv; calibration paths are resolved against its folder.
    pub fn read_with(path: &Path, limits: ReadLimits) -> Result<Self, IoError> {
        let table = CsvTable::read_path(path, "sensor, calibration", limits)?;
        let base = path.parent().unwrap_or_else(|| Path::new(""));
        let sensor = table.column("sensor")?;
        let calibration = table.column("calibration")?;
        table.require_rows()?;
        let mut rows: Vec<NetworkSensorRow> = Vec::new();
        let mut first: HashMap<String, usize> = HashMap::new();
        for row in &table.rows {
            let id = table.identifier(row, &sensor, "a sensor identifier")?;
            let file = table.identifier(row, &calibration, "a calibration.json path")?;
            if let Some(&first_line) = first.get(&id) {
                return Err(IoError::Duplicate {
                    at: table.at(row.line),
                    first_line,
                    what: format!("sensor '{id}'"),
                });
            }
            first.insert(id.clone(), row.line);
            rows.push(NetworkSensorRow {
                line_no: row.line,
                sensor: id,
                calibration_path: base.join(&file),
                calibration: file,
            });
        }
        Ok(Self {
            source: table.source,
            rows,
        })
    }
}

/// LEDs at 3-D positions: wand.csv or frame.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct LedPositions {
    /// File name, for messages.
    pub source: String,
    /// Names, in file order.
    pub names: Vec<String>,
    /// Positions, mm.
    pub positions: Vec<Vector3<f64>>,
}

impl LedPositions {
    /// Reads wand.csv or frame.csv.
    pub fn read_with(path: &Path, limits: ReadLimits) -> Result<Self, IoError> {
        let table = CsvTable::read_path(path, "led, X_mm, Y_mm, Z_mm", limits)?;
        let led = table.column("led")?;
        let cols = [
            table.column("X_mm")?,
            table.column("Y_mm")?,
            table.column("Z_mm")?,
        ];
        table.require_rows()?;
        let (mut names, mut positions) = (Vec::new(), Vec::new());
        let mut first: HashMap<String, usize> = HashMap::new();
        for row in &table.rows {
            let id = table.identifier(row, &led, "an LED identifier")?;
            if let Some(&first_line) = first.get(&id) {
                return Err(IoError::Duplicate {
                    at: table.at(row.line),
                    first_line,
                    what: format!("LED '{id}'"),
                });
            }
            first.insert(id.clone(), row.line);
            names.push(id);
            positions.push(Vector3::new(
                table.number(row, &cols[0])?,
                table.number(row, &cols[1])?,
                table.number(row, &cols[2])?,
            ));
        }
        Ok(Self {
            source: table.source,
            names,
            positions,
        })
    }
}

/// One row of network_points.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkPointRow {
    /// Physical line.
    pub line_no: usize,
    /// Frame (instant) identifier.
    pub frame: String,
    /// Sensor identifier.
    pub sensor: String,
    /// LED identifier (a wand's or the static frame's).
    pub led: String,
    /// The measured point or amplitudes.
    pub input: PointInput,
}

/// network_points.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkPoints {
    /// File name, for messages.
    pub source: String,
    /// The rows, in file order.
    pub rows: Vec<NetworkPointRow>,
}

impl NetworkPoints {
    /// Reads network_points.csv.
    pub fn read_with(path: &Path, limits: ReadLimits) -> Result<Self, IoError> {
        let table = CsvTable::read_path(
            path,
            "frame, sensor, led, x_mm, y_mm (or vx1, vx2, vy1, vy2)",
            limits,
        )?;
        let frame = table.column("frame")?;
        let sensor = table.column("sensor")?;
        let led = table.column("led")?;
        let x = table.find_column("x_mm")?;
        let y = table.find_column("y_mm")?;
        let amplitudes = (x.is_none() || y.is_none()) && table.find_column("vx1")?.is_some();
        let amp_cols = if amplitudes {
            Some([
                table.column("vx1")?,
                table.column("vx2")?,
                table.column("vy1")?,
                table.column("vy2")?,
            ])
        } else {
            None
        };
        let xy = if amplitudes {
            None
        } else {
            Some((
                x.ok_or_else(|| table.missing_column("x_mm"))?,
                y.ok_or_else(|| table.missing_column("y_mm"))?,
            ))
        };
        table.require_rows()?;
        let mut rows = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            let input = match (&amp_cols, &xy) {
                (Some(c), _) => PointInput::Amplitudes(psdcal_model::Amplitudes {
                    vx1: table.number(row, &c[0])?,
                    vx2: table.number(row, &c[1])?,
                    vy1: table.number(row, &c[2])?,
                    vy2: table.number(row, &c[3])?,
                }),
                (None, Some((x, y))) => PointInput::Position(nalgebra::Vector2::new(
                    table.number(row, x)?,
                    table.number(row, y)?,
                )),
                (None, None) => unreachable!("x_mm, y_mm or the amplitudes are required above"),
            };
            rows.push(NetworkPointRow {
                line_no: row.line,
                frame: table.identifier(row, &frame, "a frame identifier")?,
                sensor: table.identifier(row, &sensor, "a sensor identifier")?,
                led: table.identifier(row, &led, "an LED identifier")?,
                input,
            });
        }
        Ok(Self {
            source: table.source,
            rows,
        })
    }
}
