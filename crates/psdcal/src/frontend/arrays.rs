//! Arrays in, arrays out: the entry points for front ends that hold their
//! data in memory as rows of numbers (the Python package) instead of files.
//! Same validation, same answers as the file commands; only the container
//! differs.
//!
//! Conventions (every array row-major, `f64`):
//! - template: `(N, 2)` rows `X_mm, Y_mm` (LEDs named `1 … N`) or `(N, 3)`
//!   rows `led, X_mm, Y_mm`;
//! - observations: `(M, 4)` rows `image, led, x_mm, y_mm`;
//! - signals: `(M, 6)` rows `image, led, vx1, vx2, vy1, vy2`, or `(M, 7)`
//!   with the record's `snr_db` last;
//! - identifiers (`image`, `led`) are whole numbers, written as decimal text
//!   (`3.0` is LED `3`, as in the files);
//! - points: `(N, 2)` rows `x_mm, y_mm` (measured points) or `(N, 4)` rows
//!   `vx1, vx2, vy1, vy2` (electrode amplitudes).
//!
//! A message names the array and the row as `<array>:<n>` with `n` counting
//! rows from 1 (a file's line). The per-point answers ([`aoa_into`],
//! [`correct_into`], [`locate_into`]) compute each row as `psdcal aoa`,
//! `correct` and `locate` do (docs/model.md §5) and refuse the batch at the
//! first row they cannot answer, naming it and the row's status. They
//! answer a range of rows into flat output vectors, so that a front end
//! can work in chunks (releasing Python's GIL and checking for Ctrl-C
//! between them) with nothing kept per row but the numbers returned.

use std::collections::HashMap;
use std::ops::Range;
use std::path::PathBuf;

use nalgebra::Vector2;
use psdcal_io::{Led, Observation, Observations, SignalRow, Signals, Template};
use psdcal_locate::{
    sigmas_and_correlation, CalibratedSensor, LocateError, LocateOptions, Measurement, Plane,
};
use psdcal_model::psd::Amplitudes;

use crate::answer::correct::correct_point;
use crate::base::error::{Error, Result};
use crate::base::provenance::InputHashes;
use crate::dataset::data_set::{DataSet, DataSetFiles, LoadOptions, MemoryPoints, PointSource};

/// Rows of numbers: `values.len() == rows × columns`, row-major.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rows<'a> {
    /// The array's name in messages (`template array`, …).
    pub name: &'a str,
    /// The values, row-major.
    pub values: &'a [f64],
    /// Columns per row.
    pub columns: usize,
}

impl<'a> Rows<'a> {
    /// The rows, after checking the width against `allowed` (what each
    /// width means, for the message).
    fn rows(&self, allowed: &[usize], meaning: &str) -> Result<std::slice::ChunksExact<'a, f64>> {
        if !allowed.contains(&self.columns)
            || !self.values.len().is_multiple_of(self.columns.max(1))
        {
            return Err(Error::Input(format!(
                "{} has {} columns; expected {meaning}",
                self.name, self.columns
            )));
        }
        if self.values.is_empty() {
            return Err(Error::Input(format!(
                "{} has no rows; expected {meaning}",
                self.name
            )));
        }
        Ok(self.values.chunks_exact(self.columns))
    }

    /// `<name>:<row from 1>` for a message.
    fn at(&self, row: usize) -> String {
        format!("{}:{}", self.name, row + 1)
    }

    /// The finite value at (`row`, `column`), named `what` in the message.
    fn finite(&self, row: usize, values: &[f64], column: usize, what: &str) -> Result<f64> {
        let v = values[column];
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::Input(format!(
                "{}: {what} (column {}) is {v}; expected a finite number",
                self.at(row),
                column + 1
            )))
        }
    }

    /// The identifier at (`row`, `column`): a whole number as decimal text.
    fn identifier(&self, row: usize, values: &[f64], column: usize, what: &str) -> Result<String> {
        let v = self.finite(row, values, column, what)?;
        if v.fract() != 0.0 || v.abs() > 9.007_199_254_740_992e15 {
            return Err(Error::Input(format!(
                "{}: {what} (column {}) is {v}; expected a whole number (an identifier)",
                self.at(row),
                column + 1
            )));
        }
        // `-0` is LED `0`.
        Ok(format!("{}", v as i64))
    }
}

/// A template from its rows (see the module's conventions).
pub fn template_from_rows(rows: &Rows) -> Result<Template> {
    let meaning = "(N, 2) rows X_mm, Y_mm or (N, 3) rows led, X_mm, Y_mm";
    let mut leds = Vec::new();
    let mut first: HashMap<String, usize> = HashMap::new();
    for (i, r) in rows.rows(&[2, 3], meaning)?.enumerate() {
        let (id, x0) = match rows.columns {
            3 => (rows.identifier(i, r, 0, "led")?, 1),
            _ => (format!("{}", i + 1), 0),
        };
        if let Some(&j) = first.get(&id) {
            return Err(Error::Input(format!(
                "{}: LED '{id}' is already on row {} (from 1); keep only one of the two rows",
                rows.at(i),
                j + 1
            )));
        }
        first.insert(id.clone(), i);
        leds.push(Led {
            id,
            x_mm: rows.finite(i, r, x0, "X_mm")?,
            y_mm: rows.finite(i, r, x0 + 1, "Y_mm")?,
            // A template from an array is planar (surveyed 3-D points come
            // from template.csv's Z_mm).
            z_mm: None,
            lines: Vec::new(),
            line_no: i + 1,
        });
    }
    if leds.len() < Template::MIN_LEDS {
        return Err(Error::Input(format!(
            "{}: the template has {} LEDs; expected at least {}",
            rows.name,
            leds.len(),
            Template::MIN_LEDS
        )));
    }
    Ok(Template {
        source: rows.name.to_string(),
        leds,
    })
}

/// Observations from their rows (see the module's conventions).
pub fn observations_from_rows(rows: &Rows) -> Result<Observations> {
    let meaning = "(M, 4) rows image, led, x_mm, y_mm";
    let mut out = Vec::new();
    for (i, r) in rows.rows(&[4], meaning)?.enumerate() {
        out.push(Observation {
            image: rows.identifier(i, r, 0, "image")?,
            led: rows.identifier(i, r, 1, "led")?,
            x_mm: rows.finite(i, r, 2, "x_mm")?,
            y_mm: rows.finite(i, r, 3, "y_mm")?,
            line_no: i + 1,
        });
    }
    Ok(Observations {
        source: rows.name.to_string(),
        rows: out,
    })
}

/// Signals from their rows (see the module's conventions).
pub fn signals_from_rows(rows: &Rows) -> Result<Signals> {
    let meaning = "(M, 6) rows image, led, vx1, vx2, vy1, vy2 (or (M, 7) with snr_db)";
    let mut out = Vec::new();
    for (i, r) in rows.rows(&[6, 7], meaning)?.enumerate() {
        let v = |c: usize, what: &str| rows.finite(i, r, c, what);
        out.push(SignalRow {
            image: rows.identifier(i, r, 0, "image")?,
            led: rows.identifier(i, r, 1, "led")?,
            vx1: v(2, "vx1")?,
            vx2: v(3, "vx2")?,
            vy1: v(4, "vy1")?,
            vy2: v(5, "vy2")?,
            snr_db: if rows.columns == 7 {
                Some(v(6, "snr_db")?)
            } else {
                None
            },
            line_no: i + 1,
        });
    }
    Ok(Signals {
        source: rows.name.to_string(),
        rows: out,
    })
}

/// A table given as a file or as rows.
#[derive(Debug, Clone, PartialEq)]
pub enum TableInput<'a> {
    /// A file (read as the command line reads it).
    File(PathBuf),
    /// Rows of numbers.
    Rows(Rows<'a>),
}

/// Where a data set's points come from, file or rows.
#[derive(Debug, Clone, PartialEq)]
pub enum PointsInput<'a> {
    /// Measured impact points (observations).
    Observations(TableInput<'a>),
    /// Electrode amplitudes (signals).
    Signals(TableInput<'a>),
}

/// A data set from files, rows or both; `gains` is gains.json (with
/// signals only). All files: exactly [`DataSet::from_files`] (with the
/// files' hashes for the provenance); otherwise the files' hashes only.
pub fn data_set(
    template: &TableInput,
    points: &PointsInput,
    gains: Option<&PathBuf>,
    options: &LoadOptions,
) -> Result<DataSet> {
    let file_points = match points {
        PointsInput::Observations(TableInput::File(p)) => {
            Some(PointSource::Observations(p.clone()))
        }
        PointsInput::Signals(TableInput::File(p)) => Some(PointSource::Signals(p.clone())),
        _ => None,
    };
    if let (TableInput::File(template), Some(points)) = (template, file_points) {
        let files = DataSetFiles {
            template: template.clone(),
            points,
            gains: gains.cloned(),
        };
        return DataSet::from_files(&files, options);
    }
    // Each file is hashed as it is read (the provenance lists what was read).
    let mut inputs = InputHashes::default();
    let limits = options.limits;
    let template = match template {
        TableInput::File(p) => inputs.read(p, |s, r| Template::from_reader_with(s, r, limits))?,
        TableInput::Rows(r) => template_from_rows(r)?,
    };
    let known = match gains {
        Some(p) => Some(
            inputs
                .read(p, |s, r| {
                    psdcal_io::GainsFile::from_reader_with(s, r, limits)
                })?
                .gains(),
        ),
        None => None,
    };
    let memory = match points {
        PointsInput::Observations(TableInput::File(p)) => MemoryPoints::Observations(
            inputs.read(p, |s, r| Observations::from_reader_with(s, r, limits))?,
        ),
        PointsInput::Observations(TableInput::Rows(r)) => {
            MemoryPoints::Observations(observations_from_rows(r)?)
        }
        PointsInput::Signals(TableInput::File(p)) => MemoryPoints::Signals(
            inputs.read(p, |s, r| Signals::from_reader_with(s, r, limits))?,
            known,
        ),
        PointsInput::Signals(TableInput::Rows(r)) => {
            MemoryPoints::Signals(signals_from_rows(r)?, known)
        }
    };
    if known.is_some() && !matches!(memory, MemoryPoints::Signals(..)) {
        return Err(Error::Options(
            "known gains (gains.json) are divided out of the electrode amplitudes: give \
             signals instead of observations"
                .into(),
        ));
    }
    let mut set = DataSet::from_memory(template, memory, options)?;
    set.inputs = inputs;
    Ok(set)
}

/// The measurements of point rows: `(N, 2)` measured points or `(N, 4)`
/// amplitudes, every value finite.
pub fn measurements_from_rows(rows: &Rows) -> Result<Vec<Measurement>> {
    let meaning = "(N, 2) rows x_mm, y_mm or (N, 4) rows vx1, vx2, vy1, vy2";
    let mut out = Vec::new();
    for (i, r) in rows.rows(&[2, 4], meaning)?.enumerate() {
        let names: &[&str] = if rows.columns == 2 {
            &["x_mm", "y_mm"]
        } else {
            &["vx1", "vx2", "vy1", "vy2"]
        };
        let mut v = [0.0; 4];
        for (c, name) in names.iter().enumerate() {
            v[c] = rows.finite(i, r, c, name)?;
        }
        out.push(if rows.columns == 2 {
            Measurement::Point(Vector2::new(v[0], v[1]))
        } else {
            Measurement::Amplitudes(Amplitudes {
                vx1: v[0],
                vx2: v[1],
                vy1: v[2],
                vy2: v[3],
            })
        });
    }
    Ok(out)
}

/// Answers the rows `range` of `points` with `answer`, handing each answer
/// to `keep`; at the first row it cannot answer, the error names that row
/// (counted in all of `points`) and how many rows from there to the end
/// cannot be answered. The callers stream: nothing per row is kept but
/// what `keep` stores.
fn each_row_in<T>(
    name: &str,
    points: &[Measurement],
    range: Range<usize>,
    mut answer: impl FnMut(&Measurement) -> std::result::Result<T, LocateError>,
    mut keep: impl FnMut(T),
) -> Result<()> {
    for i in range {
        match answer(&points[i]) {
            Ok(v) => keep(v),
            Err(e) => {
                let failing = points[i..].iter().filter(|m| answer(m).is_err()).count();
                return Err(Error::Input(format!(
                    "{name}:{}: {} ({e}); {failing} of {} rows cannot be answered",
                    i + 1,
                    e.status(),
                    points.len()
                )));
            }
        }
    }
    Ok(())
}

/// The options of a per-point answer: the point noise (as `--point-sigma`,
/// a length from 0 mm).
pub fn locate_options(point_sigma_mm: Option<f64>) -> Result<LocateOptions> {
    let point_sigma_mm = match point_sigma_mm {
        Some(v) => crate::base::option_text::non_negative_mm(&v.to_string())
            .map_err(|e| Error::Options(format!("point_sigma_mm: {e}")))?,
        None => 0.0,
    };
    Ok(LocateOptions {
        point_sigma_mm,
        ..LocateOptions::default()
    })
}

/// The angles of arrival of the rows `range` of `points`, as `psdcal aoa`
/// computes them, appended to `alpha_deg` (`alpha_x, alpha_y` per row,
/// degrees) and `sigma_deg` (their standard deviations: the calibration's
/// and, with a point σ in `options`, the point noise's). Called on chunks
/// of rows, it fills arrays of any length with nothing else per row.
pub fn aoa_into(
    sensor: &CalibratedSensor,
    name: &str,
    points: &[Measurement],
    range: Range<usize>,
    options: &LocateOptions,
    alpha_deg: &mut Vec<f64>,
    sigma_deg: &mut Vec<f64>,
) -> Result<()> {
    each_row_in(
        name,
        points,
        range,
        |m| sensor.aoa(m, options),
        |est| {
            let (sx, sy, _) = sigmas_and_correlation(&est.alpha_covariance());
            let a = &est.aoa;
            alpha_deg.extend([a.alpha.x.to_degrees(), a.alpha.y.to_degrees()]);
            sigma_deg.extend([sx.to_degrees(), sy.to_degrees()]);
        },
    )
}

/// The ideal (corrected) points of the rows `range` of `points`, mm, as
/// `psdcal correct` computes them, appended to `ideal_mm` (`x, y` per row).
pub fn correct_into(
    sensor: &CalibratedSensor,
    name: &str,
    points: &[Measurement],
    range: Range<usize>,
    ideal_mm: &mut Vec<f64>,
) -> Result<()> {
    each_row_in(
        name,
        points,
        range,
        |m| correct_point(sensor, m),
        |c| ideal_mm.extend([c.ideal.x, c.ideal.y]),
    )
}

/// The emitters of the rows `range` of `points` located on `plane` (sensor
/// frame), as `psdcal locate` computes them: positions appended to
/// `position_mm` (`x, y, z` per row, mm), and with `covariance_mm2` their
/// 3 × 3 covariances (row-major, mm²).
pub fn locate_into(
    sensor: &CalibratedSensor,
    name: &str,
    points: &[Measurement],
    range: Range<usize>,
    (plane, options): (&Plane, &LocateOptions),
    position_mm: &mut Vec<f64>,
    mut covariance_mm2: Option<&mut Vec<f64>>,
) -> Result<()> {
    each_row_in(
        name,
        points,
        range,
        |m| sensor.locate_on_plane(m, plane, options),
        |l| {
            let p = l.intersection.position;
            position_mm.extend([p.x, p.y, p.z]);
            if let Some(out) = covariance_mm2.as_deref_mut() {
                let c = l.covariance();
                out.extend((0..3).flat_map(|i| (0..3).map(move |j| c[(i, j)])));
            }
        },
    )
}

/// Every parameter of a calibrated sensor's model, by name, in the model's
/// flat order (docs/model.md §8: the standard names, other stages', the
/// gains).
pub fn parameters(sensor: &CalibratedSensor) -> Vec<(String, f64)> {
    let chain = sensor.chain();
    chain
        .names()
        .into_iter()
        .map(String::from)
        .zip(chain.values().iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows<'a>(name: &'a str, values: &'a [f64], columns: usize) -> Rows<'a> {
        Rows {
            name,
            values,
            columns,
        }
    }

    #[test]
    fn templates_number_their_leds_or_read_them() {
        let xy = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0, 10.0, 10.0];
        let t = template_from_rows(&rows("template array", &xy, 2)).unwrap();
        let ids: Vec<_> = t.leds.iter().map(|l| l.id.as_str()).collect();
        assert_eq!(ids, ["1", "2", "3", "4"]);
        assert_eq!((t.leds[1].x_mm, t.leds[1].y_mm), (10.0, 0.0));
        let named = [7.0, 0.0, 0.0, 3.0, 1.0, 0.0, -0.0, 0.0, 1.0, 9.0, 1.0, 1.0];
        let t = template_from_rows(&rows("template array", &named, 3)).unwrap();
        let ids: Vec<_> = t.leds.iter().map(|l| l.id.as_str()).collect();
        assert_eq!(ids, ["7", "3", "0", "9"]);
    }

    #[test]
    fn bad_rows_are_named() {
        let short = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let e = template_from_rows(&rows("template array", &short, 2)).unwrap_err();
        assert!(
            e.to_string().contains("has 3 LEDs; expected at least 4"),
            "{e}"
        );
        let dup = [1.0, 0.0, 0.0, 2.0, 1.0, 0.0, 1.0, 0.0, 1.0, 3.0, 1.0, 1.0];
        let e = template_from_rows(&rows("template array", &dup, 3)).unwrap_err();
        assert!(
            e.to_string().starts_with("template array:3: LED '1'"),
            "{e}"
        );
        let nan = [1.0, 2.0, f64::NAN, 0.5];
        let e = observations_from_rows(&rows("observations array", &nan, 4)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "observations array:1: x_mm (column 3) is NaN; expected a finite number"
        );
        let frac = [1.5, 2.0, 0.0, 0.5];
        let e = observations_from_rows(&rows("observations array", &frac, 4)).unwrap_err();
        assert!(e.to_string().contains("expected a whole number"), "{e}");
        let e = measurements_from_rows(&rows("points array", &[1.0, 2.0, 3.0], 3)).unwrap_err();
        assert!(
            e.to_string().contains("has 3 columns; expected (N, 2)"),
            "{e}"
        );
        let e = measurements_from_rows(&rows("points array", &[], 2)).unwrap_err();
        assert!(e.to_string().contains("has no rows"), "{e}");
    }

    #[test]
    fn signals_read_an_optional_snr() {
        let v = [1.0, 2.0, 0.1, 0.2, 0.3, 0.4, 41.5];
        let s = signals_from_rows(&rows("signals array", &v, 7)).unwrap();
        assert_eq!(s.rows[0].snr_db, Some(41.5));
        assert_eq!(
            (s.rows[0].image.as_str(), s.rows[0].led.as_str()),
            ("1", "2")
        );
        let s = signals_from_rows(&rows("signals array", &v[..6], 6)).unwrap();
        assert_eq!(s.rows[0].snr_db, None);
    }
}
