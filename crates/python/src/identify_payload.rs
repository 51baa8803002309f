//! `identify_payload(data, ident)` from Python: the payload at the tip from free motion with
//! it attached, on top of an identification (issue 30's contract; docs/python.md,
//! "Identification").

use admittance_dynamics::identify_payload as rust_identify_payload;
use pyo3::prelude::*;

use crate::convert::value_error;
use crate::identification::{conditioned_columns, PyIdentification};
use crate::payload::PyPayload;

/// The payload at the tip frame of `ident`'s arm from free-motion `data` recorded with it
/// attached (a CSV path or a dict of arrays, as for `identify`; 20 s is enough), fitted on
/// top of `ident` (what it does not explain is the payload's torque) and physically
/// consistent. The data are conditioned as `ident`'s were (`summary["input_filter_hz"]`;
/// `input_filter_hz` overrides it), the whole recording, and the rows from `from_s` seconds
/// after its start are fitted (leave out a start the models do not describe: the arm
/// settling under the new load).
#[pyfunction]
#[pyo3(signature = (data, ident, input_filter_hz=None, from_s=0.0))]
pub fn identify_payload(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    ident: &Bound<'_, PyIdentification>,
    input_filter_hz: Option<f64>,
    from_s: f64,
) -> PyResult<PyPayload> {
    let ident = ident.get();
    let base = ident.identification.clone();
    let filter_hz = input_filter_hz.unwrap_or(base.summary.input_filter_hz);
    if !(filter_hz.is_finite() && filter_hz >= 0.0) {
        return Err(value_error(format!(
            "`input_filter_hz` is {filter_hz}: a cut-off in Hz >= 0 (0: the signals as recorded)"
        )));
    }
    if !(from_s.is_finite() && from_s >= 0.0) {
        return Err(value_error(format!(
            "`from_s` is {from_s}: seconds from the recording's start, >= 0"
        )));
    }
    let skip = rows_before(data, &ident.urdf, from_s)?;
    let columns = conditioned_columns(py, data, "data", &ident.urdf, filter_hz)?;
    let samples = columns.samples();
    if skip >= samples.len() {
        return Err(value_error(format!(
            "`from_s` {from_s} leaves no sample of `data`"
        )));
    }
    let samples = samples.slice(skip, samples.len());
    let payload = py
        .detach(|| rust_identify_payload(&base, &samples))
        .map_err(|e| value_error(e.to_string()))?;
    Ok(PyPayload { payload })
}

/// The rows of `data` less than `from_s` seconds after its first.
fn rows_before(
    data: &Bound<'_, PyAny>,
    model: &admittance_dynamics::Model,
    from_s: f64,
) -> PyResult<usize> {
    if from_s == 0.0 {
        return Ok(0);
    }
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let t = match crate::free_motion::data_arg(data, "data", model.nq(), Some(&joints))? {
        crate::free_motion::DataArg::Csv(path) => crate::free_motion::load_csv(data.py(), &path)?.t,
        crate::free_motion::DataArg::Arrays(d) => d.t,
    };
    let start = t.first().copied().unwrap_or(0.0);
    Ok(t.iter().take_while(|x| **x < start + from_s).count())
}
