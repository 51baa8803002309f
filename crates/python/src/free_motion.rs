//! Free-motion data as Python gives it (a CSV path, or a dict of arrays), checked against
//! the arm and turned into the training arrays `[q, q', q'']` and targets that the
//! network and the identification are fitted on.

use std::path::PathBuf;

use admittance_dynamics::Identification;
use admittance_scenario::FreeMotionData;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{column, free_motion_error, rows, value_error};

/// Free-motion data as given: a CSV file (read later, without the GIL) or arrays.
pub(crate) enum DataArg {
    Csv(PathBuf),
    Arrays(FreeMotionData),
}

/// The signals of a data dict: `t` `(N,)` and `q`, `qdot`, `qddot`, `tau` as `(N, n)`
/// arrays, or the CSV column names (`q.JOINT`, ...) as `(N,)` arrays; `qdot` or `qddot`
/// left out is taken by differences (a `UserWarning` says so).
fn dict_data(
    d: &Bound<'_, PyDict>,
    arg: &str,
    n: usize,
    joints: Option<&[String]>,
) -> PyResult<FreeMotionData> {
    let t_obj = d.get_item("t")?.ok_or_else(|| {
        value_error(format!(
            "`{arg}` has no key 't' (the sample times, shape (N,))"
        ))
    })?;
    let t = column(&t_obj, &format!("{arg}['t']"), None)?;
    let rows_n = t.len();
    if rows_n == 0 {
        return Err(value_error(format!("`{arg}` has no samples")));
    }
    if let Some((k, v)) = crate::convert::first_non_finite(&t) {
        return Err(value_error(format!(
            "`{arg}['t']` row {k} is {v}; give finite values"
        )));
    }
    for (k, w) in t.windows(2).enumerate() {
        if w[1] <= w[0] {
            return Err(value_error(format!(
                "`{arg}['t']` does not increase strictly at row {}: {} after {}",
                k + 1,
                w[1],
                w[0]
            )));
        }
    }
    let mut signals: Vec<Vec<f64>> = Vec::with_capacity(4);
    let mut derived = Vec::new();
    for sig in ["q", "qdot", "qddot", "tau"] {
        // A derivative left out altogether (no array, no column of any joint) is taken by
        // differences, as the CSV loader does.
        let named = |j: &String| d.contains(format!("{sig}.{j}")).unwrap_or(false);
        if matches!(sig, "qdot" | "qddot")
            && !d.contains(sig)?
            && !joints.is_some_and(|j| j.iter().any(named))
        {
            derived.push(sig.to_string());
            signals.push(vec![0.0; rows_n * n]);
            continue;
        }
        let values = if let Some(obj) = d.get_item(sig)? {
            let name = format!("{arg}['{sig}']");
            if n == 1 {
                if let Ok(v) = column(&obj, &name, Some(rows_n)) {
                    v
                } else {
                    checked_rows(&obj, &name, rows_n, n)?
                }
            } else {
                checked_rows(&obj, &name, rows_n, n)?
            }
        } else {
            let Some(joints) = joints else {
                return Err(value_error(format!(
                    "`{arg}` has no key '{sig}' (an (N, {n}) array; per-joint columns '{sig}.JOINT' need the joint names, which a loaded network does not know)"
                )));
            };
            let mut cols = Vec::with_capacity(n);
            for j in joints {
                let key = format!("{sig}.{j}");
                let obj = d.get_item(&key)?.ok_or_else(|| {
                    value_error(format!(
                        "`{arg}` has neither '{sig}' (an (N, {n}) array) nor the column '{key}'"
                    ))
                })?;
                cols.push(column(&obj, &format!("{arg}['{key}']"), Some(rows_n))?);
            }
            (0..rows_n)
                .flat_map(|r| cols.iter().map(move |c| c[r]))
                .collect()
        };
        if let Some((k, v)) = crate::convert::first_non_finite(&values) {
            return Err(value_error(format!(
                "`{arg}`: '{sig}' row {}, joint {} is {v}; give finite values",
                k / n,
                k % n
            )));
        }
        // The bound of the command line's CSV files: no joint signal in SI units comes near
        // it, and beyond it the sums of squares of a fit overflow.
        let limit = admittance_learning::broad::MAX_ABS_DATA_VALUE;
        if let Some(k) = values.iter().position(|v| v.abs() > limit) {
            return Err(value_error(format!(
                "`{arg}`: '{sig}' row {}, joint {} is {:e}, beyond +-{limit:e}; give SI values (rad, rad/s, rad/s^2, N m)",
                k / n,
                k % n,
                values[k]
            )));
        }
        signals.push(values);
    }
    let tau = signals.pop().unwrap_or_default();
    let qddot = signals.pop().unwrap_or_default();
    let qdot = signals.pop().unwrap_or_default();
    let q = signals.pop().unwrap_or_default();
    let mut data = FreeMotionData {
        joints: joints
            .map(<[String]>::to_vec)
            .unwrap_or_else(|| (0..n).map(|i| format!("joint{i}")).collect()),
        t,
        q,
        qdot,
        qddot,
        tau,
        derived,
        unwrapped: Vec::new(),
    };
    data.unwrap_turns();
    data.check_velocities(&format!("`{arg}`"))
        .map_err(|e| value_error(e.to_string()))?;
    if !data.derived.is_empty() {
        data.take_differences();
        if data.is_empty() {
            return Err(value_error(format!(
                "`{arg}` has no {} and too few rows to take them by differences (3 at least)",
                data.derived.join(" or ")
            )));
        }
        warn(
            d.py(),
            &format!(
                "`{arg}`: no {}: {}",
                data.derived.join(" and "),
                admittance_scenario::DERIVED_NOTE
            ),
        )?;
    }
    Ok(data)
}

fn checked_rows(obj: &Bound<'_, PyAny>, name: &str, rows_n: usize, n: usize) -> PyResult<Vec<f64>> {
    let (v, r, _) = rows(obj, name, n, false)?;
    if r != rows_n {
        return Err(value_error(format!(
            "`{name}` must have shape ({rows_n}, {n}) (one row per sample of 't'), got {r} rows"
        )));
    }
    Ok(v)
}

pub(crate) fn data_arg(
    obj: &Bound<'_, PyAny>,
    arg: &str,
    n: usize,
    joints: Option<&[String]>,
) -> PyResult<DataArg> {
    if let Ok(d) = obj.cast::<PyDict>() {
        let data = dict_data(d, arg, n, joints)?;
        for warning in [data.implausible_speed(), data.unwrapped_note()]
            .into_iter()
            .flatten()
        {
            warn(obj.py(), &format!("`{arg}`: {warning}"))?;
        }
        return Ok(DataArg::Arrays(data));
    }
    match obj.extract::<PathBuf>() {
        Ok(p) => {
            // Said here, with the GIL: the file itself is read later, often without it.
            let left_out = FreeMotionData::derivatives_left_out(&p, joints);
            if !left_out.is_empty() {
                warn(
                    obj.py(),
                    &format!(
                        "{}: no {} columns: {}",
                        p.display(),
                        left_out.join(" and "),
                        admittance_scenario::DERIVED_NOTE
                    ),
                )?;
            }
            Ok(DataArg::Csv(p))
        }
        Err(_) => Err(PyTypeError::new_err(format!(
            "`{arg}` must be the path of a free-motion CSV file or a dict of arrays (t, q, qdot, qddot, tau)"
        ))),
    }
}

/// Reads the data (CSV files here, without the GIL), checks its joints, and forms the rows
/// `[q, qdot, qddot]` and targets (`tau`, or `tau - RNEA_nominal` for a hybrid residual).
pub(crate) fn training_arrays(
    data: DataArg,
    arg: &str,
    n: usize,
    joints: Option<&[String]>,
    input_filter_hz: f64,
    nominal: Option<&Identification>,
) -> PyResult<(Vec<f64>, Vec<f64>, usize)> {
    let (data, source) = match data {
        DataArg::Csv(path) => (
            FreeMotionData::load(&path).map_err(free_motion_error)?,
            path.display().to_string(),
        ),
        DataArg::Arrays(d) => (d, format!("`{arg}`")),
    };
    let names_differ = joints.is_some_and(|j| data.joints != j);
    if data.dof() != n || names_differ {
        return Err(value_error(format!(
            "{source}: joints [{}] are not the arm's [{}] (chain order)",
            data.joints.join(", "),
            joints
                .map(|j| j.join(", "))
                .unwrap_or_else(|| format!("{n} joints"))
        )));
    }
    if !(input_filter_hz.is_finite() && input_filter_hz >= 0.0) {
        return Err(value_error(format!(
            "`input_filter_hz` is {input_filter_hz}, must be >= 0 (0: the columns as recorded)"
        )));
    }
    let (x, mut y) = admittance_scenario::observer_training_arrays(&data, input_filter_hz)
        .map_err(|e| {
            value_error(format!(
                "`input_filter_hz` {input_filter_hz} with the data of {source}: {e}"
            ))
        })?;
    if let Some(nominal) = nominal {
        // What the nominal model (a URDF model, or an identification with its joint terms)
        // misses: the hybrid observer's residual network.
        nominal
            .subtract_from(&x, &mut y)
            .map_err(|e| value_error(format!("`nominal`: {e}")))?;
    }
    Ok((x, y, data.len()))
}

/// Without a separate validation recording the settings are chosen on stretches of the
/// data itself; when its motion repeats those stretches are motion the fit has seen. The
/// period in samples of the joint angles `q` (row-major, `n` joints), if any, looking as far
/// as a cross-validation over `folds` stretches would hold out.
pub(crate) fn repeat_period_of_positions(q: &[f64], n: usize, folds: usize) -> Option<usize> {
    let rows = q.len() / n.max(1);
    admittance_learning::broad::repeat_period(q, n, rows - rows / folds.max(2))
}

/// [`repeat_period_of_positions`] of the training rows `x` (`[q, qdot, qddot]`).
pub(crate) fn repeat_period_of_rows(x: &[f64], n: usize, folds: usize) -> Option<usize> {
    let q: Vec<f64> = x
        .chunks_exact(3 * n)
        .flat_map(|r| r[..n].iter().copied())
        .collect();
    repeat_period_of_positions(&q, n, folds)
}

/// Reads a free-motion CSV; warns (Python `UserWarning`) when its rows come too slowly for a
/// time in seconds (`FreeMotionData::unlikely_rate`). Derivatives it leaves out were said
/// when the argument was read ([`data_arg`]).
pub(crate) fn load_csv(py: Python<'_>, path: &std::path::Path) -> PyResult<FreeMotionData> {
    let data = FreeMotionData::load(path).map_err(free_motion_error)?;
    for warning in [
        data.unlikely_rate(),
        data.implausible_speed(),
        data.unwrapped_note(),
    ]
    .into_iter()
    .flatten()
    {
        warn(py, &format!("{}: {warning}", path.display()))?;
    }
    Ok(data)
}

/// A Python `UserWarning` with `message`.
pub(crate) fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let message = std::ffi::CString::new(message).unwrap_or_default();
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyUserWarning>(),
        &message,
        1,
    )
}

/// Warns (Python `UserWarning`) when `arg`'s time column has gaps, which the identification
/// interpolates onto an even grid before the fixed-rate conditioning.
pub(crate) fn warn_gaps(py: Python<'_>, arg: &str, data: &FreeMotionData) -> PyResult<()> {
    let Some((_, found)) = admittance_scenario::evenly_sampled(data) else {
        return Ok(());
    };
    let message =
        std::ffi::CString::new(format!("`{arg}`: {}", found.describe())).unwrap_or_default();
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyUserWarning>(),
        &message,
        1,
    )
}

/// Warns (Python `UserWarning`) that `arg`'s motion repeats every `period` samples.
pub(crate) fn warn_repeating(py: Python<'_>, arg: &str, period: usize) -> PyResult<()> {
    let message = std::ffi::CString::new(format!(
        "`{arg}`: the motion repeats every {period} samples, so the held-out stretches are motion \
         the fit has seen and the expected error is optimistic; record other motion (e.g. \
         adm.excitation(m, duration, seed=2)) and pass it as `validation=`"
    ))
    .unwrap_or_default();
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyUserWarning>(),
        &message,
        1,
    )
}
