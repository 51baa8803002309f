//! The committed scenario files of experiments A (`scenarios/deadzone.toml`) and C
//! (`scenarios/dynamic_nodes.toml`) run end to end through the library API, shortened so
//! that the whole file stays well under a minute in the test profile. The checks are
//! structural (every variant runs, metrics are finite, torques are finite and within the
//! effort limits, nodes are discarded and grown); the experiments' bars are measured on the
//! full-length runs (`admittance run scenarios/FILE.toml --out DIR`).

use crate::common;
use common::{number, per_joint, scenario_path};
use std::path::PathBuf;

use admittance_scenario::{run_variant, RunOptions, ScenarioSource, VariantRun};

fn load(name: &str, overrides: &[&str]) -> (ScenarioSource, PathBuf) {
    let path = scenario_path(name);
    let mut source = ScenarioSource::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    for o in overrides {
        source.set(o).unwrap_or_else(|e| panic!("--set {o}: {e}"));
    }
    (source, path)
}

/// Facts every variant of every scenario must satisfy.
fn check_common(run: &VariantRun) {
    let name = &run.name;
    assert_eq!(
        number(run, "nonfinite_torques"),
        0.0,
        "{name}: a commanded torque was not finite"
    );
    assert_eq!(
        number(run, "torque_limit_violations"),
        0.0,
        "{name}: a torque exceeded its effort limit"
    );
    assert_eq!(number(run, "faults"), 0.0, "{name}: the controller faulted");
    for key in [
        "tracking_rmse",
        "tracking_max_abs",
        "torque_rms",
        "torque_max_abs",
        "deadzone_time_fraction",
    ] {
        for v in per_joint(run, key) {
            assert!(v.is_finite() && v >= 0.0, "{name}: {key} = {v}");
        }
    }
    // A run that has gone unstable shows up as radians of error; these bounds are loose on
    // purpose (the runs here are short, learning has barely started).
    for (j, v) in per_joint(run, "tracking_max_abs").iter().enumerate() {
        assert!(
            *v < 0.5,
            "{name}: joint {} tracking error {v} rad",
            run.joints[j]
        );
    }
    let ee_max = number(run, "ee_error_max");
    let ee_rms = number(run, "ee_error_rms");
    assert!(
        ee_rms.is_finite() && ee_rms <= ee_max + 1e-12,
        "{name}: ee_error_rms {ee_rms}, max {ee_max}"
    );
    assert!(ee_max < 0.3, "{name}: hand error {ee_max} m");
    assert!(number(run, "controller_step_median_us") > 0.0);
    assert!(!run.series.rows.is_empty());
    for row in &run.series.rows {
        assert_eq!(row.len(), run.series.columns.len());
        assert!(
            row.iter().all(|v| v.is_finite()),
            "{name}: a non-finite value in the time series"
        );
    }
}

#[test]
fn deadzone_scenario_runs_every_variant() {
    let (source, path) = load("deadzone.toml", &["duration=6.0", "evaluation_start=3.0"]);
    let names = source.variant_names();
    for expected in [
        "nn_compensated",
        "nn_uncompensated",
        "pd",
        "nn_compensated_wide",
        "nn_uncompensated_wide",
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "variant {expected} missing from {names:?}"
        );
    }
    let options = RunOptions::default();
    for name in &names {
        let run = run_variant(&source, &path, Some(name), &options)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        check_common(&run);
        let weights = run.metrics.weight_norm_final.as_ref();
        let nodes = &run.metrics.nodes;
        match name.as_str() {
            "pd" => assert!(nodes.is_empty(), "pd has no networks"),
            n if n.starts_with("nn_") => {
                let weights = weights.expect("weight norms of the neural variants");
                assert!(weights.values().all(|w| w.is_finite()));
                let compensated = !n.contains("uncompensated");
                assert_eq!(
                    nodes.contains_key("deadzone"),
                    compensated,
                    "{n}: deadzone network presence"
                );
                assert!(nodes.contains_key("f"));
            }
            other => panic!("unexpected variant {other}"),
        }
        // The actuator deadzone on s0 is active in every variant (wide: +-5 N m).
        let fraction = per_joint(&run, "deadzone_time_fraction");
        assert!(fraction[0] > 0.0, "{name}: s0 never in its deadzone");
        assert!(
            fraction[1..].iter().all(|f| *f == 0.0),
            "{name}: only s0 has a deadzone"
        );
    }
}

/// Experiment A's bars that the committed configuration meets, on a 20 s run (errors over
/// 10-20 s; the full 40 s run gives 0.00149 vs 0.00193 rad and 0.00242 vs 0.00836 rad):
/// the compensation lowers s0's tracking error in the paper's pair, and to under a third
/// in the wide pair (the bar; 0.29 over the full 40 s, see the comments in
/// `scenarios/deadzone.toml`). The hand error of the compensated variants stays below
/// 0.01 m (the aim), the uncompensated ones below the paper's 0.04 m.
#[test]
fn deadzone_compensation_lowers_s0_error() {
    let (source, path) = load("deadzone.toml", &["duration=20.0", "evaluation_start=10.0"]);
    let options = RunOptions::default();
    let s0 = |name: &str, hand_error_bound: f64| {
        let run = run_variant(&source, &path, Some(name), &options)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        check_common(&run);
        let ee = number(&run, "ee_error_max");
        assert!(ee < hand_error_bound, "{name}: hand error {ee} m");
        per_joint(&run, "tracking_rmse")[0]
    };
    let comp = s0("nn_compensated", 0.01);
    let uncomp = s0("nn_uncompensated", 0.04);
    assert!(
        comp < 0.95 * uncomp,
        "paper's deadzone: s0 rmse {comp:.3e} compensated vs {uncomp:.3e}"
    );
    let comp = s0("nn_compensated_wide", 0.01);
    let uncomp = s0("nn_uncompensated_wide", 0.04);
    assert!(
        comp < uncomp / 3.0,
        "+-5 N m deadzone: s0 rmse {comp:.3e} compensated vs {uncomp:.3e}"
    );
}

#[test]
fn dynamic_nodes_scenario_discards_and_grows() {
    let (source, path) = load(
        "dynamic_nodes.toml",
        &[
            "duration=9.0",
            "evaluation_start=1.0",
            "dynamic_nodes.discard_time=5.0",
            "dynamic_nodes.grow_time=6.0",
            "dynamic_nodes.approximation_window=1.0",
            // The file's 13 s relevance window is longer than this whole run; nodes tracked
            // for less than a window are never discarded.
            "controller.neural.f.network.relevance_window=2000",
        ],
    );
    assert_eq!(source.variant_names(), vec!["dynamic".to_string()]);
    let run =
        run_variant(&source, &path, Some("dynamic"), &RunOptions::default()).expect("dynamic runs");
    check_common(&run);
    let discarded = number(&run, "nodes_discarded");
    let added = number(&run, "nodes_added");
    assert!(discarded > 0.0, "no node discarded");
    assert!(added > 0.0, "no node added");
    let nodes = run.metrics.nodes["f"] as f64;
    assert_eq!(nodes, 512.0 - discarded + added, "node bookkeeping");
    assert!(
        !run.metrics.nodes.contains_key("deadzone"),
        "C runs without the deadzone network"
    );
    for key in [
        "approx_rmse_full",
        "approx_rmse_after_discard",
        "approx_rmse_after_growth",
        "weight_norm_max",
    ] {
        let v = number(&run, key);
        assert!(v.is_finite() && v > 0.0, "{key} = {v}");
    }
    for col in ["f.left_s0", "f_hat.left_s0", "nodes.f"] {
        assert!(run.series.column(col).is_some(), "column {col} missing");
    }
}

/// One simulated hour of experiment A with the compensation network (docs/method.md section 3:
/// the weights and errors stay bounded). Slow (minutes): run with
/// `cargo test --release -p admittance-sim --test scenarios -- --ignored`.
/// The same check from the command line:
/// `admittance run scenarios/deadzone.toml --out DIR --variant nn_compensated --set duration=3600 --set evaluation_start=3000`.
#[test]
#[ignore = "one simulated hour: minutes of wall time"]
fn deadzone_one_hour_stays_bounded() {
    let (source, path) = load(
        "deadzone.toml",
        &[
            "duration=3600.0",
            "evaluation_start=3000.0",
            "output.decimation=1000",
        ],
    );
    let run = run_variant(
        &source,
        &path,
        Some("nn_compensated"),
        &RunOptions::default(),
    )
    .expect("runs");
    check_common(&run);
    let weights = run.metrics.weight_norm_final.clone().expect("weight norms");
    for (net, w) in weights {
        let w: f64 = w;
        assert!(w.is_finite() && w < 1e3, "network {net}: weight norm {w}");
    }
    assert!(
        number(&run, "ee_error_max") < 0.04,
        "hand error over the last 600 s"
    );
}

/// An approximation window longer than a phase would mix samples from before the discard
/// into the "after discard" error: the scenario is rejected, naming the key.
#[test]
fn dynamic_nodes_window_longer_than_a_phase_is_rejected() {
    let (source, path) = load(
        "dynamic_nodes.toml",
        &[
            "duration=9.0",
            "evaluation_start=1.0",
            "dynamic_nodes.discard_time=5.0",
            "dynamic_nodes.grow_time=6.0",
            "dynamic_nodes.approximation_window=2.0",
        ],
    );
    let err = run_variant(&source, &path, Some("dynamic"), &RunOptions::default())
        .expect_err("window 2 s > phase 1 s");
    let text = err.to_string();
    assert!(text.contains("approximation_window"), "{text}");
}

/// Issue 32, item 5: a setting the simulator refuses keeps its key up to the scenario
/// file (it was reported at the whole `[plant]` table), located where it is written.
#[test]
fn a_plant_setting_the_simulator_refuses_is_located_at_its_key() {
    let (source, path) = load("deadzone.toml", &["plant.inertia_scale=0.0"]);
    let err = run_variant(&source, &path, None, &RunOptions::default())
        .expect_err("an inertia scale of 0 is refused");
    assert_eq!(err.key.as_deref(), Some("plant.inertia_scale"), "{err}");
    assert_eq!(err.file, "--set plant.inertia_scale=0.0", "{err}");
}
