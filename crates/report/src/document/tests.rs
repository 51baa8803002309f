use serde_json::{json, Value};

use super::*;
use crate::folder::Variant;
use crate::table::Table;

const JOINTS: [&str; 2] = ["left_s0", "left_s1"];

fn variant(name: &str, metrics: Value) -> Variant {
    let t: Vec<f64> = (0..10).map(|k| k as f64).collect();
    let mut columns = vec!["t".to_string(), "nodes.f".into()];
    let mut data = vec![t.clone(), vec![512.0; 10]];
    for j in JOINTS {
        columns.push(format!("q.{j}"));
        data.push(t.iter().map(|x| 0.1 * x).collect());
    }
    Variant {
        name: name.into(),
        metrics: metrics.as_object().cloned().unwrap(),
        table: Table::from_columns(columns, data),
    }
}

fn folder(scenario: &str, variants: Vec<Variant>, toml: &str) -> RunFolder {
    let toml = toml.to_string();
    let mut f = old_folder(scenario, variants, &toml);
    // A folder of this build: its settings.json holds what the scenario file says.
    f.settings = Some(f.settings_from_scenario());
    f
}

/// A folder written before settings.json: the settings come from scenario.toml.
fn old_folder(scenario: &str, variants: Vec<Variant>, toml: &str) -> RunFolder {
    RunFolder {
        dir: ".".into(),
        scenario: scenario.into(),
        plant: None,
        joints: JOINTS.iter().map(|s| s.to_string()).collect(),
        variants,
        warnings: Vec::new(),
        health: None,
        scenario_toml: Some(toml.parse().unwrap()),
        settings: None,
        free_motion: Vec::new(),
        node_weights: Vec::new(),
        observer_validation: Vec::new(),
    }
}

/// A deadzone comparison (the neural controller with and without compensation, PD).
const DEADZONE: &str = "[controller]\nkind = \"neural\"\n\
    [[plant.deadzones]]\njoint = \"left_s0\"\nd_left = -0.49\nd_right = 0.49\n\
    [variants.nn_uncompensated]\ncontroller.neural.deadzone_compensation = false\n\
    [variants.pd]\ncontroller.kind = \"pd\"\n";

/// An observer comparison.
const OBSERVERS: &str = "[admittance]\ndamping = 3\nstiffness = 5\n\
    [observer]\nkind = \"learned\"\n[variants.momentum]\nobserver.kind = \"momentum\"\n\
    [variants.oracle]\nobserver.kind = \"oracle\"\n";

fn md(f: &RunFolder) -> String {
    markdown(f, &[], None)
}

/// The part of the report before the metrics: the opening.
fn opening(f: &RunFolder) -> String {
    let text = md(f);
    text[..text.find("## Metrics").unwrap()].to_string()
}

fn clean(extra: Value) -> Value {
    let mut m = json!({
        "tracking_rmse": [0.0015, 0.0003],
        "ee_error_max": 0.0014,
        "ee_error_rms": 0.0009,
        "external_torque_rmse": [0.0, 0.0],
        "external_torque_nrmse": null,
        "faults": 0,
        "observer_faults": 0,
        "diverged": false,
        "diverged_at": null,
        "q_limit_violation_fraction": [0.0, 0.0],
        "steps": 1000,
        "nodes": {"f": 512},
    });
    for (k, v) in extra.as_object().unwrap() {
        m[k] = v.clone();
    }
    m
}

#[test]
fn a_clean_run_opens_with_the_claim_and_the_headline_beside_the_paper() {
    let f = folder(
        "panda_deadzone_renamed",
        vec![
            variant("nn_compensated", clean(json!({}))),
            variant(
                "nn_uncompensated",
                clean(
                    json!({"tracking_rmse": [0.002, 0.0004], "ee_error_max": 0.003, "ee_error_rms": 0.002}),
                ),
            ),
            variant(
                "pd",
                clean(
                    json!({"tracking_rmse": [0.006, 0.0004], "ee_error_max": 0.005, "ee_error_rms": 0.004}),
                ),
            ),
        ],
        &format!("description = \"Experiment A\"\n{DEADZONE}"),
    );
    let top = opening(&f);
    assert!(
        top.starts_with("# Experiment A: deadzone compensation"),
        "{top}"
    );
    assert!(
        top.contains("below 0.04 m") && top.contains("0.001400 m"),
        "{top}"
    );
    // The bound says nothing by itself: the other controllers' values are beside it.
    assert!(
        top.contains("uncompensated 0.003000 m (`nn_uncompensated`); PD 0.005000 m (`pd`); every controller is below it, so the bound does not tell them apart"),
        "{top}"
    );
    assert!(top.contains("×0.75"), "the s0 ratio 0.0015 / 0.002: {top}");
    // The checks that tell them apart: against the uncompensated controller and PD.
    assert!(
        top.contains("| s0 tracking RMSE, compensated / PD (its linear part alone) | – (the learning should beat PD) | 0.001500 / 0.006000 rad = ×0.25 (`nn_compensated` / `pd`) | yes |"),
        "{top}"
    );
    assert!(
        top.contains(
            "`nn_compensated` 9.000e-4 m; `nn_uncompensated` 0.002000 m; `pd` 0.004000 m | yes |"
        ),
        "{top}"
    );
    assert!(top.contains("| yes |"), "{top}");
    assert!(top.contains("No warnings"), "{top}");
    // Metrics this summary lacks are named: they could not be checked.
    assert!(
        top.contains("does not have `torque_saturation_fraction`, `estimate_saturation_fraction`"),
        "{top}"
    );
    assert!(!top.contains("Warning:"), "{top}");
}

#[test]
fn every_problem_is_a_warning_at_the_top() {
    let bad = clean(json!({
        "diverged": true,
        "diverged_at": 12.5,
        "q_limit_violation_fraction": [0.0, 0.032],
        "torque_saturation_fraction": [0.5, 0.0],
        "estimate_saturation_fraction": [0.0, 0.002],
        "faults": 3,
        "stale_measurements": 7,
        "ee_error_rms": null,
        "tracking_rmse": [0.1, null],
    }));
    let mut f = folder(
        "something",
        vec![variant("ok", clean(json!({}))), variant("bad", bad)],
        "",
    );
    f.warnings.push("link `x` has no inertia".into());
    let top = opening(&f);
    for words in [
        "`bad` **failed** `divergence`: diverged at t = 12.5 s",
        "`bad` warning `joint_limits` on s1: left_s1 was outside its position limits 3.20 %",
        "`bad` **failed** `effort_saturation` on s0: left_s0 commanded at its effort limit 50.00 %",
        "`bad` **failed** `estimate_beyond_effort` on s1: the external-torque estimate of left_s1 exceeded the effort limit 0.20 %",
        "`bad` warning `controller_faults`: 3 control steps with a controller fault",
        "`bad` warning `stale_data`: 7 control steps with a stale (frozen or dropped) encoder reading",
        "not finite (null in summary.json): `ee_error_rms`, `tracking_rmse` of left_s1",
        "when the scenario loaded: link `x` has no inertia",
    ] {
        assert!(top.contains(words), "missing `{words}` in:\n{top}");
    }
    assert!(
        !top.contains("**Warning:** `ok`"),
        "the clean variant has no warning:\n{top}"
    );
    // A null that means "no contact" is not a warning.
    assert!(!top.contains("external_torque_nrmse"), "{top}");
    // The HTML has the same warnings, highlighted.
    let html = html(&f, &[], None);
    assert!(html.contains("<div class=\"warnings\">") && html.contains("<b>failed</b>"));
}

#[test]
fn metrics_tables_have_units_windows_joint_columns_and_the_scenario_order() {
    let f = folder(
        "deadzone",
        vec![
            variant(
                "nn_compensated",
                clean(json!({"deadzone_time_fraction": [0.04, 0.0]})),
            ),
            variant(
                "nn_uncompensated",
                clean(json!({"deadzone_time_fraction": [0.036, 0.0]})),
            ),
            variant("pd", clean(json!({"deadzone_time_fraction": [0.05, 0.0]}))),
        ],
        &format!("evaluation_start = 20\n{DEADZONE}"),
    );
    let text = md(&f);
    let metrics = &text[text.find("## Metrics").unwrap()..text.find("## Figures").unwrap()];
    // Variants as columns in the folder's (scenario's) order.
    assert!(
        metrics
            .contains("| metric | unit | window | `nn_compensated` | `nn_uncompensated` | `pd` |"),
        "{metrics}"
    );
    assert!(
        metrics.contains("| `ee_error_max` | m | t ≥ 20 s | 0.001400 |"),
        "{metrics}"
    );
    // Per joint: one column per joint, no comma lists.
    assert!(
        metrics.contains("| metric (unit, window) | variant | s0 | s1 |"),
        "{metrics}"
    );
    assert!(
        metrics.contains(
            "| `tracking_rmse` (rad, t ≥ 20 s) | `nn_compensated` | 0.001500 | 3.000e-4 |"
        ),
        "{metrics}"
    );
    assert!(!metrics.contains("0.001500, "), "{metrics}");
    // Fractions in %, and a joint without a deadzone blank.
    assert!(
        metrics
            .contains("| `deadzone_time_fraction` (%, t ≥ 20 s) | `nn_compensated` | 4.00 % | – |"),
        "{metrics}"
    );
    // Rows that do not apply are left out: no estimate, no contact.
    assert!(!metrics.contains("external_torque"), "{metrics}");
    // Checks that passed are one line, not rows.
    assert!(metrics.contains("**Checks passed in every variant** (whole run): no divergence, no controller faults, no observer faults, every joint inside its limits."), "{metrics}");
    assert!(!metrics.contains("| `faults`"), "{metrics}");
    // Run details: objects one row per key.
    assert!(
        metrics.contains("| `nodes` (f) |  | 512 | 512 | 512 |"),
        "{metrics}"
    );
    // A check that failed is a row.
    let mut f = f;
    f.variants[2].metrics.insert("faults".into(), json!(4));
    let text = md(&f);
    assert!(
        text.contains("| `faults` |  | whole run | 0 | 0 | 4 |"),
        "{text}"
    );
}

#[test]
fn each_experiment_has_its_opening() {
    let b = folder(
        "admittance",
        vec![
            variant(
                "learned",
                json!({"external_torque_nrmse": 0.46, "train_seconds": 8.4, "observer_nodes": 1000, "reference_bound_violations": 0}),
            ),
            variant(
                "momentum",
                json!({"external_torque_nrmse": 0.81, "reference_bound_violations": 2}),
            ),
        ],
        &format!("{OBSERVERS}[admittance.saturation]\nrho = 0.95\nhalf_range = [1.1, inf]\n"),
    );
    let top = opening(&b);
    assert!(
        top.starts_with("# Experiment B: force-sensorless admittance"),
        "{top}"
    );
    assert!(top.contains("`learned` 0.4600; `momentum` 0.8100"), "{top}");
    assert!(
        top.contains("5.088 s (1000 nodes, the authors' computer)")
            && top.contains("8.400 s (`learned`, 1000 nodes; on the computer that made this run)"),
        "{top}"
    );
    assert!(!top.contains("another machine"), "{top}");
    assert!(
        top.contains("`learned` 0.4600 (next `momentum` 0.8100, ×1.8 larger)"),
        "{top}"
    );
    assert!(
        top.contains("samples × joints outside: `momentum` 2 | no |"),
        "{top}"
    );
    assert!(
        top.contains("`momentum` warning `reference_bound`: 2 samples x joints with q_r outside its saturation bound"),
        "{top}"
    );
    let mut mujoco = b.clone();
    mujoco.scenario = "baxter_mujoco".into();
    mujoco.plant = Some("mujoco".into());
    assert!(opening(&mujoco).starts_with("# Experiment B on the MuJoCo plant"));

    let c = folder(
        "dynamic_nodes",
        vec![variant(
            "dynamic",
            json!({"nodes_discarded": 185, "nodes_added": 100, "approx_rmse_full": 2.5633, "approx_rmse_after_discard": 2.5720, "approx_rmse_after_growth": 1.5126}),
        )],
        "[dynamic_nodes]\napproximation_window = 12.0\n",
    );
    let top = opening(&c);
    assert!(
        top.contains("| nodes discarded | 208 of 512 | 185 of 512 |"),
        "{top}"
    );
    assert!(top.contains("(+0.3 %) | yes (within 10 %) |"), "{top}");
    assert!(top.contains("(-41.2 %) | yes |"), "{top}");

    let data = folder(
        "free_motion",
        vec![variant("base", json!({}))],
        "[record]\nfree_motion_csv = true\n",
    );
    let top = opening(&data);
    assert!(
        top.contains("| duration | 450 s | 9 s, 10 samples |"),
        "{top}"
    );

    let other = folder("mine", vec![variant("a", clean(json!({})))], "");
    let top = opening(&other);
    assert!(
        top.contains("is not one of the paper's experiments"),
        "{top}"
    );
    assert!(top.contains("`a` 0.001500 rad (s0)"), "{top}");
}

#[test]
fn the_html_is_well_formed_and_self_contained() {
    let f = folder(
        "deadzone",
        vec![variant("nn_compensated", clean(json!({})))],
        DEADZONE,
    );
    let text = html(&f, &[], None);
    assert!(text.starts_with("<!DOCTYPE html>"));
    assert!(!text.contains("http://") && !text.contains("https://"));
    assert_eq!(
        text.matches("<table>").count(),
        text.matches("</table>").count()
    );
}

#[test]
fn the_admittance_claim_takes_its_window_from_the_run() {
    // The co-simulation's push from 3 s to 6 s (no environment in scenario.toml: the window is
    // where the true external torque is non-zero), 0.5 s samples.
    let t: Vec<f64> = (0..20).map(|k| 0.5 * k as f64).collect();
    let push: Vec<f64> = t
        .iter()
        .map(|&x| if (3.0..=6.0).contains(&x) { 1.0 } else { 0.0 })
        .collect();
    let columns = vec![
        "t".to_string(),
        "tau_ext.left_s0".into(),
        "tau_ext.left_s1".into(),
    ];
    let table = Table::from_columns(columns, vec![t.clone(), push, vec![0.0; 20]]);
    let v = Variant {
        name: "oracle".into(),
        metrics: json!({"external_torque_nrmse": 0.03})
            .as_object()
            .cloned()
            .unwrap(),
        table,
    };
    let mut mujoco = folder("mujoco_franka_panda", vec![v], "");
    mujoco.plant = Some("mujoco".into());
    let top = opening(&mujoco);
    assert!(
        top.contains("while the environment acts (3-6 s, Figs 18-19)"),
        "{top}"
    );
    assert!(!top.contains("12-30"), "{top}");
    // Experiment B's own scenario: its environment's window.
    let b = folder(
        "admittance",
        vec![variant("learned", json!({"external_torque_nrmse": 0.46}))],
        &format!("{OBSERVERS}[[plant.environment.joint_springs]]\njoints = [\"left_s0\"]\nt_start = 1.5\nt_end = 7\n"),
    );
    let top = opening(&b);
    assert!(
        top.contains("while the environment acts (1.5-7 s, Figs 18-19)"),
        "{top}"
    );
}

#[test]
fn a_compensated_controller_that_does_not_beat_the_others_says_no() {
    let f = folder(
        "deadzone",
        vec![
            variant(
                "nn_compensated",
                clean(json!({"tracking_rmse": [0.004, 0.0003], "ee_error_rms": 0.003})),
            ),
            variant(
                "nn_uncompensated",
                clean(json!({"tracking_rmse": [0.002, 0.0004], "ee_error_rms": 0.002})),
            ),
            variant(
                "pd",
                clean(json!({"tracking_rmse": [0.003, 0.0004], "ee_error_rms": 0.004})),
            ),
        ],
        DEADZONE,
    );
    let top = opening(&f);
    assert!(
        top.contains(
            "×2.00 (`nn_compensated` / `nn_uncompensated`), deadzone [-0.49, 0.49] N m | no |"
        ),
        "{top}"
    );
    assert!(
        top.contains("×1.33 (`nn_compensated` / `pd`) | no |"),
        "{top}"
    );
    assert!(top.contains("`pd` 0.004000 m | no |"), "{top}");
}

#[test]
fn an_old_folder_says_where_its_settings_came_from() {
    let f = old_folder(
        "deadzone",
        vec![variant("nn_compensated", clean(json!({})))],
        DEADZONE,
    );
    let top = opening(&f);
    assert!(
        top.contains("has no `settings.json`")
            && top.contains("read from scenario.toml")
            && top.contains("rerun the scenario"),
        "{top}"
    );
    // Still the deadzone report: the classification reads scenario.toml's content.
    assert!(top.starts_with("# Experiment A"), "{top}");
    assert!(!opening(&folder(
        "deadzone",
        vec![variant("nn_compensated", clean(json!({})))],
        DEADZONE
    ))
    .contains("settings.json"));
}
