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

use crate::csv_table::{CsvStream, CsvTable};
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::points::{point_columns, point_input, PointInput};

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

/// network_points.csv's columns, for messages.
const EXPECTED_COLUMNS: &str = "frame, sensor, led, x_mm, y_mm (or vx1, vx2, vy1, vy2)";

impl NetworkPoints {
    csv_table_readers!(streamed "network_points.csv");

    /// Each record converted as it is read (a long wave's file is never
    /// held as text).
    fn from_stream<R: std::io::BufRead>(stream: CsvStream<R>) -> Result<Self, IoError> {
        let head = &stream.head;
        let frame = head.column("frame")?;
        let sensor = head.column("sensor")?;
        let led = head.column("led")?;
        let (columns, amplitudes) = point_columns(head)?;
        let (table, rows) = stream.map_rows(|table, row| {
            Ok(NetworkPointRow {
                line_no: row.line,
                frame: table.identifier(row, &frame, "a frame identifier")?,
                sensor: table.identifier(row, &sensor, "a sensor identifier")?,
                led: table.identifier(row, &led, "an LED identifier")?,
                // An empty or non-finite cell: the network's reader names
                // the line.
                input: point_input(table, row, &columns, amplitudes)?,
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_are_read_as_they_stream_with_non_finite_cells_kept_as_such() {
        let text = "frame,sensor,led,x_mm,y_mm\n0,s1,w1,0.5,-1\n0,s2,w1,,2\n";
        let p = NetworkPoints::from_str("network_points.csv", text).unwrap();
        assert_eq!(p.rows.len(), 2);
        assert_eq!(
            (p.rows[0].frame.as_str(), p.rows[0].sensor.as_str()),
            ("0", "s1")
        );
        assert_eq!(
            p.rows[0].input,
            PointInput::Position(nalgebra::Vector2::new(0.5, -1.0))
        );
        assert!(matches!(p.rows[1].input, PointInput::NonFinite { .. }));
        let e = NetworkPoints::from_str("p.csv", "frame,sensor,led,x_mm,y_mm\n0,s1,w1,abc,1\n");
        assert!(e.unwrap_err().to_string().starts_with("p.csv:2:"));
        let amps = "frame,sensor,led,vx1,vx2,vy1,vy2\n0,s1,w1,1,2,3,4\n";
        let p = NetworkPoints::from_str("a.csv", amps).unwrap();
        assert!(matches!(p.rows[0].input, PointInput::Amplitudes(_)));
        assert!(NetworkPoints::from_str("e.csv", "frame,sensor,led,x_mm,y_mm\n").is_err());
    }
}
