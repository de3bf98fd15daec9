//! Python values → the facade's inputs: a path (`str` or `os.PathLike`) or
//! an array of numbers (anything numpy turns into `float64`: arrays, lists),
//! and the rows of numbers the facade's `arrays` module takes.

use std::path::PathBuf;

use numpy::{AllowTypeChange, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::input_error;

/// A 2-D array of numbers, row-major.
#[derive(Debug, Clone)]
pub(crate) struct Table {
    /// Its name in messages.
    pub name: String,
    /// The values, row-major.
    pub values: Vec<f64>,
    /// Columns per row.
    pub columns: usize,
}

impl Table {
    /// The facade's view of it.
    pub fn rows(&self) -> psdcal::arrays::Rows<'_> {
        psdcal::arrays::Rows {
            name: &self.name,
            values: &self.values,
            columns: self.columns,
        }
    }
}

/// A file or rows of numbers.
#[derive(Debug, Clone)]
pub(crate) enum Given {
    /// A path.
    File(PathBuf),
    /// A 2-D array.
    Table(Table),
}

impl Given {
    /// The facade's input.
    pub fn input(&self) -> psdcal::arrays::TableInput<'_> {
        match self {
            Given::File(p) => psdcal::arrays::TableInput::File(p.clone()),
            Given::Table(t) => psdcal::arrays::TableInput::Rows(t.rows()),
        }
    }
}

/// Whether `value` is a path: `str` or `os.PathLike`.
fn is_path(value: &Bound<'_, PyAny>) -> bool {
    value.is_instance_of::<PyString>() || value.hasattr("__fspath__").unwrap_or(false)
}

/// A path argument.
pub(crate) fn path(value: &Bound<'_, PyAny>, what: &str) -> PyResult<PathBuf> {
    if !is_path(value) {
        return Err(input_error(format!(
            "{what}: expected a path (str or os.PathLike), found {}",
            type_name(value)
        )));
    }
    value
        .extract::<PathBuf>()
        .map_err(|e| input_error(format!("{what}: not a usable path ({e})")))
}

/// A path or a 2-D array of numbers; `what` names it in messages (the
/// array is `<what> array`).
pub(crate) fn path_or_table(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Given> {
    if is_path(value) {
        return path(value, what).map(Given::File);
    }
    table(value, what).map(Given::Table)
}

/// A 2-D array of numbers (a single row may be given as a 1-D array).
pub(crate) fn table(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Table> {
    let name = format!("{what} array");
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = value.extract().map_err(|_| {
        input_error(format!(
            "{what}: expected a path or a 2-D array of numbers, found {}",
            type_name(value)
        ))
    })?;
    let shape = array.shape().to_vec();
    let columns = match shape.as_slice() {
        [_, c] => *c,
        [c] => *c,
        _ => {
            return Err(input_error(format!(
                "{name} has shape {shape:?}; expected a 2-D array (rows of numbers)"
            )))
        }
    };
    let values: Vec<f64> = array.as_array().iter().copied().collect();
    Ok(Table {
        name,
        values,
        columns,
    })
}

/// The Python type's name of `value`, for a message.
pub(crate) fn type_name(value: &Bound<'_, PyAny>) -> String {
    value
        .get_type()
        .name()
        .map_or_else(|_| "an object".to_string(), |n| n.to_string())
}

/// The text of an option value as the command line would have it: a
/// string as is, a bool as `true`/`false`, a sequence of names joined by
/// `,`, anything else as `str(value)`.
pub(crate) fn option_text(value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(b) = value.extract::<bool>() {
        if value.is_instance_of::<pyo3::types::PyBool>() {
            return Ok(b.to_string());
        }
    }
    if value.is_instance_of::<PyString>() {
        return value.extract::<String>();
    }
    if is_path(value) {
        return Ok(path(value, "option")?.display().to_string());
    }
    if let Ok(items) = value.extract::<Vec<String>>() {
        return Ok(items.join(","));
    }
    if let Ok(numbers) = value.extract::<Vec<f64>>() {
        let text: Vec<String> = numbers.iter().map(f64::to_string).collect();
        return Ok(text.join(","));
    }
    Ok(value.str()?.to_string())
}

/// A number argument (`float`, `int`, numpy scalars): anything else, or an
/// integer beyond the `f64` range, is `PsdcalError` naming the argument
/// (never `OverflowError` or `TypeError`).
pub(crate) fn number(value: &Bound<'_, PyAny>, what: &str) -> PyResult<f64> {
    value
        .extract::<f64>()
        .map_err(|_| input_error(format!("{what}: expected a number, found {}", shown(value))))
}

/// A seed: a whole number from 0 to 2⁶⁴ − 1 (as `--seed`); a negative or
/// larger integer, or anything else, is `PsdcalError`.
pub(crate) fn seed(value: &Bound<'_, PyAny>) -> PyResult<u64> {
    if value.is_instance_of::<pyo3::types::PyBool>() {
        return Err(input_error(
            "seed: expected a whole number from 0 to 18446744073709551615, found a bool",
        ));
    }
    value.extract::<u64>().map_err(|_| {
        input_error(format!(
            "seed: expected a whole number from 0 to 18446744073709551615, found {}",
            shown(value)
        ))
    })
}

/// A value for a message: its `repr`, clipped to 40 characters.
fn shown(value: &Bound<'_, PyAny>) -> String {
    let text = value
        .repr()
        .map_or_else(|_| type_name(value), |r| r.to_string());
    match text.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &text[..i]),
        None => text,
    }
}
