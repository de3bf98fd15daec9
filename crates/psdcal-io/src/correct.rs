//! Correction of a points table with a calibration: measured → ideal
//! impact points (docs/model.md §2, `SensorModel::undistort`).
//!
//! Amplitude rows are first turned into measured points with docs/model.md §1 on
//! the calibration's sensor size, dividing out its channel gains if it has
//! any. The answer is the input table with its columns and text unchanged,
//! followed by `x_mm`, `y_mm` (amplitude input only) and `x_ideal_mm`,
//! `y_ideal_mm`. Points off the active area are corrected anyway, with a
//! warning: the model was not fitted there. Points outside the calibration's
//! valid region (docs/model.md §8.2: past the first fold of the correction
//! from the optical centre) have no ideal point: their fields are left empty,
//! with a warning (status `outside_valid_region`).

use std::io::{self, Write};

use nalgebra::Vector2;
use psdcal_model::sensor::is_on_active_area;
use psdcal_model::ChannelGains;

use crate::calibration::Calibration;
use crate::error::{IoError, Location};
use crate::points::{AddedColumn, Points};
use crate::warning::Warning;

/// Columns added for measured points computed from amplitudes.
pub const MEASURED_COLUMNS: [&str; 2] = ["x_mm", "y_mm"];
/// Columns added for the ideal points.
pub const IDEAL_COLUMNS: [&str; 2] = ["x_ideal_mm", "y_ideal_mm"];

/// The corrected points of a table.
#[derive(Debug, Clone, PartialEq)]
pub struct Correction {
    /// Measured point of each row, mm.
    pub measured: Vec<Vector2<f64>>,
    /// Ideal point of each row, mm (`None`: outside the valid region).
    pub ideal: Vec<Option<Vector2<f64>>>,
    /// Whether the measured points were computed from amplitudes.
    pub from_amplitudes: bool,
    /// Points off the active area or outside the valid region.
    pub warnings: Vec<Warning>,
}

/// Corrects every row of `points` with `calibration`.
pub fn correct_points(points: &Points, calibration: &Calibration) -> Result<Correction, IoError> {
    let added = added_columns(points.amplitudes);
    if let Some(name) = added.iter().find(|name| points.has_column(name)) {
        return Err(IoError::Structure {
            at: Location::line(&points.source, points.header_line),
            message: format!(
                "the input already has a column '{name}', which the answer adds; expected \
                 input without the columns {}",
                added.join(", ")
            ),
        });
    }
    let model = calibration.to_model();
    let geometry = calibration.geometry();
    let region = calibration.valid_region();
    let gains = calibration.gains().unwrap_or(ChannelGains::UNIT);
    let measured = points.measured(&geometry, &gains)?;
    let mut ideal = Vec::with_capacity(measured.len());
    let mut warnings = Vec::new();
    for (row, m) in points.rows.iter().zip(&measured) {
        if let Err(outside) = region.check(m) {
            warnings.push(Warning::PointOutsideValidRegion {
                file: points.source.clone(),
                line: row.line_no,
                x_mm: m.x,
                y_mm: m.y,
                distance_mm: outside.distance_mm,
                limit_mm: outside.limit_mm,
                fold: outside.fold,
            });
            ideal.push(None);
            continue;
        }
        let p = model.undistort(m);
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Err(IoError::Invalid {
                at: Location::line(&points.source, row.line_no),
                message: format!(
                    "the point ({}, {}) mm is so far off the sensor that its correction \
                     overflows; expected a point near the {} x {} mm active area",
                    m.x, m.y, geometry.lx, geometry.ly
                ),
            });
        }
        if !is_on_active_area(&geometry, m) {
            warnings.push(Warning::PointOutsideArea {
                file: points.source.clone(),
                line: row.line_no,
                x_mm: m.x,
                y_mm: m.y,
                lx_mm: geometry.lx,
                ly_mm: geometry.ly,
            });
        }
        ideal.push(Some(p));
    }
    Ok(Correction {
        measured,
        ideal,
        from_amplitudes: points.amplitudes,
        warnings,
    })
}

fn added_columns(from_amplitudes: bool) -> Vec<&'static str> {
    let mut names = Vec::with_capacity(4);
    if from_amplitudes {
        names.extend(MEASURED_COLUMNS);
    }
    names.extend(IDEAL_COLUMNS);
    names
}

impl Correction {
    /// Names of the columns the answer adds, in order.
    pub fn added_columns(&self) -> Vec<&'static str> {
        added_columns(self.from_amplitudes)
    }

    /// Writes `points` (the table this correction was made from) with the
    /// added columns.
    pub fn write_csv<W: Write>(&self, points: &Points, out: W) -> io::Result<()> {
        let xm: Vec<Option<f64>> = self.measured.iter().map(|p| Some(p.x)).collect();
        let ym: Vec<Option<f64>> = self.measured.iter().map(|p| Some(p.y)).collect();
        let xi: Vec<Option<f64>> = self.ideal.iter().map(|p| p.map(|p| p.x)).collect();
        let yi: Vec<Option<f64>> = self.ideal.iter().map(|p| p.map(|p| p.y)).collect();
        let mut added = Vec::with_capacity(4);
        if self.from_amplitudes {
            added.push(AddedColumn {
                name: MEASURED_COLUMNS[0],
                values: &xm,
            });
            added.push(AddedColumn {
                name: MEASURED_COLUMNS[1],
                values: &ym,
            });
        }
        added.push(AddedColumn {
            name: IDEAL_COLUMNS[0],
            values: &xi,
        });
        added.push(AddedColumn {
            name: IDEAL_COLUMNS[1],
            values: &yi,
        });
        points.write_csv(out, &added)
    }
}

#[cfg(test)]
mod tests {
    use psdcal_model::sensor::electrode_currents;
    use psdcal_model::{PsdGeometry, SensorModel};

    use super::*;
    use crate::calibration::GainsRecord;

    fn calibration() -> Calibration {
        Calibration::from_model(&SensorModel::paper_lens2(), &PsdGeometry::default())
    }

    #[test]
    fn corrects_positions_and_keeps_the_table() {
        let points =
            Points::from_str("points.csv", "name,x_mm,y_mm\nfirst,1.5,-2\nsecond,0,0\n").unwrap();
        let cal = calibration();
        let c = correct_points(&points, &cal).unwrap();
        let model = SensorModel::paper_lens2();
        assert_eq!(c.ideal[0], Some(model.undistort(&Vector2::new(1.5, -2.0))));
        assert_eq!(c.ideal[1], Some(model.undistort(&Vector2::zeros())));
        assert!(c.warnings.is_empty());
        assert_eq!(c.added_columns(), ["x_ideal_mm", "y_ideal_mm"]);
        let mut out = Vec::new();
        c.write_csv(&points, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let expected = format!(
            "name,x_mm,y_mm,x_ideal_mm,y_ideal_mm\nfirst,1.5,-2,{},{}\nsecond,0,0,{},{}\n",
            c.ideal[0].unwrap().x,
            c.ideal[0].unwrap().y,
            c.ideal[1].unwrap().x,
            c.ideal[1].unwrap().y
        );
        assert_eq!(text, expected);
    }

    #[test]
    fn corrects_amplitudes_dividing_the_gains() {
        let geometry = PsdGeometry::default();
        let gains = ChannelGains {
            x2: 1.05,
            y1: 0.95,
            y2: 1.02,
        };
        let mut cal = calibration();
        cal.gains = Some(GainsRecord::new(&gains, false));
        let a = electrode_currents(&geometry, &Vector2::new(2.0, 1.0), 1.0).apply_gains(&gains);
        let text = format!("vx1,vx2,vy1,vy2\n{},{},{},{}\n", a.vx1, a.vx2, a.vy1, a.vy2);
        let points = Points::from_str("points.csv", &text).unwrap();
        let c = correct_points(&points, &cal).unwrap();
        assert!(c.from_amplitudes);
        assert!((c.measured[0] - Vector2::new(2.0, 1.0)).norm() < 1e-12);
        assert_eq!(c.ideal[0], Some(cal.to_model().undistort(&c.measured[0])));
        assert_eq!(
            c.added_columns(),
            ["x_mm", "y_mm", "x_ideal_mm", "y_ideal_mm"]
        );
        let mut out = Vec::new();
        c.write_csv(&points, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("vx1,vx2,vy1,vy2,x_mm,y_mm,x_ideal_mm,y_ideal_mm\n"));
    }

    #[test]
    fn off_area_points_warn_and_overflow_is_an_error() {
        let points = Points::from_str("points.csv", "x_mm,y_mm\n0,0\n5,0\n").unwrap();
        let c = correct_points(&points, &calibration()).unwrap();
        assert_eq!(c.warnings.len(), 1);
        assert_eq!(
            c.warnings[0].to_string(),
            "points.csv:3: point (5, 0) mm is off the 9 x 9 mm active area, where the model was \
             not fitted: corrected anyway"
        );
        // Far beyond the active area (and the valid region's checked zone):
        // no answer, never an overflowed number.
        let points = Points::from_str("points.csv", "x_mm,y_mm\n0,0\n1e300,0\n").unwrap();
        let c = correct_points(&points, &calibration()).unwrap();
        assert_eq!(c.ideal[1], None);
        assert!(c.warnings[0]
            .to_string()
            .contains("outside the calibration's valid region"));
    }

    /// Issue 12's reproducer: k1 = −0.02 mm⁻² about (0.5, −0.7) folds at
    /// r* = 1/√(3 · 0.02) = 4.08 mm from the centre; the corner (−4.5, 4.5),
    /// 7.21 mm away, is past the fold (its determinant is positive again and
    /// its ideal point mirrored) and gets no ideal point.
    #[test]
    fn points_past_a_fold_are_not_corrected() {
        let mut model = SensorModel::pinhole(8.0, 0.5, -0.7);
        model.distortion.k1 = -0.02;
        let cal = Calibration::from_model(&model, &PsdGeometry::default());
        let points =
            Points::from_str("points.csv", "name,x_mm,y_mm\nnear,1,1\ncorner,-4.5,4.5\n").unwrap();
        let c = correct_points(&points, &cal).unwrap();
        assert_eq!(c.ideal[0], Some(model.undistort(&Vector2::new(1.0, 1.0))));
        assert_eq!(c.ideal[1], None);
        assert_eq!(c.warnings.len(), 1);
        let w = c.warnings[0].to_string();
        assert!(
            w.starts_with("points.csv:3: point (-4.5, 4.5) mm is outside"),
            "{w}"
        );
        let mut out = Vec::new();
        c.write_csv(&points, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.ends_with("\ncorner,-4.5,4.5,,\n"), "{text}");
    }

    #[test]
    fn an_existing_output_column_is_an_error() {
        let points = Points::from_str("points.csv", "# c\nx_mm,y_mm,x_ideal_mm\n0,0,0\n").unwrap();
        let e = correct_points(&points, &calibration()).unwrap_err();
        assert_eq!(e.line(), Some(2));
        assert!(
            e.to_string().contains("already has a column 'x_ideal_mm'"),
            "{e}"
        );
        let points = Points::from_str("points.csv", "vx1,vx2,vy1,vy2,Y_MM\n1,1,1,1,0\n").unwrap();
        let e = correct_points(&points, &calibration()).unwrap_err();
        assert!(e.to_string().contains("already has a column 'y_mm'"), "{e}");
    }
}
