//! How a report opens: the experiment, the paper's claim, and this run's headline numbers
//! beside the paper's (with whether they agree where the paper gives a bound or a
//! direction). The paper's numbers are those of its text (Section V).

use admittance_runfolder::{columns, metrics as m, settings as rs};

use super::blocks::Block;
use crate::experiment::{deadzone_groups, DeadzoneGroup, Experiment};
use crate::figures::short_name;
use crate::folder::{RunFolder, Variant};
use crate::number::setting;
use crate::values::{fmt_num, num};

/// The metrics the warnings read; a summary without them could not be checked.
const CHECKED: [&str; 4] = [
    m::DIVERGED,
    m::Q_LIMIT_VIOLATION_FRACTION,
    m::TORQUE_SATURATION_FRACTION,
    m::ESTIMATE_SATURATION_FRACTION,
];

/// A headline row: quantity, the paper's value, this run's, whether they agree.
type Row = [String; 4];

fn row(quantity: &str, paper: &str, ours: String, agrees: &str) -> Row {
    [quantity.into(), paper.into(), ours, agrees.into()]
}

fn yes_no(ok: bool) -> &'static str {
    if ok {
        "yes"
    } else {
        "no"
    }
}

/// The value of a per-joint metric at joint `index`.
fn joint_value(v: &Variant, name: &str, index: usize) -> Option<f64> {
    crate::values::joint_metric(v, name, index)
}

/// `a / b = ×r` of the tracking RMSE of `joint` for two variants, and whether `a` is the
/// smaller.
fn rmse_ratio(folder: &RunFolder, a: &str, b: &str, joint: &str) -> Option<(String, bool)> {
    let k = folder.joints.iter().position(|j| j == joint)?;
    let (va, vb) = (folder.variant(a)?, folder.variant(b)?);
    let (x, y) = (
        joint_value(va, m::TRACKING_RMSE, k)?,
        joint_value(vb, m::TRACKING_RMSE, k)?,
    );
    Some((
        format!(
            "{} / {} rad = ×{:.2} (`{a}` / `{b}`)",
            fmt_num(x),
            fmt_num(y),
            x / y
        ),
        x < y,
    ))
}

/// One deadzone comparison's rows: the hand-error bound of the paper with what the other
/// controllers reach (a bound that every controller meets says nothing), and the
/// comparisons that tell them apart: the deadzone joint's tracking RMSE against the
/// uncompensated controller and against PD, and the hand error RMS of all three.
fn deadzone_rows(folder: &RunFolder, g: &DeadzoneGroup, first: bool, rows: &mut Vec<Row>) {
    let s = short_name(&g.joint);
    let band = g
        .with
        .as_deref()
        .or(g.without.as_deref())
        .and_then(|v| folder.deadzone(v, &g.joint))
        .map_or(String::new(), |(l, r)| {
            format!(", deadzone [{}, {}] N m", setting(l), setting(r))
        });
    let tag = if first {
        String::new()
    } else {
        format!(" (second deadzone{band}; not in the paper)")
    };
    fn value<'a>(
        folder: &RunFolder,
        name: &'a Option<String>,
        metric: &str,
    ) -> Option<(&'a str, f64)> {
        let n = name.as_deref()?;
        num(folder.variant(n)?, metric).map(|x| (n, x))
    }
    let with_max = value(folder, &g.with, m::EE_ERROR_MAX);
    let others: Vec<(&str, &str, f64)> = [("uncompensated", &g.without), ("PD", &g.pd)]
        .into_iter()
        .filter_map(|(what, n)| value(folder, n, m::EE_ERROR_MAX).map(|(n, x)| (what, n, x)))
        .collect();
    if let Some((n, x)) = with_max {
        let mut ours = format!("{} m (`{n}`)", fmt_num(x));
        for (what, name, y) in &others {
            ours.push_str(&format!("; {what} {} m (`{name}`)", fmt_num(*y)));
        }
        if x < 0.04 && !others.is_empty() && others.iter().all(|(_, _, y)| *y < 0.04) {
            ours.push_str(
                "; every controller is below it, so the bound does not tell them apart (the rows below do)",
            );
        }
        rows.push(row(
            &format!("hand position error with compensation, largest (t ≥ evaluation start){tag}"),
            if first { "below 0.04 m" } else { "–" },
            ours,
            yes_no(x < 0.04),
        ));
    }
    if let (Some(a), Some(b)) = (&g.with, &g.without) {
        if let Some((text, ok)) = rmse_ratio(folder, a, b, &g.joint) {
            rows.push(row(
                &format!("{s} tracking RMSE, compensated / uncompensated{tag}"),
                if first {
                    "smaller with compensation"
                } else {
                    "–"
                },
                format!("{text}{}", if first { band.as_str() } else { "" }),
                yes_no(ok),
            ));
        }
    }
    if let (Some(a), Some(b)) = (&g.with, &g.pd) {
        if let Some((text, ok)) = rmse_ratio(folder, a, b, &g.joint) {
            rows.push(row(
                &format!("{s} tracking RMSE, compensated / PD (its linear part alone){tag}"),
                "– (the learning should beat PD)",
                text,
                yes_no(ok),
            ));
        }
    }
    let rms: Vec<(&str, f64)> = [&g.with, &g.without, &g.pd]
        .into_iter()
        .filter_map(|n| value(folder, n, m::EE_ERROR_RMS))
        .collect();
    if let (Some(&(_, x)), true) = (rms.first(), g.with.is_some() && rms.len() > 1) {
        let lowest = rms[1..].iter().all(|(_, y)| x < *y);
        rows.push(row(
            &format!("hand position error RMS, compensated against the others{tag}"),
            "– (lowest with compensation)",
            rms.iter()
                .map(|(n, y)| format!("`{n}` {} m", fmt_num(*y)))
                .collect::<Vec<_>>()
                .join("; "),
            yes_no(lowest),
        ));
    }
}

fn deadzone(folder: &RunFolder) -> (String, Vec<Row>) {
    let groups = deadzone_groups(folder);
    let joint = groups
        .first()
        .map_or("s0".to_string(), |g| short_name(&g.joint).to_string());
    let claim = format!("With the neural network compensating the actuator deadzone, the joint with the deadzone ({joint}) tracks better than without compensation (Figs 9-11), and the hand follows its desired path with an error below 0.04 m (Figs 7-8).");
    let mut rows = Vec::new();
    for (k, g) in groups.iter().enumerate() {
        deadzone_rows(folder, g, k == 0, &mut rows);
    }
    (claim, rows)
}

/// Whether a variant's estimate is the true external torque (its settings; a folder without
/// them, like the co-simulation's, by the variant's name).
fn is_oracle(folder: &RunFolder, v: &Variant) -> bool {
    match &folder.settings {
        Some(_) => folder.variant_settings(&v.name).observer == rs::OBSERVER_ORACLE,
        None => {
            folder.variant_settings(&v.name).observer == rs::OBSERVER_ORACLE
                || v.name == rs::OBSERVER_ORACLE
        }
    }
}

/// The best estimate among the variants that are not the oracle, by `metric` (lower is
/// better), with the runner-up: `` `hybrid` 0.06400 (next `momentum` 0.2000, ×3.1) ``.
fn best_estimate(folder: &RunFolder, metric: &str) -> Option<String> {
    let mut ranked: Vec<(&str, f64)> = folder
        .variants
        .iter()
        .filter(|v| !is_oracle(folder, v))
        .filter_map(|v| {
            num(v, metric)
                .filter(|x| x.is_finite())
                .map(|x| (v.name.as_str(), x))
        })
        .collect();
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (name, x) = *ranked.first()?;
    let mut text = format!("`{name}` {}", fmt_num(x));
    if let Some(&(next, y)) = ranked.get(1) {
        text.push_str(&format!(
            " (next `{next}` {}, ×{:.1} larger)",
            fmt_num(y),
            y / x
        ));
    }
    Some(text)
}

/// `VARIANT value` for every variant that has the metric.
fn per_variant(folder: &RunFolder, name: &str, unit: &str) -> Option<String> {
    let parts: Vec<String> = folder
        .variants
        .iter()
        .filter_map(|v| num(v, name).map(|x| format!("`{}` {}{unit}", v.name, fmt_num(x))))
        .collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}

/// When something acts on the arm, from the run folder's own timing: the scenario's
/// environment windows, else where the true external torque is non-zero (the MuJoCo
/// co-simulation's push or wall) -- the spans the figures shade. `"8-22 s"`, to 0.1 s.
fn acting_window(folder: &RunFolder) -> Option<String> {
    let v = folder.variants.first()?;
    let spans = crate::figures::contact_spans(folder, v);
    let (from, to) = (spans.first()?.from, spans.last()?.to);
    let tenth = |x: f64| {
        let text = format!("{:.1}", (x * 10.0).round() / 10.0);
        text.strip_suffix(".0").map_or(text.clone(), str::to_string)
    };
    Some(format!("{}-{} s", tenth(from), tenth(to)))
}

fn admittance(folder: &RunFolder) -> (String, Vec<Row>) {
    let when = acting_window(folder).map_or(String::new(), |w| format!("{w}, "));
    let claim = format!("A network trained on free motion estimates the external torque without a force sensor (Figs 15, 17) well enough to drive the admittance model: the reference yields while the environment acts ({when}Figs 18-19), and the saturation keeps it inside its bound (Fig 20).");
    let mut rows = Vec::new();
    if let Some(text) = per_variant(folder, m::EXTERNAL_TORQUE_NRMSE, "") {
        rows.push(row(
            "external-torque estimate in contact, NRMSE (0 is exact)",
            "follows the true torque (Fig 17); no number",
            text,
            "–",
        ));
    }
    if let Some(text) = best_estimate(folder, m::EXTERNAL_TORQUE_NRMSE) {
        rows.push(row(
            "best estimate, the oracle aside (lowest NRMSE)",
            "–",
            text,
            "–",
        ));
    }
    let trained = folder.variant("learned").or_else(|| {
        folder
            .variants
            .iter()
            .find(|v| num(v, m::TRAIN_SECONDS).is_some())
    });
    if let Some(v) = trained {
        if let Some(s) = num(v, m::TRAIN_SECONDS) {
            let nodes = num(v, m::OBSERVER_NODES)
                .map_or(String::new(), |n| format!(", {} nodes", fmt_num(n)));
            let rows_used = num(v, m::TRAINING_SAMPLES)
                .map_or(String::new(), |n| format!(", {} rows", fmt_num(n)));
            let cached = v
                .metrics
                .get(m::OBSERVER_MODEL_CACHED)
                .and_then(serde_json::Value::as_bool)
                == Some(true);
            let when = if cached {
                "the fit that filled the cache, on the computer that ran it"
            } else {
                "on the computer that made this run"
            };
            rows.push(row(
                "time to train the observer's network",
                "5.088 s (1000 nodes, the authors' computer)",
                format!("{} s (`{}`{nodes}{rows_used}; {when})", fmt_num(s), v.name),
                "–",
            ));
        }
    }
    if folder.has_saturation() {
        let counts: Vec<(String, f64)> = folder
            .variants
            .iter()
            .filter_map(|v| num(v, m::REFERENCE_BOUND_VIOLATIONS).map(|n| (v.name.clone(), n)))
            .collect();
        if !counts.is_empty() {
            let bad: Vec<String> = counts
                .iter()
                .filter(|(_, n)| *n > 0.0)
                .map(|(v, n)| format!("`{v}` {}", fmt_num(*n)))
                .collect();
            let ours = if bad.is_empty() {
                "0 samples outside, every variant".to_string()
            } else {
                format!("samples × joints outside: {}", bad.join("; "))
            };
            rows.push(row(
                "q_r inside its saturation bound",
                "yes (Fig 20)",
                ours,
                yes_no(bad.is_empty()),
            ));
        }
    }
    (claim, rows)
}

fn dynamic_nodes(folder: &RunFolder) -> (String, Vec<Row>) {
    let claim = "Discarding the nodes whose centres are far from the trajectory costs little approximation accuracy (Fig 21), and adding nodes near the trajectory improves it (Fig 24); the weights converge (Figs 22-26).";
    let mut rows = Vec::new();
    let Some(v) = folder.variant("dynamic").or(folder.variants.first()) else {
        return (claim.into(), rows);
    };
    let initial = v
        .table
        .col(columns::NODES_F)
        .and_then(|c| c.first().copied());
    if let Some(d) = num(v, m::NODES_DISCARDED) {
        let of = initial.map_or(String::new(), |n| format!(" of {}", fmt_num(n)));
        rows.push(row(
            "nodes discarded",
            "208 of 512",
            format!("{}{of}", fmt_num(d)),
            "–",
        ));
    }
    let rmse = |name| num(v, name);
    if let (Some(full), Some(after)) = (
        rmse(m::APPROX_RMSE_FULL),
        rmse(m::APPROX_RMSE_AFTER_DISCARD),
    ) {
        let change = after / full - 1.0;
        rows.push(row(
            "approximation error after the discard against before (RMS of f - f_hat)",
            "\"affected little\"",
            format!(
                "{} against {} N m ({:+.1} %)",
                fmt_num(after),
                fmt_num(full),
                100.0 * change
            ),
            if change.abs() <= 0.1 {
                "yes (within 10 %)"
            } else {
                "no (over 10 %)"
            },
        ));
    }
    if let Some(n) = num(v, m::NODES_ADDED) {
        rows.push(row(
            "nodes added near the trajectory",
            "100",
            fmt_num(n),
            "–",
        ));
    }
    if let (Some(after), Some(grown)) = (
        rmse(m::APPROX_RMSE_AFTER_DISCARD),
        rmse(m::APPROX_RMSE_AFTER_GROWTH),
    ) {
        let change = grown / after - 1.0;
        rows.push(row(
            "approximation error after growth against after the discard",
            "better",
            format!(
                "{} against {} N m ({:+.1} %)",
                fmt_num(grown),
                fmt_num(after),
                100.0 * change
            ),
            yes_no(change < 0.0),
        ));
    }
    (claim.into(), rows)
}

/// The paper's motion range of the Baxter arm (Section V-B), joint order s0 .. w2.
const PAPER_BOX: [(f64, f64); 7] = [
    (-1.7, 1.7),
    (-2.14, 1.05),
    (-3.05, 3.05),
    (-0.15, 2.61),
    (-3.05, 3.05),
    (-1.57, 2.09),
    (-3.05, 3.05),
];

fn data_run(folder: &RunFolder, validation: bool) -> (String, Vec<Row>) {
    let claim = if validation {
        "Validation data for the learned observer: a trajectory like the training one with different amplitudes and periods, in the same joint box (Fig 14)."
    } else {
        "Training data for the learned observer: the arm moves freely, excited in the paper's joint box, recorded as the observer will see it (Fig 13)."
    };
    let mut rows = Vec::new();
    let table = folder
        .free_motion
        .first()
        .map(|(_, t)| t)
        .or(folder.variants.first().map(|v| &v.table));
    let Some(table) = table else {
        return (claim.into(), rows);
    };
    if let Some(end) = table.col(columns::TIME).and_then(|t| t.last()) {
        rows.push(row(
            "duration",
            if validation { "not given" } else { "450 s" },
            format!("{} s, {} samples", fmt_num(*end), table.rows()),
            "–",
        ));
    }
    if folder.joints.len() == PAPER_BOX.len() {
        let outside: Vec<String> = folder
            .joints
            .iter()
            .zip(PAPER_BOX)
            .filter_map(|(j, (lo, hi))| {
                let q = table.col(&columns::joint(columns::POSITION, j))?;
                let (a, b) = q
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    });
                (a < lo || b > hi)
                    .then(|| format!("{} [{}, {}]", short_name(j), fmt_num(a), fmt_num(b)))
            })
            .collect();
        let ours = if outside.is_empty() {
            "every joint inside".to_string()
        } else {
            format!("outside: {}", outside.join(", "))
        };
        rows.push(row(
            "joint angles inside the paper's motion range",
            "[-1.7, 1.7] × [-2.14, 1.05] × [-3.05, 3.05] × [-0.15, 2.61] × [-3.05, 3.05] × [-1.57, 2.09] × [-3.05, 3.05] rad",
            ours,
            yes_no(outside.is_empty()),
        ));
    }
    (claim.into(), rows)
}

fn hand_contact(folder: &RunFolder) -> (String, Vec<Row>) {
    let claim = "Task-space contact (not in the paper): the force on the hand estimated without a force sensor, J^+T tau_ext_hat, against the true contact force.";
    let mut rows = Vec::new();
    for (name, what, unit) in [
        (
            m::WRENCH_ESTIMATE_NRMSE,
            "hand-force estimate in contact, NRMSE",
            "",
        ),
        (
            m::FALSE_FORCE_RMS,
            "estimated hand force without contact, RMS",
            " N",
        ),
        (m::CONTACT_FORCE_MAX, "largest true contact force", " N"),
    ] {
        if let Some(text) = per_variant(folder, name, unit) {
            rows.push(row(what, "–", text, "–"));
        }
    }
    if let Some(text) = best_estimate(folder, m::WRENCH_ESTIMATE_NRMSE) {
        rows.push(row(
            "best hand-force estimate, the oracle aside (lowest NRMSE)",
            "–",
            text,
            "–",
        ));
    }
    // The force the wall reached against the oracle's: how far the admittance, driven by
    // the estimate, behaved as if it knew the true force.
    let oracle = folder
        .variants
        .iter()
        .find(|v| is_oracle(folder, v))
        .and_then(|v| num(v, m::CONTACT_FORCE_MAX).map(|x| (v.name.as_str(), x)))
        .filter(|(_, x)| *x > 0.0);
    if let Some((oracle_name, peak)) = oracle {
        let parts: Vec<String> = folder
            .variants
            .iter()
            .filter(|v| !is_oracle(folder, v))
            .filter_map(|v| {
                num(v, m::CONTACT_FORCE_MAX)
                    .map(|x| format!("`{}` {:+.1} %", v.name, 100.0 * (x / peak - 1.0)))
            })
            .collect();
        if !parts.is_empty() {
            rows.push(row(
                &format!(
                    "largest contact force against the oracle's ({} N, `{oracle_name}`)",
                    fmt_num(peak)
                ),
                "–",
                parts.join("; "),
                "–",
            ));
        }
    }
    (claim.into(), rows)
}

fn other(folder: &RunFolder) -> (String, Vec<Row>) {
    let claim = format!(
        "Scenario `{}` is not one of the paper's experiments: the report shows its metrics and generic figures.",
        folder.scenario
    );
    let mut rows = Vec::new();
    let worst: Vec<String> = folder
        .variants
        .iter()
        .filter_map(|v| {
            let list = crate::values::per_joint(v, m::TRACKING_RMSE)?;
            let (k, x) = list
                .iter()
                .enumerate()
                .filter_map(|(k, x)| x.map(|x| (k, x)))
                .max_by(|a, b| a.1.total_cmp(&b.1))?;
            let j = folder.joints.get(k).map_or("?", |j| short_name(j));
            Some(format!("`{}` {} rad ({j})", v.name, fmt_num(x)))
        })
        .collect();
    if !worst.is_empty() {
        rows.push(row(
            "largest joint tracking RMSE",
            "–",
            worst.join("; "),
            "–",
        ));
    }
    if let Some(text) = per_variant(folder, m::EE_ERROR_RMS, " m") {
        rows.push(row("hand position error, RMS", "–", text, "–"));
    }
    if let Some(text) = per_variant(folder, m::EXTERNAL_TORQUE_NRMSE, "") {
        rows.push(row(
            "external-torque estimate in contact, NRMSE",
            "–",
            text,
            "–",
        ));
    }
    (claim, rows)
}

/// The title of the report.
pub fn title(folder: &RunFolder) -> String {
    let what = match Experiment::of(folder) {
        Experiment::Deadzone => "Experiment A: deadzone compensation".to_string(),
        Experiment::Admittance { mujoco: false } => {
            "Experiment B: force-sensorless admittance".to_string()
        }
        Experiment::Admittance { mujoco: true } => {
            "Experiment B on the MuJoCo plant (co-simulation)".to_string()
        }
        Experiment::DynamicNodes => "Experiment C: dynamic RBF nodes".to_string(),
        Experiment::TrainingData => "Experiment B: the observer's training data".to_string(),
        Experiment::ValidationData => "Experiment B: the observer's validation data".to_string(),
        Experiment::HandContact => "Task-space contact".to_string(),
        Experiment::Other => "A scenario outside the paper".to_string(),
    };
    format!("{what} (scenario `{}`)", folder.scenario)
}

/// The opening blocks: title, description, claim, headline table, warnings.
pub fn blocks(folder: &RunFolder, warnings: Vec<String>) -> Vec<Block<'static>> {
    let (claim, rows) = match Experiment::of(folder) {
        Experiment::Deadzone => deadzone(folder),
        Experiment::Admittance { .. } => admittance(folder),
        Experiment::DynamicNodes => dynamic_nodes(folder),
        Experiment::TrainingData => data_run(folder, false),
        Experiment::ValidationData => data_run(folder, true),
        Experiment::HandContact => hand_contact(folder),
        Experiment::Other => other(folder),
    };
    let mut out = vec![Block::Title(title(folder))];
    if let Some(d) = folder.description() {
        out.push(Block::Paragraph(d.to_string()));
    }
    let paper = if matches!(
        Experiment::of(folder),
        Experiment::Other | Experiment::HandContact
    ) {
        "**Claim.**"
    } else {
        "**The paper's claim.**"
    };
    out.push(Block::Paragraph(format!("{paper} {claim}")));
    if rows.is_empty() {
        out.push(Block::Paragraph(
            "This run's summary has none of the headline metrics.".into(),
        ));
    } else {
        out.push(Block::Table {
            header: ["quantity", "paper", "this run", "agrees"]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            rows: rows.into_iter().map(Vec::from).collect(),
        });
    }
    if warnings.is_empty() {
        let mut text = "No warnings: every variant passed every health rule (summary.json's `health`: no divergence, hand error, saturation, limit or fault beyond its threshold), every metric is finite and every sample was drawn.".to_string();
        let missing: Vec<&str> = CHECKED
            .iter()
            .copied()
            .filter(|name| {
                folder
                    .variants
                    .iter()
                    .all(|v| !v.metrics.contains_key(*name))
            })
            .collect();
        if !missing.is_empty() {
            text.push_str(&format!(
                " This summary does not have {} (a run folder written before them, or a plant that does not report them), so those were not checked.",
                missing
                    .iter()
                    .map(|n| format!("`{n}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        out.push(Block::Paragraph(text));
    } else {
        out.push(Block::Warnings(warnings));
    }
    out
}
