//! The metrics of `summary.json` as tables: units and windows from the contract
//! (`admittance_runfolder::metrics`), variants as columns in the scenario's order,
//! per-joint values one column per joint, rows that do not apply left out, and the checks
//! that must be zero said in one line when they are.

use admittance_runfolder::metrics::{self as m, Metric, Window};
use serde_json::Value;

use super::blocks::Block;
use crate::figures::short_name;
use crate::folder::RunFolder;
use crate::values::{fmt_value, is_zero};

/// Metrics that must be zero (or false): said in one line when they are everywhere.
const CHECKS: [&str; 11] = [
    m::DIVERGED,
    m::DIVERGED_AT,
    m::FAULTS,
    m::OBSERVER_FAULTS,
    m::STALE_MEASUREMENTS,
    m::TORQUE_LIMIT_VIOLATIONS,
    m::NONFINITE_TORQUES,
    m::REFERENCE_BOUND_VIOLATIONS,
    m::Q_LIMIT_VIOLATION_FRACTION,
    m::TORQUE_SATURATION_FRACTION,
    m::ESTIMATE_SATURATION_FRACTION,
];

/// How each check reads when it passed.
const PASSED: [(&str, &str); 10] = [
    (m::DIVERGED, "no divergence"),
    (m::FAULTS, "no controller faults"),
    (m::OBSERVER_FAULTS, "no observer faults"),
    (m::STALE_MEASUREMENTS, "no stale encoder readings"),
    (
        m::TORQUE_LIMIT_VIOLATIONS,
        "no command beyond the effort limit",
    ),
    (m::NONFINITE_TORQUES, "no non-finite command"),
    (
        m::REFERENCE_BOUND_VIOLATIONS,
        "q_r inside its saturation bound",
    ),
    (
        m::Q_LIMIT_VIOLATION_FRACTION,
        "every joint inside its limits",
    ),
    (
        m::TORQUE_SATURATION_FRACTION,
        "no command at the effort limit",
    ),
    (
        m::ESTIMATE_SATURATION_FRACTION,
        "no external-torque estimate beyond the effort limit",
    ),
];

/// Properties of the run rather than results: a table of their own.
const DETAILS: [&str; 10] = [
    m::STEPS,
    m::CONTROLLER_STEP_MEDIAN_US,
    m::NODES,
    m::WEIGHT_NORM_FINAL,
    m::WEIGHT_NORM_MAX,
    m::TRAIN_SECONDS,
    m::OBSERVER_NODES,
    m::OBSERVER_LAMBDA,
    m::OBSERVER_MODEL_CACHED,
    m::TRAINING_SAMPLES,
];

/// Results that are zero everywhere only when they do not apply (no contact, no
/// estimate, no deadzone): left out then.
const ZERO_MEANS_NOT_APPLICABLE: [&str; 8] = [
    m::EXTERNAL_TORQUE_RMSE,
    m::FALSE_TORQUE_RMS,
    m::DEADZONE_TIME_FRACTION,
    m::WRENCH_ESTIMATE_RMSE,
    m::WRENCH_ESTIMATE_NRMSE,
    m::FALSE_FORCE_RMS,
    m::CONTACT_FORCE_MAX,
    m::ADMITTANCE_ERROR_RMS,
];

/// Whether a metric is a fraction (shown in %).
fn is_fraction(name: &str) -> bool {
    name.ends_with("_fraction")
}

fn unit(name: &str, info: Option<&Metric>) -> String {
    if is_fraction(name) {
        "%".into()
    } else {
        info.map_or("", |i| i.unit).to_string()
    }
}

/// The window of a metric, in words with this run's numbers.
fn window(folder: &RunFolder, info: Option<&Metric>) -> String {
    match info.map(|i| i.window) {
        Some(Window::Evaluation) => format!("t ≥ {} s", folder.evaluation_start()),
        Some(Window::Phases) => format!("last {} s of each phase", folder.approximation_window()),
        Some(w) => w.describe().to_string(),
        None => String::new(),
    }
}

/// Metric names in the contract's order, then any the contract does not know.
fn names(folder: &RunFolder) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for v in &folder.variants {
        for k in v.metrics.keys() {
            if !seen.contains(k) {
                seen.push(k.clone());
            }
        }
    }
    let mut out: Vec<String> = m::ALL
        .iter()
        .map(|i| i.name.to_string())
        .filter(|n| seen.contains(n))
        .collect();
    out.extend(seen.into_iter().filter(|n| m::info(n).is_none()));
    out
}

/// Values of metric `name` per variant (`None`: absent).
fn values<'a>(folder: &'a RunFolder, name: &str) -> Vec<Option<&'a Value>> {
    folder
        .variants
        .iter()
        .map(|v| v.metrics.get(name))
        .collect()
}

/// Whether a row tells anything: some variant has a value that is not null, and for the
/// results that only apply sometimes, not zero everywhere.
fn applies(folder: &RunFolder, name: &str) -> bool {
    let vals = values(folder, name);
    if vals.iter().all(|v| v.is_none_or(Value::is_null)) {
        return false;
    }
    if name == m::DEADZONE_TIME_FRACTION && !folder.has_deadzone() {
        return false;
    }
    !(ZERO_MEANS_NOT_APPLICABLE.contains(&name) && vals.iter().flatten().all(|v| is_zero(v)))
}

/// Whether every check passed in every variant.
fn checks_passed(folder: &RunFolder, name: &str) -> bool {
    values(folder, name).iter().flatten().all(|v| is_zero(v))
}

fn header(folder: &RunFolder, first: &[&str]) -> Vec<String> {
    first
        .iter()
        .map(|s| s.to_string())
        .chain(folder.variants.iter().map(|v| format!("`{}`", v.name)))
        .collect()
}

/// Rows of scalar metrics (objects such as `nodes` one row per key).
fn scalar_rows(folder: &RunFolder, selected: &[&String], with_window: bool) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for name in selected {
        let info = m::info(name);
        let vals = values(folder, name);
        let percent = is_fraction(name);
        let keys: Vec<String> = vals
            .iter()
            .flatten()
            .filter_map(|v| v.as_object())
            .flat_map(|o| o.keys().cloned())
            .fold(Vec::new(), |mut acc, k| {
                if !acc.contains(&k) {
                    acc.push(k);
                }
                acc
            });
        let lead = |label: String| {
            let mut row = vec![label, unit(name, info)];
            if with_window {
                row.push(window(folder, info));
            }
            row
        };
        if keys.is_empty() {
            let mut row = lead(format!("`{name}`"));
            row.extend(
                vals.iter()
                    .map(|v| v.map_or(String::new(), |v| fmt_value(v, percent))),
            );
            rows.push(row);
        } else {
            for k in &keys {
                let mut row = lead(format!("`{name}` ({k})"));
                row.extend(vals.iter().map(|v| {
                    v.and_then(|v| v.get(k))
                        .map_or(String::new(), |x| fmt_value(x, percent))
                }));
                rows.push(row);
            }
        }
    }
    rows
}

/// Rows of per-joint metrics: one row per (metric, variant), one column per joint.
fn joint_rows(folder: &RunFolder, selected: &[&String]) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for name in selected {
        let info = m::info(name);
        let percent = is_fraction(name);
        // A joint on which such a metric is zero in every variant has nothing to show
        // (no deadzone, no contact there).
        let blank: Vec<bool> = (0..folder.joints.len())
            .map(|k| {
                ZERO_MEANS_NOT_APPLICABLE.contains(&name.as_str())
                    && folder.variants.iter().all(|v| {
                        v.metrics
                            .get(name.as_str())
                            .and_then(|l| l.get(k))
                            .is_none_or(is_zero)
                    })
            })
            .collect();
        let mut first = true;
        for v in &folder.variants {
            let Some(list) = v.metrics.get(name.as_str()).and_then(Value::as_array) else {
                continue;
            };
            let label = if first {
                let u = unit(name, info);
                let w = window(folder, info);
                let parts: Vec<&str> = [u.as_str(), w.as_str()]
                    .into_iter()
                    .filter(|s| !s.is_empty())
                    .collect();
                format!("`{name}` ({})", parts.join(", "))
            } else {
                String::new()
            };
            first = false;
            let mut row = vec![label, format!("`{}`", v.name)];
            row.extend((0..folder.joints.len()).map(|k| match list.get(k) {
                _ if blank[k] => "–".to_string(),
                Some(x) => fmt_value(x, percent),
                None => String::new(),
            }));
            rows.push(row);
        }
    }
    rows
}

fn is_per_joint(folder: &RunFolder, name: &str) -> bool {
    m::info(name).map_or_else(
        || values(folder, name).iter().flatten().any(|v| v.is_array()),
        |i| i.per_joint,
    )
}

/// The metrics section: checks, results, per-joint results, run details, definitions.
pub fn section(folder: &RunFolder) -> Vec<Block<'static>> {
    let mut out = vec![
        Block::Heading("Metrics".into()),
        Block::Paragraph(format!(
            "From `summary.json`, variants in the scenario's order. Windows: `t ≥ {} s` is the evaluation window; \"whole run\" counts every control step; \"in contact\" / \"without contact\" are the samples of the evaluation window where the true external torque is / is not zero. Units and definitions: docs/outputs.md and the list below.",
            folder.evaluation_start()
        )),
    ];
    let all = names(folder);
    let passed: Vec<&str> = PASSED
        .iter()
        .filter(|(name, _)| all.iter().any(|n| n == name) && checks_passed(folder, name))
        .filter(|(name, _)| *name != m::REFERENCE_BOUND_VIOLATIONS || folder.has_saturation())
        .map(|(_, text)| *text)
        .collect();
    if !passed.is_empty() {
        out.push(Block::Paragraph(format!(
            "**Checks passed in every variant** (whole run): {}.",
            passed.join(", ")
        )));
    }
    let shown: Vec<&String> = all
        .iter()
        .filter(|n| applies(folder, n))
        .filter(|n| !CHECKS.contains(&n.as_str()) || !checks_passed(folder, n))
        .collect();
    let results: Vec<&String> = shown
        .iter()
        .copied()
        .filter(|n| !DETAILS.contains(&n.as_str()) && !is_per_joint(folder, n))
        .collect();
    let joint_metrics: Vec<&String> = shown
        .iter()
        .copied()
        .filter(|n| !DETAILS.contains(&n.as_str()) && is_per_joint(folder, n))
        .collect();
    let details: Vec<&String> = shown
        .iter()
        .copied()
        .filter(|n| DETAILS.contains(&n.as_str()))
        .collect();
    if !results.is_empty() {
        out.push(Block::Table {
            header: header(folder, &["metric", "unit", "window"]),
            rows: scalar_rows(folder, &results, true),
        });
    }
    if !joint_metrics.is_empty() {
        out.push(Block::Subheading("Per joint".into()));
        out.push(Block::Table {
            header: ["metric (unit, window)", "variant"]
                .iter()
                .map(|s| s.to_string())
                .chain(folder.joints.iter().map(|j| short_name(j).to_string()))
                .collect(),
            rows: joint_rows(folder, &joint_metrics),
        });
    }
    if !details.is_empty() {
        out.push(Block::Subheading("Run details".into()));
        out.push(Block::Table {
            header: header(folder, &["quantity", "unit"]),
            rows: scalar_rows(folder, &details, false),
        });
    }
    let definitions: Vec<String> = shown
        .iter()
        .filter_map(|n| m::info(n).map(|i| format!("`{}`: {}", i.name, i.meaning)))
        .collect();
    if !definitions.is_empty() {
        out.push(Block::Subheading("Definitions".into()));
        out.push(Block::List(definitions));
    }
    out
}
