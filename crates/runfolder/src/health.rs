//! Whether a run is healthy: the rules every front end applies to a variant's metrics (the
//! command line's `admittance run`, the Python bindings, the MuJoCo co-simulation, the
//! report), each with a name, one threshold ([`HealthSettings`], one default each) and one
//! severity. docs/outputs.md, "Health", lists them for users.
//!
//! ```
//! use admittance_runfolder::health::{assess, HealthSettings, Severity};
//! let metrics = serde_json::json!({
//!     "diverged": false, "diverged_at": null, "ee_error_max": 0.084,
//!     "torque_saturation_fraction": [0.0, 0.2],
//! });
//! let joints = vec!["j1".to_string(), "j2".to_string()];
//! let verdicts = assess(metrics.as_object().unwrap(), &joints, &HealthSettings::default());
//! assert!(verdicts.iter().any(|v| v.rule == "hand_error" && v.severity == Severity::Failure));
//! assert!(verdicts.iter().any(|v| v.rule == "effort_saturation" && v.joint.as_deref() == Some("j2")));
//! ```
//!
//! The rules read only the metrics of `summary.json` (names in [`crate::metrics`]), so a
//! folder written by any plant is judged the same way. Divergence itself is detected while
//! the loop runs (`admittance_loop::HealthMonitor`), which sets `diverged` and `diverged_at`.

use serde::{Deserialize, Serialize};
use serde_json::{json, Map, Value};

use crate::metrics::{self as m, Window};

/// How bad a broken rule is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Worth knowing; the run still counts (exit 0).
    Warning,
    /// The run's numbers do not describe a working controller: `admittance run` exits non-zero.
    Failure,
}

impl Severity {
    /// `"warning"` or `"failure"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Warning => "warning",
            Severity::Failure => "failure",
        }
    }
}

/// The thresholds of the rules, one per rule that has one (`[health]` in a scenario file;
/// variants may override each key). Every default is documented in docs/outputs.md.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HealthSettings {
    // `inf` switches a rule off; JSON writes it as `null`, which reads back as `inf`.
    /// `hand_error` (failure): the largest hand position error `ee_error_max` (m) over the
    /// evaluation window. Default 0.04 m, the paper's bound for experiment A.
    #[serde(deserialize_with = "inf_if_null")]
    pub max_hand_error: f64,
    /// `effort_saturation` (failure): the largest share of control steps, per joint, with
    /// the command at the effort limit (`torque_saturation_fraction`). Default 0.01.
    #[serde(deserialize_with = "inf_if_null")]
    pub max_effort_saturation: f64,
    /// `estimate_beyond_effort` (failure): the largest share of control steps, per joint,
    /// with the external-torque estimate beyond the effort limit
    /// (`estimate_saturation_fraction`): how an estimate in a limit cycle through the
    /// admittance loop shows. Default 0.001.
    #[serde(deserialize_with = "inf_if_null")]
    pub max_estimate_saturation: f64,
    /// `stale_data` (warning): the largest number of control steps with a stale encoder
    /// reading (`stale_measurements`). Default 0.
    #[serde(deserialize_with = "inf_if_null")]
    pub max_stale_steps: f64,
    /// `joint_limits` (warning): the largest share of control steps, per joint, with the
    /// angle outside the joint's limits (`q_limit_violation_fraction`). Default 0.
    #[serde(deserialize_with = "inf_if_null")]
    pub max_joint_limit_fraction: f64,
}

fn inf_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

impl Default for HealthSettings {
    fn default() -> Self {
        Self {
            max_hand_error: 0.04,
            max_effort_saturation: 0.01,
            max_estimate_saturation: 0.001,
            max_stale_steps: 0.0,
            max_joint_limit_fraction: 0.0,
        }
    }
}

impl HealthSettings {
    /// Each threshold's key and value, for messages and checks.
    pub fn thresholds(&self) -> [(&'static str, f64); 5] {
        [
            ("max_hand_error", self.max_hand_error),
            ("max_effort_saturation", self.max_effort_saturation),
            ("max_estimate_saturation", self.max_estimate_saturation),
            ("max_stale_steps", self.max_stale_steps),
            ("max_joint_limit_fraction", self.max_joint_limit_fraction),
        ]
    }

    /// The thresholds that are not numbers `>= 0` (`+inf` switches a rule off), as
    /// `(key, problem)`.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        self.thresholds()
            .into_iter()
            // NaN is not >= 0 either.
            .filter(|(_, v)| v.partial_cmp(&0.0).is_none_or(|o| o.is_lt()))
            .map(|(k, v)| {
                (
                    k,
                    format!("is {v}, must be >= 0 (inf switches the rule off)"),
                )
            })
            .collect()
    }
}

/// One rule: its name, severity, the setting that holds its threshold (if any) and what it
/// checks.
#[derive(Clone, Copy, Debug)]
pub struct Rule {
    /// The name verdicts carry.
    pub name: &'static str,
    /// Its severity.
    pub severity: Severity,
    /// The [`HealthSettings`] key of its threshold (`""`: none, any occurrence breaks it).
    pub setting: &'static str,
    /// One line for users.
    pub meaning: &'static str,
}

/// Every rule, in the order verdicts are listed.
pub const RULES: &[Rule] = &[
    Rule { name: "divergence", severity: Severity::Failure, setting: "", meaning: "the plant's state or the estimate became non-finite or left physical bounds; the variant stopped (`diverged`)" },
    Rule { name: "nonfinite_metric", severity: Severity::Failure, setting: "", meaning: "a metric is null where a number is expected" },
    Rule { name: "command_limits", severity: Severity::Failure, setting: "", meaning: "commands beyond the effort limit or not finite (`torque_limit_violations`, `nonfinite_torques`)" },
    Rule { name: "hand_error", severity: Severity::Failure, setting: "max_hand_error", meaning: "the hand left the reference by more than the scenario's bound (`ee_error_max`, m)" },
    Rule { name: "effort_saturation", severity: Severity::Failure, setting: "max_effort_saturation", meaning: "a joint's command sat at the effort limit for more than this share of the run (`torque_saturation_fraction`)" },
    Rule { name: "estimate_beyond_effort", severity: Severity::Failure, setting: "max_estimate_saturation", meaning: "a joint's external-torque estimate exceeded the effort limit for more than this share of the run: an estimate limit cycle (`estimate_saturation_fraction`)" },
    Rule { name: "stale_data", severity: Severity::Warning, setting: "max_stale_steps", meaning: "control steps with a frozen or dropped encoder reading (`stale_measurements`)" },
    Rule { name: "joint_limits", severity: Severity::Warning, setting: "max_joint_limit_fraction", meaning: "a joint spent part of the run outside its position limits (`q_limit_violation_fraction`)" },
    Rule { name: "controller_faults", severity: Severity::Warning, setting: "", meaning: "control steps on which the controller applied its safe hold (`faults`)" },
    Rule { name: "observer_faults", severity: Severity::Warning, setting: "", meaning: "observer updates that reported a fault (`observer_faults`)" },
    Rule { name: "reference_bound", severity: Severity::Warning, setting: "", meaning: "q_r left its saturation bound (`reference_bound_violations`)" },
];

/// The rule called `name`.
pub fn rule(name: &str) -> Option<&'static Rule> {
    RULES.iter().find(|r| r.name == name)
}

/// A broken rule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    /// The rule's name (one of [`RULES`]).
    pub rule: String,
    /// Its severity.
    pub severity: Severity,
    /// The joint it concerns, when per joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<String>,
    /// The metric's value that broke it.
    pub value: Option<f64>,
    /// The threshold (`None` for rules without one).
    pub threshold: Option<f64>,
    /// One sentence: what happened and what to change.
    pub message: String,
}

/// Whether `null` is a legitimate value of a metric: `diverged_at` without divergence, the
/// metrics of a window that can be empty (contact, no contact), the hand metrics that need
/// an oracle variant or a release.
pub fn may_be_null(name: &str) -> bool {
    name == m::DIVERGED_AT
        || name == m::HAND_COMPLIANCE_ERROR_RMS
        || name == m::HAND_DRIFT_AFTER_RELEASE
        || m::info(name).is_some_and(|i| matches!(i.window, Window::Contact | Window::NoContact))
}

fn finite(v: &Value) -> bool {
    match v {
        Value::Number(n) => n.as_f64().is_some_and(f64::is_finite),
        Value::Array(a) => a.iter().all(finite),
        Value::Object(o) => o.values().all(finite),
        Value::Null => false,
        _ => true,
    }
}

fn number(metrics: &Map<String, Value>, name: &str) -> Option<f64> {
    metrics.get(name).and_then(Value::as_f64)
}

fn pct(x: f64) -> String {
    format!("{:.2} %", 100.0 * x)
}

/// Judges one variant's metrics (a `summary.json` variant object) with `settings`; `joints`
/// are the joint names in chain order. Returns the broken rules, failures first, in the
/// order of [`RULES`]; an empty list is a healthy run. Metrics that are absent are not
/// judged (a plant that does not report them).
pub fn assess(
    metrics: &Map<String, Value>,
    joints: &[String],
    settings: &HealthSettings,
) -> Vec<Verdict> {
    let mut out = Vec::new();
    let verdict = |rule: &str,
                   joint: Option<&str>,
                   value: Option<f64>,
                   threshold: Option<f64>,
                   message: String| {
        let r = self::rule(rule).expect("a rule of RULES");
        Verdict {
            rule: rule.to_string(),
            severity: r.severity,
            joint: joint.map(str::to_string),
            value,
            threshold,
            message,
        }
    };
    let joint_name = |k: usize| {
        joints
            .get(k)
            .map_or_else(|| format!("joint {}", k + 1), Clone::clone)
    };

    if metrics.get(m::DIVERGED).and_then(Value::as_bool) == Some(true) {
        let at = number(metrics, m::DIVERGED_AT);
        out.push(verdict(
            "divergence",
            None,
            at,
            None,
            format!(
                "diverged at {}: the simulation stopped there; its metrics cover the run until then",
                at.map_or("an unknown time".into(), |t| format!("t = {t} s"))
            ),
        ));
    }
    let mut bad = Vec::new();
    for (name, value) in metrics {
        if may_be_null(name) || finite(value) {
            continue;
        }
        match value {
            Value::Array(a) => {
                for (k, x) in a.iter().enumerate() {
                    if !finite(x) {
                        bad.push(format!("`{name}` of {}", joint_name(k)));
                    }
                }
            }
            Value::Object(o) => {
                for (k, x) in o {
                    if !finite(x) {
                        bad.push(format!("`{name}` ({k})"));
                    }
                }
            }
            _ => bad.push(format!("`{name}`")),
        }
    }
    if !bad.is_empty() {
        out.push(verdict(
            "nonfinite_metric",
            None,
            None,
            None,
            format!(
                "metrics that are not finite (null in summary.json): {}",
                bad.join(", ")
            ),
        ));
    }
    let violations = number(metrics, m::TORQUE_LIMIT_VIOLATIONS).unwrap_or(0.0)
        + number(metrics, m::NONFINITE_TORQUES).unwrap_or(0.0);
    if violations > 0.0 {
        out.push(verdict(
            "command_limits",
            None,
            Some(violations),
            None,
            format!("{violations} commands beyond the effort limit or not finite (`torque_limit_violations`, `nonfinite_torques`): the controller's output stage is broken"),
        ));
    }
    if let Some(e) = number(metrics, m::EE_ERROR_MAX) {
        if e > settings.max_hand_error {
            let rms = number(metrics, m::EE_ERROR_RMS)
                .map_or(String::new(), |r| format!(" (rms {:.4} m)", r));
            out.push(verdict(
                "hand_error",
                None,
                Some(e),
                Some(settings.max_hand_error),
                format!(
                    "the hand left its reference by up to {e:.4} m{rms}, beyond health.max_hand_error = {} m: the arm does not track; check the gains against the arm (`admittance gains --urdf FILE`), or raise health.max_hand_error if the task allows it",
                    settings.max_hand_error
                ),
            ));
        }
    }
    let per_joint = |name: &str| -> Vec<(usize, f64)> {
        metrics
            .get(name)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .enumerate()
                    .filter_map(|(k, x)| x.as_f64().map(|x| (k, x)))
                    .collect()
            })
            .unwrap_or_default()
    };
    for (k, x) in per_joint(m::TORQUE_SATURATION_FRACTION) {
        if x > settings.max_effort_saturation {
            let j = joint_name(k);
            out.push(verdict(
                "effort_saturation",
                Some(&j),
                Some(x),
                Some(settings.max_effort_saturation),
                format!(
                    "{j} commanded at its effort limit {} of the run (health.max_effort_saturation = {}): the controller asks for more than the motor gives; lower its gains or slow the motion",
                    pct(x), settings.max_effort_saturation
                ),
            ));
        }
    }
    for (k, x) in per_joint(m::ESTIMATE_SATURATION_FRACTION) {
        if x > settings.max_estimate_saturation {
            let j = joint_name(k);
            out.push(verdict(
                "estimate_beyond_effort",
                Some(&j),
                Some(x),
                Some(settings.max_estimate_saturation),
                format!(
                    "the external-torque estimate of {j} exceeded the effort limit {} of the run (health.max_estimate_saturation = {}): the estimate is in a limit cycle through the admittance loop; slow the admittance (more damping) or the estimate's filter",
                    pct(x), settings.max_estimate_saturation
                ),
            ));
        }
    }
    if let Some(n) = number(metrics, m::STALE_MEASUREMENTS) {
        if n > settings.max_stale_steps {
            out.push(verdict(
                "stale_data",
                None,
                Some(n),
                Some(settings.max_stale_steps),
                format!("{n} control steps with a stale (frozen or dropped) encoder reading (health.max_stale_steps = {}): check the sensors", settings.max_stale_steps),
            ));
        }
    }
    for (k, x) in per_joint(m::Q_LIMIT_VIOLATION_FRACTION) {
        if x > settings.max_joint_limit_fraction {
            let j = joint_name(k);
            out.push(verdict(
                "joint_limits",
                Some(&j),
                Some(x),
                Some(settings.max_joint_limit_fraction),
                format!("{j} was outside its position limits {} of the run (health.max_joint_limit_fraction = {})", pct(x), settings.max_joint_limit_fraction),
            ));
        }
    }
    for (rule, metric, what) in [
        (
            "controller_faults",
            m::FAULTS,
            "control steps with a controller fault (safe hold applied)",
        ),
        (
            "observer_faults",
            m::OBSERVER_FAULTS,
            "observer updates that reported a fault",
        ),
        (
            "reference_bound",
            m::REFERENCE_BOUND_VIOLATIONS,
            "samples x joints with q_r outside its saturation bound",
        ),
    ] {
        if let Some(n) = number(metrics, metric).filter(|n| *n > 0.0) {
            out.push(verdict(
                rule,
                None,
                Some(n),
                None,
                format!("{n} {what} (`{metric}`)"),
            ));
        }
    }
    out.sort_by_key(|v| std::cmp::Reverse(v.severity));
    out
}

/// The judgement of one variant, as `summary.json` stores it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariantHealth {
    /// `"ok"`, `"warning"` or `"failure"`: the worst verdict.
    pub status: String,
    /// The thresholds it was judged with.
    pub settings: HealthSettings,
    /// The broken rules.
    pub verdicts: Vec<Verdict>,
}

impl VariantHealth {
    /// The judgement of `verdicts` made with `settings`.
    pub fn new(settings: HealthSettings, verdicts: Vec<Verdict>) -> Self {
        Self {
            status: status(&verdicts).to_string(),
            settings,
            verdicts,
        }
    }
}

/// `"ok"`, `"warning"` or `"failure"`: the worst of `verdicts`.
pub fn status(verdicts: &[Verdict]) -> &'static str {
    match verdicts.iter().map(|v| v.severity).max() {
        None => "ok",
        Some(s) => s.as_str(),
    }
}

/// The `health` object of `summary.json` ([`crate::summary::KEY_HEALTH`]):
/// `{"status": worst, "variants": {VARIANT: {"status", "settings", "verdicts"}}}`.
pub fn summary_value<'a>(
    variants: impl IntoIterator<Item = (&'a str, &'a VariantHealth)>,
) -> Value {
    let mut worst = "ok";
    let mut map = Map::new();
    for (name, h) in variants {
        if h.status == "failure" || (h.status == "warning" && worst == "ok") {
            worst = if h.status == "failure" {
                "failure"
            } else {
                "warning"
            };
        }
        map.insert(
            name.to_string(),
            serde_json::to_value(h).unwrap_or(Value::Null),
        );
    }
    json!({"status": worst, "variants": Value::Object(map)})
}

/// The verdicts of each variant recorded in a parsed `summary.json` (`None`: a summary
/// written before health was recorded, or not readable as such).
pub fn read(summary: &Value) -> Option<Vec<(String, VariantHealth)>> {
    let variants = summary
        .get(crate::summary::KEY_HEALTH)?
        .get("variants")?
        .as_object()?;
    variants
        .iter()
        .map(|(k, v)| Some((k.clone(), serde_json::from_value(v.clone()).ok()?)))
        .collect()
}

/// One console line per verdict: `failure: VARIANT: [joint] message (rule)`.
pub fn console_line(variant: &str, v: &Verdict) -> String {
    format!(
        "{}: `{variant}`: {} [{}]",
        v.severity.as_str(),
        v.message,
        v.rule
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joints() -> Vec<String> {
        vec!["a".into(), "b".into()]
    }

    fn healthy() -> Map<String, Value> {
        json!({
            "diverged": false, "diverged_at": null, "ee_error_max": 0.001, "ee_error_rms": 0.0005,
            "torque_saturation_fraction": [0.0, 0.0], "estimate_saturation_fraction": [0.0, 0.0],
            "q_limit_violation_fraction": [0.0, 0.0], "stale_measurements": 0, "faults": 0,
            "observer_faults": 0, "reference_bound_violations": 0, "torque_limit_violations": 0,
            "nonfinite_torques": 0, "external_torque_nrmse": null, "false_torque_rms": [0.1, null],
        })
        .as_object()
        .unwrap()
        .clone()
    }

    #[test]
    fn a_healthy_run_has_no_verdict() {
        assert!(assess(&healthy(), &joints(), &HealthSettings::default()).is_empty());
    }

    #[test]
    fn each_threshold_is_the_boundary() {
        let s = HealthSettings::default();
        let mut m = healthy();
        m.insert("ee_error_max".into(), json!(s.max_hand_error));
        assert!(
            assess(&m, &joints(), &s).is_empty(),
            "at the bound is inside"
        );
        m.insert("ee_error_max".into(), json!(s.max_hand_error * 1.001));
        let v = assess(&m, &joints(), &s);
        assert_eq!(v.len(), 1);
        assert_eq!(
            (v[0].rule.as_str(), v[0].severity),
            ("hand_error", Severity::Failure)
        );
        let mut m = healthy();
        m.insert("torque_saturation_fraction".into(), json!([0.0, 0.02]));
        m.insert("stale_measurements".into(), json!(3));
        let v = assess(&m, &joints(), &s);
        assert_eq!(
            v.iter().map(|v| v.rule.as_str()).collect::<Vec<_>>(),
            ["effort_saturation", "stale_data"]
        );
        assert_eq!(v[0].joint.as_deref(), Some("b"));
        assert_eq!(status(&v), "failure");
        let off = HealthSettings {
            max_effort_saturation: f64::INFINITY,
            ..s.clone()
        };
        assert_eq!(status(&assess(&m, &joints(), &off)), "warning");
    }

    #[test]
    fn divergence_and_nulls_are_failures() {
        let mut m = healthy();
        m.insert("diverged".into(), json!(true));
        m.insert("diverged_at".into(), json!(0.66));
        m.insert("tracking_rmse".into(), json!([0.1, null]));
        let v = assess(&m, &joints(), &HealthSettings::default());
        assert_eq!(v[0].rule, "divergence");
        assert!(
            v[1].message.contains("`tracking_rmse` of b"),
            "{}",
            v[1].message
        );
    }

    #[test]
    fn verdicts_round_trip_through_the_summary() {
        let mut m = healthy();
        m.insert("faults".into(), json!(2));
        let h = VariantHealth::new(
            HealthSettings::default(),
            assess(&m, &joints(), &HealthSettings::default()),
        );
        let summary = json!({ "health": summary_value([("x", &h)]) });
        assert_eq!(summary["health"]["status"], "warning");
        assert_eq!(read(&summary).unwrap(), vec![("x".to_string(), h)]);
        assert!(read(&json!({})).is_none());
    }

    #[test]
    fn every_rule_with_a_setting_names_a_real_one() {
        let keys: Vec<&str> = HealthSettings::default()
            .thresholds()
            .iter()
            .map(|(k, _)| *k)
            .collect();
        for r in RULES {
            assert!(
                r.setting.is_empty() || keys.contains(&r.setting),
                "{}",
                r.name
            );
        }
        assert!(
            HealthSettings {
                max_hand_error: -1.0,
                ..Default::default()
            }
            .problems()
            .len()
                == 1
        );
        assert!(
            HealthSettings {
                max_hand_error: f64::NAN,
                ..Default::default()
            }
            .problems()
            .len()
                == 1
        );
    }
}
