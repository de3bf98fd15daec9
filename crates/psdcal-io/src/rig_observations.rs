//! rig_points.csv: what the sensors of a rig measured, one row per sensor
//! per emitter (docs/positioning.md, "Rig files").
//!
//! | column | meaning |
//! | --- | --- |
//! | `emitter` | emitter (or observation) identifier, text: the rows of one emitter are intersected |
//! | `sensor` | sensor identifier, as in the rig file |
//! | `x_mm`, `y_mm` | measured impact point on that sensor, mm, sensor frame |
//!
//! or, instead of `x_mm`, `y_mm`, the four electrode amplitudes `vx1`,
//! `vx2`, `vy1`, `vy2` (converted with each sensor's calibration: its sensor
//! size and channel gains). Other columns are ignored. [`RigObservations::check_against`]
//! refuses sensors the rig does not have and a sensor seen twice for one
//! emitter, naming the line.

use std::collections::HashMap;

use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::points::{point_columns, point_input, PointInput};
use crate::rig::RigFile;

const EXPECTED_COLUMNS: &str = "emitter, sensor, x_mm, y_mm (or vx1, vx2, vy1, vy2)";

/// One measurement of one emitter by one sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct RigObservation {
    /// Physical line, 1-based.
    pub line_no: usize,
    /// Emitter identifier.
    pub emitter: String,
    /// Sensor identifier.
    pub sensor: String,
    /// The measured point or amplitudes.
    pub input: PointInput,
}

/// The rows of a rig observations file.
#[derive(Debug, Clone, PartialEq)]
pub struct RigObservations {
    /// File name, for messages.
    pub source: String,
    /// Whether the rows give amplitudes rather than points.
    pub amplitudes: bool,
    /// The rows, in file order.
    pub rows: Vec<RigObservation>,
}

impl RigObservations {
    csv_table_readers!("rig_points.csv");

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        let emitter = table.column("emitter")?;
        let sensor = table.column("sensor")?;
        let (columns, amplitudes) = point_columns(&table)?;
        table.require_rows()?;
        let mut rows = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            rows.push(RigObservation {
                line_no: row.line,
                emitter: table.identifier(row, &emitter, "an emitter identifier")?,
                sensor: table.identifier(row, &sensor, "a sensor identifier")?,
                // An empty or non-finite cell: that row's emitter is answered
                // with a status naming the line, the others go on.
                input: point_input(&table, row, &columns, amplitudes)?,
            });
        }
        Ok(Self {
            source: table.source,
            amplitudes,
            rows,
        })
    }

    /// Checks that every sensor is in `rig` and that no emitter is seen
    /// twice by one sensor; errors name the line.
    pub fn check_against(&self, rig: &RigFile) -> Result<(), IoError> {
        let index = rig.index();
        let mut first: HashMap<(&str, &str), usize> = HashMap::with_capacity(self.rows.len());
        for row in &self.rows {
            if !index.contains_key(row.sensor.as_str()) {
                return Err(IoError::Invalid {
                    at: crate::Location::line(&self.source, row.line_no),
                    message: format!(
                        "sensor '{}' is not in the rig {}; expected one of {}",
                        row.sensor,
                        rig.source,
                        crate::limits::excerpt(&rig.ids())
                    ),
                });
            }
            let key = (row.emitter.as_str(), row.sensor.as_str());
            if let Some(&first_line) = first.get(&key) {
                return Err(IoError::Duplicate {
                    at: crate::Location::line(&self.source, row.line_no),
                    first_line,
                    what: format!("emitter '{}' seen by sensor '{}'", row.emitter, row.sensor),
                });
            }
            first.insert(key, row.line_no);
        }
        Ok(())
    }

    /// The emitters in order of first appearance, each with the indices of
    /// its rows.
    pub fn emitters(&self) -> Vec<(String, Vec<usize>)> {
        let mut out: Vec<(String, Vec<usize>)> = Vec::new();
        let mut slot: HashMap<&str, usize> = HashMap::new();
        for (i, row) in self.rows.iter().enumerate() {
            match slot.get(row.emitter.as_str()) {
                Some(&k) => out[k].1.push(i),
                None => {
                    slot.insert(row.emitter.as_str(), out.len());
                    out.push((row.emitter.clone(), vec![i]));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use nalgebra::Vector2;

    use super::*;

    #[test]
    fn a_non_finite_row_is_kept_as_such_and_the_others_read() {
        let text = "emitter,sensor,x_mm,y_mm\ne1,a,1,2\ne2,a,NaN,2\ne3,a,3,\n";
        let o = RigObservations::from_str("rig_points.csv", text).unwrap();
        assert_eq!(o.rows.len(), 3);
        assert_eq!(
            o.rows[0].input,
            PointInput::Position(Vector2::new(1.0, 2.0))
        );
        for (row, column) in o.rows[1..].iter().zip(["x_mm", "y_mm"]) {
            assert!(
                matches!(&row.input, PointInput::NonFinite { column: c, .. } if c.name == column),
                "{row:?}"
            );
        }
        // Text that is not a number is still an error naming the line.
        let e = RigObservations::from_str("r.csv", "emitter,sensor,x_mm,y_mm\ne,a,abc,1\n");
        assert!(e.unwrap_err().to_string().starts_with("r.csv:2:"));
    }

    fn rig() -> RigFile {
        RigFile::from_json_str(
            "rig.json",
            r#"{"format": "psdcal-rig", "version": 1, "sensors": [
                {"id": "a", "calibration": "a.json", "world_from_sensor": {"rvec": [0,0,0], "t_mm": [0,0,0]}},
                {"id": "b", "calibration": "b.json", "world_from_sensor": {"rvec": [0,0,0], "t_mm": [900,0,0]}}]}"#,
            Path::new(""),
        )
        .unwrap()
    }

    #[test]
    fn reads_points_and_groups_emitters() {
        let text =
            "# rig\nsensor,emitter,x_mm,y_mm,extra\na,e1,0.5,-1,x\nb,e1,1.5,-1,y\na,e2,0,0,z\n";
        let o = RigObservations::from_str("obs.csv", text).unwrap();
        assert!(!o.amplitudes);
        assert_eq!(o.rows[1].line_no, 4);
        assert_eq!(
            o.rows[1].input,
            PointInput::Position(Vector2::new(1.5, -1.0))
        );
        o.check_against(&rig()).unwrap();
        assert_eq!(
            o.emitters(),
            vec![("e1".to_string(), vec![0, 1]), ("e2".to_string(), vec![2])]
        );
    }

    #[test]
    fn reads_amplitudes() {
        let text = "emitter,sensor,vx1,vx2,vy1,vy2\n1,a,1,2,3,4\n";
        let o = RigObservations::from_str("obs.csv", text).unwrap();
        assert!(o.amplitudes);
        assert!(matches!(o.rows[0].input, PointInput::Amplitudes(a) if a.vy2 == 4.0));
    }

    #[test]
    fn errors_name_the_line() {
        let e = RigObservations::from_str("obs.csv", "emitter,x_mm,y_mm\n1,0,0\n").unwrap_err();
        assert!(e.to_string().contains("missing column 'sensor'"), "{e}");
        let e =
            RigObservations::from_str("obs.csv", "emitter,sensor,x_mm,y_mm\n1,,0,0\n").unwrap_err();
        assert_eq!(e.line(), Some(2));
        let o =
            RigObservations::from_str("obs.csv", "emitter,sensor,x_mm,y_mm\n1,a,0,0\n1,c,0,0\n")
                .unwrap();
        let e = o.check_against(&rig()).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(
            e.to_string()
                .contains("sensor 'c' is not in the rig rig.json; expected one of a, b"),
            "{e}"
        );
        let o =
            RigObservations::from_str("obs.csv", "emitter,sensor,x_mm,y_mm\n1,a,0,0\n1,a,1,0\n")
                .unwrap();
        let e = o.check_against(&rig()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "obs.csv:3: emitter '1' seen by sensor 'a' appears twice (first on line 2)"
        );
    }
}
