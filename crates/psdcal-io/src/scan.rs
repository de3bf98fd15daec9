//! scan.csv: a lensless scan of the PSD, the data of its non-linearity map
//! (docs/formats.md, docs/model.md §8.3).
//!
//! | column | meaning |
//! | --- | --- |
//! | `x_stage_mm`, `y_stage_mm` | where the stage put the light spot (sensor frame, mm) |
//! | `x_mm`, `y_mm` — or `vx1`, `vx2`, `vy1`, `vy2` | what the PSD measured there |
//!
//! The amplitude form gives the measured point by the pin-cushion formulas
//! of docs/model.md §1 (with the sensor size, and the relative channel gains
//! divided out when known). When both forms are present the points are used.
//! Two rows at the same stage position (to 1 nm) are refused: a scan visits
//! each position once.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::Vector2;
use psdcal_model::{Amplitudes, ChannelGains, PsdGeometry};

use crate::atomic::write_atomic;
use crate::csv_table::CsvTable;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::location::Location;
use crate::signals::impact_point_at;

const EXPECTED_COLUMNS: &str = "x_stage_mm, y_stage_mm, and x_mm, y_mm or vx1, vx2, vy1, vy2";

/// Two stage positions closer than this (mm, in both coordinates) are the
/// same position.
pub const SCAN_DUPLICATE_MM: f64 = 1e-6;

/// What the PSD reported at a scan position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScanReading {
    /// A measured impact point, mm.
    Point(Vector2<f64>),
    /// The four electrode amplitudes.
    Amplitudes(Amplitudes),
}

/// One row of a scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRow {
    /// Where the stage put the spot, mm.
    pub stage: Vector2<f64>,
    /// What the PSD measured.
    pub reading: ScanReading,
    /// Physical line, 1-based.
    pub line_no: usize,
}

/// A scan as read (points or amplitudes).
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// File name, for messages.
    pub source: String,
    /// The rows, in file order.
    pub rows: Vec<ScanRow>,
}

/// A scan as pairs of positions: the stage's (true) and the PSD's (measured).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanPoints {
    /// File name, for messages.
    pub source: String,
    /// Stage positions, mm.
    pub stage: Vec<Vector2<f64>>,
    /// Measured points, mm.
    pub measured: Vec<Vector2<f64>>,
    /// Physical line of each row.
    pub lines: Vec<usize>,
    /// Whether the file gave amplitudes.
    pub from_amplitudes: bool,
}

impl Scan {
    csv_table_readers!("scan.csv");

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        let sx = table.column("x_stage_mm")?;
        let sy = table.column("y_stage_mm")?;
        let point_cols = match (table.find_column("x_mm")?, table.find_column("y_mm")?) {
            (Some(x), Some(y)) => Some((x, y)),
            _ => None,
        };
        let amp_cols = if point_cols.is_none() {
            Some([
                table.column("vx1")?,
                table.column("vx2")?,
                table.column("vy1")?,
                table.column("vy2")?,
            ])
        } else {
            None
        };
        table.require_rows()?;
        let mut seen: HashMap<(i64, i64), usize> = HashMap::new();
        let mut rows = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            let stage = Vector2::new(table.number(row, &sx)?, table.number(row, &sy)?);
            let key = (
                (stage.x / SCAN_DUPLICATE_MM).round() as i64,
                (stage.y / SCAN_DUPLICATE_MM).round() as i64,
            );
            if let Some(first) = seen.insert(key, row.line) {
                return Err(IoError::Duplicate {
                    at: table.at(row.line),
                    first_line: first,
                    what: format!(
                        "the stage position ({}, {}) mm; expected each position scanned once \
                         (average repeated readings before fitting)",
                        stage.x, stage.y
                    ),
                });
            }
            let reading = match (&point_cols, &amp_cols) {
                (Some((x, y)), _) => {
                    ScanReading::Point(Vector2::new(table.number(row, x)?, table.number(row, y)?))
                }
                (None, Some(c)) => ScanReading::Amplitudes(Amplitudes {
                    vx1: table.number(row, &c[0])?,
                    vx2: table.number(row, &c[1])?,
                    vy1: table.number(row, &c[2])?,
                    vy2: table.number(row, &c[3])?,
                }),
                (None, None) => unreachable!("the amplitude columns were required above"),
            };
            rows.push(ScanRow {
                stage,
                reading,
                line_no: row.line,
            });
        }
        Ok(Self {
            source: table.source,
            rows,
        })
    }

    /// The scan as position pairs: amplitudes become measured points
    /// (docs/model.md §1 with `geometry`, `gains` divided out); every point
    /// must lie within the checked zone (1.5 × the active area), or the scan
    /// is of another sensor size.
    pub fn points(
        &self,
        geometry: &PsdGeometry,
        gains: &ChannelGains,
    ) -> Result<ScanPoints, IoError> {
        let mut out = ScanPoints {
            source: self.source.clone(),
            stage: Vec::with_capacity(self.rows.len()),
            measured: Vec::with_capacity(self.rows.len()),
            lines: Vec::with_capacity(self.rows.len()),
            from_amplitudes: false,
        };
        let (hx, hy) = (0.75 * geometry.lx, 0.75 * geometry.ly);
        for row in &self.rows {
            let at = || Location::line(&self.source, row.line_no);
            let measured = match row.reading {
                ScanReading::Point(p) => p,
                ScanReading::Amplitudes(a) => {
                    out.from_amplitudes = true;
                    impact_point_at(geometry, &a, gains, at)?
                }
            };
            for (what, p) in [("stage position", row.stage), ("measured point", measured)] {
                if p.x.abs() > hx || p.y.abs() > hy {
                    return Err(IoError::Invalid {
                        at: at(),
                        message: format!(
                            "the {what} ({}, {}) mm is off a {} mm × {} mm sensor by more than \
                             half its size; expected a scan of this sensor (check --lx/--ly)",
                            p.x, p.y, geometry.lx, geometry.ly
                        ),
                    });
                }
            }
            out.stage.push(row.stage);
            out.measured.push(measured);
            out.lines.push(row.line_no);
        }
        Ok(out)
    }
}

/// Writes scan.csv atomically: `x_stage_mm, y_stage_mm`, then `x_mm, y_mm`
/// when `measured` is given and `vx1, vx2, vy1, vy2` when `amplitudes` is
/// (numbers in shortest round-trip form).
pub fn write_scan(
    path: impl AsRef<Path>,
    stage: &[Vector2<f64>],
    measured: Option<&[Vector2<f64>]>,
    amplitudes: Option<&[Amplitudes]>,
) -> Result<(), IoError> {
    use std::io::Write;
    let n = |v: f64| crate::number_text::number_text(v);
    write_atomic(path, |w| {
        let mut header = vec!["x_stage_mm", "y_stage_mm"];
        if measured.is_some() {
            header.extend(["x_mm", "y_mm"]);
        }
        if amplitudes.is_some() {
            header.extend(["vx1", "vx2", "vy1", "vy2"]);
        }
        writeln!(w, "{}", header.join(","))?;
        for (i, s) in stage.iter().enumerate() {
            let mut row = vec![n(s.x), n(s.y)];
            if let Some(m) = measured.and_then(|m| m.get(i)) {
                row.extend([n(m.x), n(m.y)]);
            }
            if let Some(a) = amplitudes.and_then(|a| a.get(i)) {
                row.extend([n(a.vx1), n(a.vx2), n(a.vy1), n(a.vy2)]);
            }
            writeln!(w, "{}", row.join(","))?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use psdcal_model::psd::electrode_currents;

    use super::*;

    #[test]
    fn reads_points_and_amplitudes_alike() {
        let geometry = PsdGeometry::default();
        let m = Vector2::new(1.25, -2.0);
        let a = electrode_currents(&geometry, &m, 1.0);
        let text = format!(
            "# scan\ny_stage_mm,x_stage_mm,vx1,vx2,vy1,vy2\n-2.01,1.2,{},{},{},{}\n",
            a.vx1, a.vx2, a.vy1, a.vy2
        );
        let scan = Scan::from_str("scan.csv", &text).unwrap();
        let p = scan.points(&geometry, &ChannelGains::UNIT).unwrap();
        assert!(p.from_amplitudes);
        assert_eq!(p.lines, [3]);
        assert_eq!(p.stage[0], Vector2::new(1.2, -2.01));
        assert!((p.measured[0] - m).norm() < 1e-12);
        let text = "x_stage_mm,y_stage_mm,x_mm,y_mm\n1,2,1.001,2.002\n";
        let p = Scan::from_str("scan.csv", text)
            .unwrap()
            .points(&geometry, &ChannelGains::UNIT)
            .unwrap();
        assert_eq!(p.measured[0], Vector2::new(1.001, 2.002));
        assert!(!p.from_amplitudes);
    }

    #[test]
    fn bad_scans_are_refused_with_their_line() {
        let e = Scan::from_str(
            "scan.csv",
            "x_stage_mm,y_stage_mm,x_mm,y_mm\n0,0,0,0\n1,1,1,1\n0,0,0.1,0\n",
        )
        .unwrap_err();
        assert_eq!(e.line(), Some(4));
        assert!(e.to_string().contains("first on line 2"), "{e}");
        let e = Scan::from_str("scan.csv", "x_stage_mm,y_stage_mm,x_mm\n0,0,0\n").unwrap_err();
        assert!(e.to_string().contains("vx1"), "{e}");
        let e =
            Scan::from_str("scan.csv", "x_stage_mm,y_stage_mm,x_mm,y_mm\n0,0,abc,0\n").unwrap_err();
        assert_eq!(e.line(), Some(2));
        let far = Scan::from_str(
            "scan.csv",
            "x_stage_mm,y_stage_mm,x_mm,y_mm\n0,0,0,0\n9,9,9,9\n",
        )
        .unwrap();
        let e = far
            .points(&PsdGeometry::default(), &ChannelGains::UNIT)
            .unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(e.to_string().contains("--lx"), "{e}");
    }
}
