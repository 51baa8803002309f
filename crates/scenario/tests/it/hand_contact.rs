//! The hand-contact scenario (`scenarios/hand_contact.toml`, issue 16) through the library
//! API: the oracle and momentum variants, full length (a few seconds each). The checks are
//! mechanical (the wall loads the joints, the oracle's hand-force estimate is the true force,
//! the hand yields along the pushed axis, finite metrics, no bound violations); the bars on
//! the learned observers are measured on the full run
//! (`admittance run scenarios/hand_contact.toml --out runs/hand_contact`).

use crate::common;
use common::{column, metric, number, per_joint, scenario_path};

use admittance_scenario::{run_variant, RunOptions, ScenarioSource, VariantRun};

fn run(variant: &str) -> VariantRun {
    let path = scenario_path("hand_contact.toml");
    let source = ScenarioSource::load(&path).unwrap();
    run_variant(&source, &path, Some(variant), &RunOptions::default())
        .unwrap_or_else(|e| panic!("{variant}: {e}"))
}

#[test]
fn the_wall_loads_the_joints_and_the_oracle_reads_the_true_force() {
    let oracle = run("oracle");
    assert_eq!(metric(&oracle, "diverged"), serde_json::Value::Bool(false));
    assert_eq!(number(&oracle, "reference_bound_violations"), 0.0);
    assert_eq!(number(&oracle, "torque_limit_violations"), 0.0);
    // Pressing on the wall: a firm contact (several newtons), read exactly by the oracle.
    let peak = number(&oracle, "contact_force_max");
    assert!((5.0..30.0).contains(&peak), "contact force {peak} N");
    assert!(number(&oracle, "wrench_estimate_nrmse") < 0.02);
    // Every joint whose axis the force can turn feels it: all but w2, whose axis passes
    // through the hand frame (the file's header says why).
    let t = column(&oracle, "t");
    let at = t.iter().position(|&x| x >= 8.0).unwrap();
    for (j, name) in oracle.joints.iter().enumerate() {
        let tau = column(&oracle, &format!("tau_ext.{name}"))[at];
        if j < 6 {
            assert!(tau.abs() > 0.05, "{name}: {tau} N m in contact");
        } else {
            assert!(tau.abs() < 1e-6, "{name}: {tau} N m");
        }
    }
    // Hand guiding: zero stiffness along y, the hand follows the 5 N push (5 N over
    // 300 N s/m for about 2 s: several centimetres) and stays where it was left.
    let y = column(&oracle, "x_hand.y");
    let before = y[t.iter().position(|&x| x >= 16.9).unwrap()];
    let after = y[t.iter().position(|&x| x >= 21.0).unwrap()];
    assert!(after - before > 0.02, "the hand moved {} m", after - before);
    let end = *y.last().unwrap();
    assert!(
        (end - after).abs() < 0.005,
        "drifted {} m after release",
        end - after
    );
}

#[test]
fn the_momentum_observer_reads_friction_as_force() {
    // Friction the observer does not know: a false force without contact, which the
    // zero-stiffness axis turns into drift; metrics stay finite and the reference inside
    // its bounds.
    let momentum = run("momentum");
    assert_eq!(number(&momentum, "reference_bound_violations"), 0.0);
    assert!(number(&momentum, "false_force_rms") > 1.0);
    for key in ["wrench_estimate_nrmse", "external_torque_nrmse"] {
        let v = number(&momentum, key);
        assert!(v.is_finite() && v > 0.0, "{key} = {v}");
    }
    for v in per_joint(&momentum, "q_limit_violation_fraction") {
        assert_eq!(v, 0.0);
    }
}
