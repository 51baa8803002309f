//! The rows of `train` and `grow`: the free-motion file read for the arm's joints, split
//! into training and held-out rows, conditioned as at run time, and the network's target
//! (the torque, or the nominal model's residual).

use std::path::Path;

use admittance_dynamics::{Identification, Model};
use admittance_learning::broad::{BroadError, Dataset};
use admittance_scenario::{FreeMotionData, FreeMotionError};

use super::args::learn_error;
use crate::CliError;

/// The joints named by the `q.*` columns of the file's header (for messages).
fn file_joints(path: &Path) -> Option<Vec<String>> {
    use std::io::BufRead;
    let file = admittance_files::open_regular(path, u64::MAX).ok()?;
    let header = std::io::BufReader::new(file)
        .lines()
        .map_while(Result::ok)
        .find(|l| !l.trim().is_empty())?;
    Some(
        header
            .split(',')
            .filter_map(|c| c.trim().strip_prefix("q."))
            .map(String::from)
            .collect(),
    )
}

/// Reads the file for `joints` (chain order; `None`: the file's `q.*` order). A missing
/// joint column also lists the file's joints, as the arm's and the data's usually differ
/// as a whole.
pub fn load(path: &Path, joints: Option<&[String]>) -> Result<FreeMotionData, CliError> {
    let result = match joints {
        Some(j) => FreeMotionData::load_joints(path, j),
        None => FreeMotionData::load(path),
    };
    if let Ok(data) = &result {
        for warning in [data.unlikely_rate(), data.implausible_speed()]
            .into_iter()
            .flatten()
        {
            eprintln!("admittance: warning: {}: {warning}", path.display());
        }
        if let Some(note) = data.unwrapped_note() {
            eprintln!("admittance: note: {}: {note}", path.display());
        }
        if !data.derived.is_empty() {
            eprintln!(
                "admittance: note: {}: no {} columns: {}",
                path.display(),
                data.derived.join(" and "),
                admittance_scenario::DERIVED_NOTE
            );
        }
    }
    result.map_err(|e| {
        let mut message = e.to_string();
        if let (FreeMotionError::MissingColumn { column, .. }, Some(j)) = (&e, joints) {
            if column != "t" {
                if let Some(found) = file_joints(path) {
                    message.push_str(&format!(
                        "; the file's joints are [{}], the arm's [{}]",
                        found.join(", "),
                        j.join(", ")
                    ));
                }
            }
        }
        CliError::input(message)
    })
}

/// Training rows: all but the last `fraction` (none held out without a fraction).
pub fn training_rows(
    path: &Path,
    data: &FreeMotionData,
    fraction: Option<f64>,
) -> Result<usize, CliError> {
    let Some(fraction) = fraction else {
        return Ok(data.len());
    };
    let rows = ((data.len() as f64) * (1.0 - fraction)).floor() as usize;
    if rows < 2 || rows >= data.len() {
        return Err(CliError::input(format!(
            "{}: {} rows are too few to hold out {fraction} of them for validation",
            path.display(),
            data.len()
        )));
    }
    Ok(rows)
}

/// Inputs `[q, qdot, qddot]` and targets (row-major), through the input conditioning
/// when `input_filter_hz > 0`; with `nominal`, the target is `tau - RNEA_nominal`.
pub fn arrays(
    path: &Path,
    data: &FreeMotionData,
    input_filter_hz: f64,
    nominal: Option<&Model>,
) -> Result<(Vec<f64>, Vec<f64>), CliError> {
    let (x, mut y) =
        admittance_scenario::observer_training_arrays(data, input_filter_hz).map_err(|e| {
            CliError::usage(format!(
                "--input-filter-hz {input_filter_hz} with the data of {}: {e}",
                path.display()
            ))
        })?;
    if let Some(model) = nominal {
        // A URDF model is an identification without joint terms: one residual rule.
        Identification::from_model(model.clone())
            .subtract_from(&x, &mut y)
            .map_err(|e| CliError::input(format!("nominal model: {e}")))?;
    }
    Ok((x, y))
}

/// Replaces the targets `y` by what the identified model does not explain,
/// `tau - ident.predict(q, qdot, qddot)`.
pub fn subtract_identified(
    ident: &Identification,
    x: &[f64],
    y: &mut [f64],
) -> Result<(), CliError> {
    ident
        .subtract_from(x, y)
        .map_err(|e| CliError::input(format!("--nominal: {e}")))
}

/// The training and held-out data sets of rows `..train_rows` and `train_rows..`
/// (`None` when nothing is held out). A value that is not finite or beyond the limit
/// (after the conditioning, which differentiates) names the data row and the column.
pub fn datasets<'a>(
    path: &Path,
    data: &FreeMotionData,
    (x, y): (&'a [f64], &'a [f64]),
    train_rows: usize,
    input_filter_hz: f64,
) -> Result<(Dataset<'a>, Option<Dataset<'a>>), CliError> {
    let n = data.dof();
    let locate = |e: BroadError, offset: usize| -> CliError {
        let (row, column, what) = match &e {
            BroadError::NonFinite {
                row, column, what, ..
            }
            | BroadError::OutOfRange {
                row, column, what, ..
            } => (*row, *column, *what),
            _ => return learn_error(e),
        };
        let name = if what == "inputs" {
            let signal = ["q", "qdot", "qddot"][(column / n).min(2)];
            format!("{signal}.{}", data.joints[column % n])
        } else {
            format!("target of {}", data.joints[column % n])
        };
        let via = if input_filter_hz > 0.0 {
            format!(" after the input conditioning (--input-filter-hz {input_filter_hz})")
        } else {
            String::new()
        };
        CliError::input(format!(
            "{}: data row {} (t = {}), column `{name}`{via}: {e}",
            path.display(),
            offset + row + 1,
            data.t[offset + row]
        ))
    };
    let train = Dataset::new(&x[..train_rows * 3 * n], &y[..train_rows * n], 3 * n, n)
        .map_err(|e| locate(e, 0))?;
    let held_out = if train_rows < data.len() {
        Some(
            Dataset::new(&x[train_rows * 3 * n..], &y[train_rows * n..], 3 * n, n)
                .map_err(|e| locate(e, train_rows))?,
        )
    } else {
        None
    };
    Ok((train, held_out))
}

/// Without a separate validation recording the settings are chosen on stretches of `data`
/// itself; when its motion repeats (an excitation's base period) those stretches are motion
/// the fit has seen. Says so on stderr and returns the period (s), or `None`.
pub fn warn_if_repeating(
    path: &Path,
    data: &FreeMotionData,
    rows: usize,
    folds: usize,
) -> Option<f64> {
    let n = data.joints.len();
    let rows = rows.min(data.t.len());
    if rows < 2 || n == 0 {
        return None;
    }
    let dt = (data.t[rows - 1] - data.t[0]) / (rows - 1) as f64;
    let max_lag = rows - rows / folds.max(2);
    let lag = admittance_learning::broad::repeat_period(&data.q[..rows * n], n, max_lag)?;
    let period = lag as f64 * dt;
    eprintln!(
        "admittance: warning: {}: the motion repeats every {period:.2} s, so the held-out stretches \
         are motion the fit has seen and the expected error is optimistic; record other motion \
         (e.g. `admittance excite ... --seed 2`) and give it as --validation",
        path.display()
    );
    Some(period)
}
