//! The warnings a report opens with: divergence, limits, saturation, faults, metrics that
//! are not finite, what the arm's description said when it was read, and samples the
//! figures could not draw. A folder without these metrics simply has no such warnings.

use admittance_runfolder::metrics::{self as m, Window};
use serde_json::Value;

use super::values::{fmt_num, fmt_percent, num, per_joint};
use crate::figures::short_name;
use crate::folder::{RunFolder, Variant};

/// Per-joint fractions of the run spent in a bad state, with what they mean.
const FRACTIONS: [(&str, &str); 3] = [
    (m::Q_LIMIT_VIOLATION_FRACTION, "outside their joint limits"),
    (
        m::TORQUE_SATURATION_FRACTION,
        "commanded at the effort limit",
    ),
    (
        m::ESTIMATE_SATURATION_FRACTION,
        "with the external-torque estimate beyond the effort limit",
    ),
];

/// Counts that must be zero, with what one of them is.
const COUNTS: [(&str, &str); 5] = [
    (
        m::FAULTS,
        "control steps with a controller fault (safe hold applied)",
    ),
    (m::OBSERVER_FAULTS, "observer updates that reported a fault"),
    (
        m::STALE_MEASUREMENTS,
        "control steps with a stale encoder reading (frozen or dropped)",
    ),
    (
        m::TORQUE_LIMIT_VIOLATIONS,
        "commands beyond the effort limit",
    ),
    (m::NONFINITE_TORQUES, "commands that were not finite"),
];

/// Whether `null` is a legitimate value of a metric (a window that can be empty).
pub fn may_be_null(name: &str) -> bool {
    name == m::DIVERGED_AT
        || m::info(name).is_none_or(|i| matches!(i.window, Window::Contact | Window::NoContact))
}

/// The metrics of a variant that are null where a number is expected (`name` or
/// `name[joint]`).
fn not_finite(folder: &RunFolder, v: &Variant) -> Vec<String> {
    let mut out = Vec::new();
    for (name, value) in &v.metrics {
        if may_be_null(name) {
            continue;
        }
        match value {
            Value::Null => out.push(format!("`{name}`")),
            Value::Array(a) => {
                for (k, x) in a.iter().enumerate() {
                    if x.is_null() {
                        let joint = folder.joints.get(k).map_or("?", |j| short_name(j));
                        out.push(format!("`{name}` of {joint}"));
                    }
                }
            }
            Value::Object(o) => {
                for (k, x) in o {
                    if x.is_null() {
                        out.push(format!("`{name}` ({k})"));
                    }
                }
            }
            _ => {}
        }
    }
    out
}

fn variant_warnings(folder: &RunFolder, v: &Variant, out: &mut Vec<String>) {
    let name = &v.name;
    if v.metrics.get(m::DIVERGED).and_then(Value::as_bool) == Some(true) {
        let at = num(v, m::DIVERGED_AT).map_or("an unknown time".to_string(), |t| {
            format!("t = {} s", fmt_num(t))
        });
        out.push(format!(
            "`{name}` **diverged** at {at}: the simulation stopped there, and its metrics and figures cover the run until then."
        ));
    }
    for (metric, what) in FRACTIONS {
        let Some(values) = per_joint(v, metric) else {
            continue;
        };
        let bad: Vec<String> = values
            .iter()
            .zip(&folder.joints)
            .filter_map(|(x, j)| {
                x.filter(|x| *x > 0.0)
                    .map(|x| format!("{} {}", short_name(j), fmt_percent(x)))
            })
            .collect();
        if !bad.is_empty() {
            out.push(format!(
                "`{name}`: joints {what} for part of the run: {} (`{metric}`, whole run).",
                bad.join(", ")
            ));
        }
    }
    for (metric, what) in COUNTS {
        if let Some(n) = num(v, metric).filter(|n| *n > 0.0) {
            out.push(format!("`{name}`: {} {what} (`{metric}`).", fmt_num(n)));
        }
    }
    if folder.has_saturation() {
        if let Some(n) = num(v, m::REFERENCE_BOUND_VIOLATIONS).filter(|n| *n > 0.0) {
            out.push(format!(
                "`{name}`: q_r left its saturation bound on {} samples × joints (`{}`).",
                fmt_num(n),
                m::REFERENCE_BOUND_VIOLATIONS
            ));
        }
    }
    let bad = not_finite(folder, v);
    if !bad.is_empty() {
        out.push(format!(
            "`{name}`: metrics that are not finite (null in summary.json): {}.",
            bad.join(", ")
        ));
    }
}

/// Every warning of the run, variants in the scenario's order; `figure_notes` are the
/// figures' notes on samples they could not draw (`(figure id, note)`).
pub fn warnings(folder: &RunFolder, figure_notes: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for v in &folder.variants {
        variant_warnings(folder, v, &mut out);
    }
    for w in &folder.warnings {
        out.push(format!("the arm's description: {w}"));
    }
    let mut ids: Vec<&str> = figure_notes.iter().map(|(id, _)| id.as_str()).collect();
    ids.dedup();
    for id in ids {
        let notes: Vec<&str> = figure_notes
            .iter()
            .filter(|(i, _)| i == id)
            .map(|(_, n)| n.as_str())
            .collect();
        out.push(format!(
            "Fig. {id} left out data it cannot draw: {}.",
            notes.join("; ")
        ));
    }
    out
}
