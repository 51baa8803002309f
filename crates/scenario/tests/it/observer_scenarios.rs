//! Experiment B (`scenarios/admittance.toml`, docs/method.md sections 2 and 5) and the
//! free-motion recording (`scenarios/free_motion.toml`) through the library API, shortened.
//! Structural checks plus the properties that hold at any length: the oracle's estimate is
//! the true torque (one control step late), the oracle's own admittance error is zero, the
//! momentum observer sees the contact, no reference leaves its saturation bound, and the
//! free-motion file reads back through the validating loader.

use crate::common;
use common::{number, per_joint, scenario_path};

use admittance_scenario::FreeMotionData;
use admittance_scenario::{run_scenario, run_variant, RunOptions, ScenarioSource};

#[test]
fn admittance_scenario_momentum_and_oracle() {
    let path = scenario_path("admittance.toml");
    let mut source = ScenarioSource::load(&path).unwrap();
    // Contact from 1 s to 3 s of a 4 s run.
    for o in [
        "duration=4.0",
        "evaluation_start=0.5",
        "plant.environment.joint_springs=[{ joints = [\"left_s0\"], mass = [0.01], damping = [0.15], stiffness = [1.1], t_start = 1.0, t_end = 3.0 }]",
    ] {
        source.set(o).unwrap_or_else(|e| panic!("{o}: {e}"));
    }
    let names = source.variant_names();
    assert!(
        names.iter().any(|n| n == "momentum") && names.iter().any(|n| n == "oracle"),
        "{names:?}"
    );
    let oracle = run_variant(&source, &path, Some("oracle"), &RunOptions::default()).unwrap();
    let momentum = run_variant(&source, &path, Some("momentum"), &RunOptions::default()).unwrap();
    for run in [&oracle, &momentum] {
        assert_eq!(
            number(run, "reference_bound_violations"),
            0.0,
            "{}",
            run.name
        );
        assert_eq!(number(run, "faults"), 0.0);
        assert_eq!(number(run, "observer_faults"), 0.0);
        assert_eq!(number(run, "torque_limit_violations"), 0.0);
        assert_eq!(per_joint(run, "false_torque_rms").len(), 7);
        assert_eq!(per_joint(run, "admittance_error_rms").len(), 7);
    }
    // The oracle is the truth one step late, and drives the same q_r as the parallel oracle.
    assert!(
        number(&oracle, "external_torque_nrmse") < 0.01,
        "{}",
        number(&oracle, "external_torque_nrmse")
    );
    assert!(per_joint(&oracle, "admittance_error_rms")
        .iter()
        .all(|v| *v == 0.0));
    assert!(per_joint(&oracle, "false_torque_rms")[1..]
        .iter()
        .all(|v| *v == 0.0));
    // The momentum observer sees the contact on s0, imperfectly (unknown friction, 20% model error).
    let nrmse = number(&momentum, "external_torque_nrmse");
    assert!(
        nrmse.is_finite() && nrmse > 0.05 && nrmse < 3.0,
        "momentum nrmse {nrmse}"
    );
    assert!(per_joint(&momentum, "admittance_error_rms")[0] > 0.0);
    // The estimate column is what the metrics saw.
    let col = momentum.series.column("tau_ext_hat.left_s0").unwrap();
    assert!(momentum.series.rows.iter().any(|r| r[col] != 0.0));
}

#[test]
fn free_motion_scenario_writes_a_loadable_file() {
    let path = scenario_path("free_motion.toml");
    let out = std::env::temp_dir().join(format!(
        "admittance-free-motion-test-{}",
        std::process::id()
    ));
    let summary = run_scenario(
        &path,
        &out,
        None,
        &["duration=1.5".to_string()],
        &RunOptions::default(),
        false,
        |_, _, _| {},
        |_| Ok(()),
    )
    .unwrap();
    let run = &summary.variants[0];
    assert_eq!(number(run, "torque_limit_violations"), 0.0);
    let data = FreeMotionData::load(&out.join("free_motion.csv")).unwrap();
    assert_eq!(data.len(), 1500);
    assert_eq!(data.joints, run.joints);
    assert!((data.t[1] - data.t[0] - 1e-3).abs() < 1e-12);
    // The arm moves (excitation) and the torques hold it against gravity.
    let n = data.dof();
    let last = data.len() - 1;
    assert!((0..n).any(|j| data.qdot[last * n + j].abs() > 0.05));
    assert!(
        data.tau[last * n + 1].abs() > 10.0,
        "s1 holds the arm: {}",
        data.tau[last * n + 1]
    );
    // The series the runner kept is the file's content.
    let fm = run.free_motion.as_ref().unwrap();
    assert_eq!(fm.rows.len(), 1500);
    assert_eq!(fm.rows[700][1 + 3 * n + 2], data.tau[700 * n + 2]);
    let _ = std::fs::remove_dir_all(&out);
}
