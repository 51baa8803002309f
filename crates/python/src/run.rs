//! `run`: the command line's `admittance run`, from Python. The same scenario loader, the same
//! `--out` rules (a folder the tool did not write is refused unless `force`), the same run
//! folder and report; the summary comes back as a dict.

use std::path::PathBuf;

use admittance_scenario::{run_scenario, RunError, RunOptions};
use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

use crate::config::from_py;

create_exception!(
    admittance,
    RunFailed,
    PyRuntimeError,
    "A scenario run that wrote its folder but failed: a variant diverged or a metric is not finite. `args[0]` says which; the attribute `summary` holds the summary dict and `out` the folder."
);

/// The overrides as the command line's `key=value` strings: a dict (values as Python
/// numbers, strings, lists...) or a list of `"key=value"` strings.
fn override_strings(overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(obj) = overrides.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut out = Vec::new();
        for (k, v) in d.iter() {
            let key: String = k
                .cast::<PyString>()
                .map_err(|_| {
                    PyTypeError::new_err(
                        "overrides: keys must be dotted strings, e.g. \"duration\"",
                    )
                })?
                .extract()?;
            if v.is_none() {
                return Err(PyValueError::new_err(format!(
                    "overrides: key `{key}`: None is not a value"
                )));
            }
            let value: toml::Value = from_py(&v, &format!("overrides: key `{key}`"))?;
            out.push(format!("{key}={value}"));
        }
        return Ok(out);
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        return obj
            .try_iter()?
            .map(|item| {
                item?.extract::<String>().map_err(|_| {
                    PyTypeError::new_err("overrides: a list must hold \"key=value\" strings")
                })
            })
            .collect();
    }
    Err(PyTypeError::new_err(
        "overrides must be a dict {\"key\": value} or a list of \"key=value\" strings",
    ))
}

/// Runs a scenario file as `admittance run SCENARIO --out OUT` does and returns
/// `summary.json` as a dict. `variant` runs one variant; `overrides` are the command line's
/// `--set` (a dict or `"key=value"` strings); `seed` overrides the sensor-noise seed;
/// `force` replaces a folder the tool did not write; `report` draws the figures and
/// reports (and `recording` the MCAP file). The GIL is released while it runs.
///
/// Raises `ValueError` for a bad scenario or override (file, line and key named),
/// `FileExistsError` when `out` may not be written, `OSError` when writing fails, and
/// `RunFailed` when the run folder was written but a variant failed.
#[pyfunction]
#[pyo3(signature = (scenario_path, out, variant=None, overrides=None, *, seed=None, force=false, report=true, recording=true))]
#[allow(clippy::too_many_arguments)]
pub fn run(
    py: Python<'_>,
    scenario_path: PathBuf,
    out: PathBuf,
    variant: Option<String>,
    overrides: Option<&Bound<'_, PyAny>>,
    seed: Option<u64>,
    force: bool,
    report: bool,
    recording: bool,
) -> PyResult<Py<PyAny>> {
    let overrides = override_strings(overrides)?;
    let report_options = admittance_report::Options {
        scenario_dir: scenario_path.parent().map(|p| {
            if p.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                p.to_path_buf()
            }
        }),
        recording,
        ..admittance_report::Options::default()
    };
    let result = py.detach(|| {
        let options = RunOptions {
            seed,
            ..RunOptions::default()
        };
        run_scenario(
            &scenario_path,
            &out,
            variant.as_deref(),
            &overrides,
            &options,
            force,
            |_, _, _| {},
            |partial| {
                if !report {
                    return Ok(());
                }
                admittance_report::generate(partial, &report_options)
                    .map(|_| ())
                    .map_err(|e| RunError::Finish(format!("writing the report: {e}")))
            },
        )
    });
    let summary = result.map_err(|e| match e {
        RunError::Scenario(s) => PyValueError::new_err(s.to_string()),
        RunError::Refused(message) => pyo3::exceptions::PyFileExistsError::new_err(message),
        RunError::Finish(message) => PyRuntimeError::new_err(message),
        io @ RunError::Io { .. } => PyOSError::new_err(io.to_string()),
    })?;
    let text = serde_json::to_string(&summary.json)
        .map_err(|e| PyRuntimeError::new_err(format!("summary: {e}")))?;
    let dict = py.import("json")?.call_method1("loads", (text,))?;
    if !summary.failures.is_empty() {
        let err = RunFailed::new_err(format!(
            "the run failed: {}; the run folder {} holds what ran",
            summary.failures.join("; "),
            summary.out_dir.display()
        ));
        let value = err.value(py);
        value.setattr("summary", &dict)?;
        value.setattr("out", summary.out_dir.clone())?;
        return Err(err);
    }
    Ok(dict.unbind())
}
