//! `psdcal.Calibration`: a calibration (calibration.json's record) and its
//! calibrated sensor; loads, saves, and answers points as `psdcal aoa`,
//! `correct` and `locate` do.

use std::path::PathBuf;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use psdcal::arrays::{
    aoa_into, correct_into, locate_into, locate_options, measurements_from_rows, parameters,
};
use psdcal::{CalibratedSensor, LoadedSensor};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::input::{path as to_path, table};
use crate::{error, input_error};

/// A sensor's calibration: the model's parameters, their covariance, the
/// fit's diagnostics, and the calibrated sensor that turns measured points
/// (mm, or electrode amplitudes) into ideal points, angles of arrival and
/// positions. Made by `psdcal.calibrate` or read by `Calibration.load`.
#[pyclass(module = "psdcal", frozen)]
pub struct Calibration {
    record: psdcal::Calibration,
    sensor: CalibratedSensor,
}

impl Calibration {
    /// A calibration of a record (from the facade's calibrate).
    pub fn of_record(record: psdcal::Calibration) -> PyResult<Self> {
        let sensor = psdcal::sensor_of(&record).map_err(|e| error(&e))?;
        Ok(Self { record, sensor })
    }
}

/// Rows answered per chunk: between chunks the GIL is taken back briefly to
/// check for Ctrl-C (a chunk of aoa takes about 10 ms).
const CHUNK_ROWS: usize = 16_384;

/// Runs `step` on the rows `0..n` in chunks of [`CHUNK_ROWS`], the GIL
/// released during each chunk (other Python threads run) and signals
/// checked between them (Ctrl-C raises KeyboardInterrupt).
fn in_chunks(
    py: Python<'_>,
    n: usize,
    mut step: impl FnMut(std::ops::Range<usize>) -> psdcal::Result<()> + Send,
) -> PyResult<()> {
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK_ROWS).min(n);
        py.detach(|| step(start..end)).map_err(|e| error(&e))?;
        py.check_signals()?;
        start = end;
    }
    Ok(())
}

/// The measurements of a points array (converted with the GIL released).
fn measurements(py: Python<'_>, t: &crate::input::Table) -> PyResult<Vec<psdcal::Measurement>> {
    py.detach(|| measurements_from_rows(&t.rows()))
        .map_err(|e| error(&e))
}

/// The options of a per-point answer from `point_sigma_mm`.
fn point_options(point_sigma_mm: Option<&Bound<'_, PyAny>>) -> PyResult<psdcal::LocateOptions> {
    let sigma = point_sigma_mm
        .map(|v| crate::input::number(v, "point_sigma_mm"))
        .transpose()?;
    locate_options(sigma).map_err(|e| error(&e))
}

/// An `(N, k)` float64 array of a flat row-major vector (moved, not
/// copied).
fn flat_array(py: Python<'_>, values: Vec<f64>, k: usize) -> PyResult<Bound<'_, PyArray2<f64>>> {
    let n = values.len() / k;
    Array2::from_shape_vec((n, k), values)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| input_error(format!("array: {e}")))
}

#[pymethods]
impl Calibration {
    /// Reads calibration.json (version 1 or 2) written by psdcal.
    #[staticmethod]
    #[pyo3(signature = (path, /))]
    fn load(path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let p = to_path(path, "calibration")?;
        let loaded = LoadedSensor::read(&p).map_err(|e| error(&e))?;
        Ok(Self {
            record: loaded.record,
            sensor: loaded.sensor,
        })
    }

    /// Writes calibration.json (atomically: a temporary file renamed), the
    /// same file `psdcal calibrate --out` writes.
    #[pyo3(signature = (path, /))]
    fn save(&self, path: &Bound<'_, PyAny>) -> PyResult<()> {
        let p: PathBuf = to_path(path, "calibration")?;
        psdcal::save_calibration(&self.record, &p).map_err(|e| error(&e))
    }

    /// calibration.json's text.
    fn to_json(&self) -> PyResult<String> {
        self.record
            .to_json_string("calibration")
            .map_err(|e| error(&e.into()))
    }

    /// Every parameter of the model by name (mm, mm⁻ⁿ, rad; docs/model.md):
    /// the standard ones, a PSD map's, the gains.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, value) in parameters(&self.sensor) {
            d.set_item(name, value)?;
        }
        Ok(d)
    }

    /// The standard deviation of each estimated parameter, by name.
    #[getter]
    fn std<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let c = &self.sensor.covariance;
        for name in c.names() {
            if let Some(s) = c.std(name) {
                d.set_item(name, s)?;
            }
        }
        Ok(d)
    }

    /// `(names, matrix)`: the estimated parameters' covariance, in the
    /// order of `names`.
    #[getter]
    fn covariance<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Vec<String>, Bound<'py, PyArray2<f64>>)> {
        let c = &self.sensor.covariance;
        let n = c.len();
        let m = c.matrix();
        let flat: Vec<f64> = (0..n)
            .flat_map(|i| (0..n).map(move |j| m[(i, j)]))
            .collect();
        let a = Array2::from_shape_vec((n, n), flat)
            .map_err(|e| input_error(format!("covariance: {e}")))?;
        Ok((c.names().to_vec(), a.into_pyarray(py)))
    }

    /// What the fit noticed about itself: a list of dicts with `code`,
    /// `severity` and `message` (empty for a clean fit or a version 1
    /// file).
    #[getter]
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for d in &self.record.diagnostics {
            let item = PyDict::new(py);
            item.set_item("code", d.code.as_str())?;
            item.set_item("severity", d.severity.as_str())?;
            item.set_item("message", &d.message)?;
            list.append(item)?;
        }
        Ok(list)
    }

    /// Angles of arrival `(alpha_x, alpha_y)` in degrees, shape `(N, 2)`, of
    /// measured points `(N, 2)` (mm) or electrode amplitudes `(N, 4)`
    /// (`vx1, vx2, vy1, vy2`). `return_sigma=True` also returns their
    /// standard deviations `(N, 2)` in degrees (the calibration's, plus the
    /// point noise's with `point_sigma_mm`). A row that cannot be answered
    /// (outside the valid region, no light, not finite) raises PsdcalError
    /// naming it. The computation releases the GIL (other Python threads
    /// run meanwhile) and stops at Ctrl-C (KeyboardInterrupt).
    #[pyo3(signature = (points, return_sigma=false, point_sigma_mm=None))]
    fn aoa<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        return_sigma: bool,
        point_sigma_mm: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        let options = point_options(point_sigma_mm)?;
        let t = table(points, "points")?;
        let m = measurements(py, &t)?;
        let n = m.len();
        let (mut alpha, mut sigma) = (Vec::with_capacity(2 * n), Vec::with_capacity(2 * n));
        in_chunks(py, n, |range| {
            aoa_into(
                &self.sensor,
                &t.name,
                &m,
                range,
                &options,
                &mut alpha,
                &mut sigma,
            )
        })?;
        let alpha = flat_array(py, alpha, 2)?;
        if return_sigma {
            let sigma = flat_array(py, sigma, 2)?;
            Ok((alpha, sigma).into_pyobject(py)?.into_any().unbind())
        } else {
            Ok(alpha.into_any().unbind())
        }
    }

    /// Ideal (corrected) points `(N, 2)`, mm, of measured points `(N, 2)` or
    /// amplitudes `(N, 4)`. Releases the GIL; stops at Ctrl-C.
    #[pyo3(signature = (points, /))]
    fn correct<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = table(points, "points")?;
        let m = measurements(py, &t)?;
        let mut ideal = Vec::with_capacity(2 * m.len());
        in_chunks(py, m.len(), |range| {
            correct_into(&self.sensor, &t.name, &m, range, &mut ideal)
        })?;
        flat_array(py, ideal, 2)
    }

    /// Emitter positions `(N, 3)`, mm, sensor frame, on the plane
    /// `z = distance` (mm) or on `plane = (nx, ny, nz, d)` (`n·P = d`);
    /// `return_covariance=True` also returns their 3 × 3 covariances
    /// `(N, 3, 3)`, mm². Releases the GIL; stops at Ctrl-C.
    #[pyo3(signature = (points, distance=None, plane=None, return_covariance=false, point_sigma_mm=None))]
    fn locate<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        distance: Option<&Bound<'py, PyAny>>,
        plane: Option<&Bound<'py, PyAny>>,
        return_covariance: bool,
        point_sigma_mm: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        let plane = match (distance, plane) {
            (Some(d), None) => psdcal::plane_at_distance(&crate::input::option_text(d)?),
            (None, Some(p)) => psdcal::option_text::parse_plane(&crate::input::option_text(p)?),
            _ => {
                return Err(input_error(
                    "locate: give exactly one of distance= (mm) and plane=(nx, ny, nz, d)",
                ))
            }
        }
        .map_err(|m| error(&psdcal::Error::Options(m)))?;
        let options = point_options(point_sigma_mm)?;
        let t = table(points, "points")?;
        let m = measurements(py, &t)?;
        let n = m.len();
        let mut positions = Vec::with_capacity(3 * n);
        let mut covariance = Vec::with_capacity(if return_covariance { 9 * n } else { 0 });
        in_chunks(py, n, |range| {
            locate_into(
                &self.sensor,
                &t.name,
                &m,
                range,
                (&plane, &options),
                &mut positions,
                return_covariance.then_some(&mut covariance),
            )
        })?;
        let positions = flat_array(py, positions, 3)?;
        if !return_covariance {
            return Ok(positions.into_any().unbind());
        }
        let cov = numpy::ndarray::Array3::from_shape_vec((n, 3, 3), covariance)
            .map_err(|e| input_error(format!("covariance: {e}")))?;
        Ok((positions, cov.into_pyarray(py))
            .into_pyobject(py)?
            .into_any()
            .unbind())
    }

    fn __repr__(&self) -> String {
        let p = parameters(&self.sensor);
        let shown: Vec<String> = p
            .iter()
            .filter(|(n, _)| self.record.estimated.iter().any(|e| e.name() == n))
            .map(|(n, v)| format!("{n}={v:.6}"))
            .collect();
        format!("<psdcal.Calibration {}>", shown.join(" "))
    }
}
