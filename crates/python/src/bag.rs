//! `import_bag`: a rosbag2 MCAP recording of a real arm as the free-motion dict that
//! `identify` and `train` take (the crate `admittance-bag`; docs/import.md).

use std::path::PathBuf;

use admittance_bag::{import, ImportOptions, Profile};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::value_error;

/// Reads a rosbag2 MCAP bag (a folder, its metadata.yaml or one .mcap file) with `profile`
/// (`"franka"`, `"ur"`, `"lbr"` or a TOML file of the same form) and returns the free-motion
/// dict: `t` `(N,)`, `q`, `qdot`, `qddot`, `tau` `(N, n)`, `joints`, `label` (the vendor's
/// own estimate, `(N, k)`, with `label_names`) when the bag has one, and `report` (what was
/// read and skipped, as text). `rate`: output rate in Hz (default: the q topic's median).
/// `accept_damaged`: skip damaged chunks (counted in the report) instead of failing;
/// `accept_low_rate`: import a recording under 200 Hz with a warning in the report.
#[pyfunction]
#[pyo3(signature = (path, profile, rate=None, accept_damaged=false, accept_low_rate=false))]
pub fn import_bag<'py>(
    py: Python<'py>,
    path: PathBuf,
    profile: &str,
    rate: Option<f64>,
    accept_damaged: bool,
    accept_low_rate: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let profile = Profile::resolve(profile).map_err(|e| value_error(e.to_string()))?;
    let options = ImportOptions {
        rate_hz: rate,
        accept_damage: accept_damaged,
        accept_low_rate,
    };
    let imported = py
        .detach(|| import(&path, &profile, &options))
        .map_err(|e| value_error(e.to_string()))?;
    let table = &imported.table;
    let (rows, n) = (table.t.len(), table.joints.len());
    let matrix = |values: &Vec<f64>, cols: usize| -> PyResult<Bound<'py, PyArray2<f64>>> {
        let a = numpy::ndarray::Array2::from_shape_vec((rows, cols), values.clone())
            .map_err(|e| value_error(e.to_string()))?;
        Ok(PyArray2::from_owned_array(py, a))
    };
    let out = PyDict::new(py);
    out.set_item("t", PyArray1::from_slice(py, &table.t))?;
    for (name, values) in [
        ("q", &table.q),
        ("qdot", &table.qdot),
        ("qddot", &table.qddot),
        ("tau", &table.tau),
    ] {
        out.set_item(name, matrix(values, n)?)?;
    }
    out.set_item("joints", table.joints.clone())?;
    if let Some((names, values)) = &table.label {
        out.set_item("label", matrix(values, names.len())?)?;
        out.set_item("label_names", names.clone())?;
    }
    out.set_item("report", imported.report.to_string())?;
    Ok(out)
}
