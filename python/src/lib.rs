//! The `psdcal` Python package's native module (`psdcal._psdcal`): a thin
//! binding of the `psdcal` library facade, as the command line is. It turns
//! Python values into the facade's inputs (paths, rows of numbers, option
//! text), calls the facade and turns its answers into numpy arrays and
//! dicts; every facade error becomes `psdcal.PsdcalError` (a `ValueError`)
//! with the command line's message and advice (`psdcal::error_text`).
//! Nothing here computes: angles, fits and checks are the facade's.
#![warn(missing_docs)]

mod calibration;
mod functions;
mod input;

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

create_exception!(
    psdcal,
    PsdcalError,
    PyValueError,
    "A psdcal failure: bad data, bad options, a file that cannot be read, a fit that failed. \
     The message is the command line's: what happened, then what to do."
);

/// A facade error as `PsdcalError` with the command line's text.
pub(crate) fn error(e: &psdcal::Error) -> PyErr {
    PsdcalError::new_err(psdcal::error_text(e))
}

/// A message of the binding's own (a Python value that is not what an
/// argument takes) as `PsdcalError`, with the facade's advice for input.
pub(crate) fn input_error(message: impl Into<String>) -> PyErr {
    error(&psdcal::Error::Input(message.into()))
}

/// The native module.
#[pymodule]
fn _psdcal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("PsdcalError", m.py().get_type::<PsdcalError>())?;
    m.add_class::<calibration::Calibration>()?;
    m.add_function(wrap_pyfunction!(functions::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(functions::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(functions::demodulate, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
