//! Conversion between Python objects and the Rust crates' slices: array-likes in (checked
//! for shape, named in every error), numpy arrays out (new, or written into `out=`), and the
//! error types of the Rust crates as Python exceptions.

use numpy::prelude::*;
use numpy::{PyArray1, PyArray2, PyArrayDyn};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;

/// `numpy.asarray`, looked up once.
static ASARRAY: PyOnceLock<Py<PyAny>> = PyOnceLock::new();

/// `(7,)`, `(100, 7)`: a shape as numpy prints it.
pub fn shape_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Any array-like as a float64 numpy array (numpy's own conversion: lists, tuples, scalars,
/// integer or float32 arrays); an object numpy cannot convert is a `TypeError` naming `name`.
fn as_float_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    expected: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let py = obj.py();
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        return Ok(a.clone());
    }
    let asarray = ASARRAY.get_or_try_init(py, || -> PyResult<Py<PyAny>> {
        Ok(py.import("numpy")?.getattr("asarray")?.unbind())
    })?;
    // Numbers only: integers and floats of any width convert; an object, string, boolean,
    // complex or date array is refused (numpy would turn '1.5' into 1.5, True into 1.0, and
    // drop imaginary parts).
    let plain = asarray.bind(py).call1((obj,)).map_err(|e| {
        PyTypeError::new_err(format!(
            "`{name}` must be a float64 array-like of shape {expected}: {}",
            e.value(py)
        ))
    })?;
    let dtype = plain.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(PyTypeError::new_err(format!(
            "`{name}` must be a float64 array-like of shape {expected}: it has dtype {} (numpy kind '{kind}'); give numbers (floats, or integers to convert)",
            dtype.str()?
        )));
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", "float64")?;
    let converted = asarray
        .bind(py)
        .call((plain,), Some(&kwargs))
        .map_err(|e| {
            PyTypeError::new_err(format!(
                "`{name}` must be a float64 array-like of shape {expected}: {}",
                e.value(py)
            ))
        })?;
    converted
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|_| PyTypeError::new_err(format!("`{name}`: numpy.asarray gave no float64 array")))
}

/// The elements of a float64 vector, when it is aligned and contiguous.
///
/// Read without numpy's dynamic borrow tracking (`try_readonly` costs a few hundred ns per
/// array, most of the bindings' overhead per control step): the slice is used only to copy
/// the values out, while this thread is attached to the interpreter, and no Rust reference
/// to the array's data is held elsewhere (the bindings copy every input before they write
/// any output). An abi3 module only loads into an interpreter with a GIL, so no other
/// thread runs Python or this module meanwhile.
fn contiguous_elements<'a>(a: &'a Bound<'_, PyArray1<f64>>) -> Option<&'a [f64]> {
    // SAFETY: see above; `as_slice` checks alignment and contiguity.
    unsafe { a.as_slice().ok() }
}

/// Whether numpy lets the array be written.
fn writeable(a: &Bound<'_, PyArray1<f64>>) -> bool {
    // SAFETY: reads the flags word of a live array object (the GIL is held).
    let flags =
        unsafe { (*numpy::npyffi::objects::_PyArray_GET_ITEM_DATA(a.as_array_ptr())).flags };
    flags & numpy::npyffi::flags::NPY_ARRAY_WRITEABLE != 0
}

/// Copies a `(len,)` array-like into `out` (`len = out.len()`); `what` says what the values
/// are (`"one value per joint"`). A numpy float64 vector is read without conversion.
pub fn read_vector(
    obj: &Bound<'_, PyAny>,
    name: &str,
    out: &mut [f64],
    what: &str,
) -> PyResult<()> {
    let n = out.len();
    if let Ok(a) = obj.cast::<PyArray1<f64>>() {
        if let Some(s) = contiguous_elements(a).filter(|s| s.len() == n) {
            out.copy_from_slice(s);
            return Ok(());
        }
    }
    let expected = shape_text(&[n]);
    let a = as_float_array(obj, name, &expected)?;
    if a.shape() != [n] {
        return Err(PyValueError::new_err(format!(
            "`{name}` must have shape {expected} ({what}), got shape {}",
            shape_text(a.shape())
        )));
    }
    let ro = a
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("`{name}`: {e}")))?;
    out.iter_mut().zip(ro.as_array()).for_each(|(o, v)| *o = *v);
    Ok(())
}

/// A `(len,)` array-like as a new vector.
pub fn vector(obj: &Bound<'_, PyAny>, name: &str, len: usize, what: &str) -> PyResult<Vec<f64>> {
    let mut v = vec![0.0; len];
    read_vector(obj, name, &mut v, what)?;
    Ok(v)
}

/// Rows of `cols` values: a `(rows, cols)` array-like, row-major. With `single_row`, a
/// `(cols,)` vector is accepted as one row and reported by the returned flag.
pub fn rows(
    obj: &Bound<'_, PyAny>,
    name: &str,
    cols: usize,
    single_row: bool,
) -> PyResult<(Vec<f64>, usize, bool)> {
    let expected = if single_row {
        format!("{} or (N, {cols})", shape_text(&[cols]))
    } else {
        format!("(N, {cols})")
    };
    let a = as_float_array(obj, name, &expected)?;
    let ro = a
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("`{name}`: {e}")))?;
    let view = ro.as_array();
    match a.shape() {
        [c] if single_row && *c == cols => Ok((view.iter().copied().collect(), 1, true)),
        [r, c] if *c == cols => Ok((view.iter().copied().collect(), *r, false)),
        other => Err(PyValueError::new_err(format!(
            "`{name}` must have shape {expected}, got shape {}",
            shape_text(other)
        ))),
    }
}

/// A `(len,)` column of a data set (`len` rows).
pub fn column(obj: &Bound<'_, PyAny>, name: &str, len: Option<usize>) -> PyResult<Vec<f64>> {
    let expected = match len {
        Some(n) => shape_text(&[n]),
        None => "(N,)".to_string(),
    };
    let a = as_float_array(obj, name, &expected)?;
    match a.shape() {
        [r] if len.is_none_or(|n| n == *r) => {
            let ro = a
                .try_readonly()
                .map_err(|e| PyValueError::new_err(format!("`{name}`: {e}")))?;
            Ok(ro.as_array().iter().copied().collect())
        }
        other => Err(PyValueError::new_err(format!(
            "`{name}` must have shape {expected}, got shape {}",
            shape_text(other)
        ))),
    }
}

/// The index and value of the first non-finite entry.
pub fn first_non_finite(values: &[f64]) -> Option<(usize, f64)> {
    values
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite())
        .map(|(i, v)| (i, *v))
}

/// A `ValueError` when the rows of `cols` values hold a NaN or infinity, naming
/// `name[row, column]` (`name[column]` for a single row given as a vector).
pub fn require_finite_rows(values: &[f64], cols: usize, single: bool, name: &str) -> PyResult<()> {
    match first_non_finite(values) {
        None => Ok(()),
        Some((i, v)) if single => Err(PyValueError::new_err(format!(
            "`{name}[{i}]` is {v}; give finite values"
        ))),
        Some((i, v)) => Err(PyValueError::new_err(format!(
            "`{name}[{}, {}]` is {v}; give finite values",
            i / cols.max(1),
            i % cols.max(1)
        ))),
    }
}

/// A `ValueError` when `values` holds a NaN or infinity, naming `name[index]`.
pub fn require_finite(values: &[f64], name: &str) -> PyResult<()> {
    match first_non_finite(values) {
        None => Ok(()),
        Some((i, v)) => Err(PyValueError::new_err(format!(
            "`{name}[{i}]` is {v}; give finite values"
        ))),
    }
}

/// `values` as a new `(len,)` array, or written into `out` (a writeable float64 array of
/// that shape), which is then returned.
pub fn vector_out<'py>(
    py: Python<'py>,
    values: &[f64],
    out: Option<&Bound<'py, PyAny>>,
    name: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let Some(out) = out else {
        return Ok(PyArray1::from_slice(py, values));
    };
    let bad = || {
        PyValueError::new_err(format!(
            "`{name}` must be a writeable float64 numpy array of shape {}",
            shape_text(&[values.len()])
        ))
    };
    let a = out.cast::<PyArray1<f64>>().map_err(|_| bad())?;
    if a.len() != values.len() || !writeable(a) {
        return Err(bad());
    }
    // SAFETY: as in `contiguous_elements`; `values` is the bindings' own buffer, never the
    // array's memory, and the slice lives only for the copy.
    match unsafe { a.as_slice_mut() } {
        Ok(s) => s.copy_from_slice(values),
        Err(_) => {
            let mut rw = a.try_readwrite().map_err(|_| bad())?;
            rw.as_array_mut()
                .iter_mut()
                .zip(values)
                .for_each(|(o, v)| *o = *v);
        }
    }
    Ok(a.clone())
}

/// A `(rows, cols)` array from a function of the index, or written into `out`.
pub fn matrix_out<'py>(
    py: Python<'py>,
    shape: (usize, usize),
    value: impl Fn(usize, usize) -> f64,
    out: Option<&Bound<'py, PyAny>>,
    name: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let Some(out) = out else {
        let a = numpy::ndarray::Array2::from_shape_fn(shape, |(i, j)| value(i, j));
        return Ok(PyArray2::from_owned_array(py, a));
    };
    let bad = || {
        PyValueError::new_err(format!(
            "`{name}` must be a writeable float64 numpy array of shape {}",
            shape_text(&[shape.0, shape.1])
        ))
    };
    let a = out.cast::<PyArray2<f64>>().map_err(|_| bad())?;
    if a.shape() != [shape.0, shape.1] {
        return Err(bad());
    }
    let mut rw = a.try_readwrite().map_err(|_| bad())?;
    rw.as_array_mut()
        .indexed_iter_mut()
        .for_each(|((i, j), o)| *o = value(i, j));
    Ok(a.clone())
}

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// A configuration error of the control crate, under `context` (e.g. `NeuralController`).
pub fn config_error(context: &str, e: admittance_control::ConfigError) -> PyErr {
    PyValueError::new_err(format!("{context}: {}", e.text()))
}

/// A dynamics error: a file that cannot be read is an `OSError`, anything else a
/// `ValueError` (the message names the file, line and element).
pub fn dynamics_error(e: admittance_dynamics::DynamicsError) -> PyErr {
    match e {
        admittance_dynamics::DynamicsError::Io { .. } => PyOSError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

/// A network error: I/O is an `OSError`, a fit that failed numerically a `RuntimeError`,
/// bad data, settings or files a `ValueError`.
pub fn broad_error(e: admittance_learning::broad::BroadError) -> PyErr {
    use admittance_learning::broad::BroadError as E;
    match e {
        E::Io { .. } => PyOSError::new_err(e.to_string()),
        E::NotPositiveDefinite { .. } | E::Greville(_) => PyRuntimeError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

/// A free-motion data error: I/O is an `OSError`, anything else (with its line and column)
/// a `ValueError`.
pub fn free_motion_error(e: admittance_scenario::FreeMotionError) -> PyErr {
    match e {
        admittance_scenario::FreeMotionError::Io { .. } => PyOSError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}
