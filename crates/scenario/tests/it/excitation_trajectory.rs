//! `[trajectory] excitation`: a scenario's desired motion designed for identification
//! (docs/method.md section 8), as `scenarios/panda_excitation.toml` records it.

use crate::common;
use admittance_scenario::{run_variant, RunOptions, ScenarioSource};
use common::{number, per_joint, scenario_path};

#[test]
fn the_excitation_scenario_moves_every_joint_inside_its_limits_from_rest() {
    let path = scenario_path("panda_excitation.toml");
    let mut source = ScenarioSource::load(&path).unwrap();
    // One period of the series, a short design search: the motion, not its optimum.
    for o in [
        "duration=10.0",
        "trajectory.excitation.iterations=50",
        "record.free_motion_csv=false",
    ] {
        source.set(o).unwrap_or_else(|e| panic!("{o}: {e}"));
    }
    let run = run_variant(&source, &path, None, &RunOptions::default()).unwrap();
    assert!(!run.metrics.diverged);
    assert!(per_joint(&run, "q_limit_violation_fraction")
        .iter()
        .all(|f| *f == 0.0));
    assert!(per_joint(&run, "torque_saturation_fraction")
        .iter()
        .all(|f| *f == 0.0));
    assert_eq!(number(&run, "torque_limit_violations"), 0.0);
    // Every joint moves: the desired angle spans a good part of each joint's range.
    let columns = &run.series.columns;
    for j in &run.joints {
        let i = columns
            .iter()
            .position(|c| c == &format!("q_d.{j}"))
            .unwrap();
        let (lo, hi) = run
            .series
            .rows
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), r| {
                (lo.min(r[i]), hi.max(r[i]))
            });
        assert!(hi - lo > 0.3, "{j}: q_d spans only {:.3} rad", hi - lo);
    }
    // From rest: the first row's desired angle is the plant's start, tracked closely.
    let tracking = per_joint(&run, "tracking_rmse");
    assert!(tracking.iter().all(|e| *e < 0.1), "{tracking:?}");
}

#[test]
fn an_excitation_with_sines_is_refused_at_its_key() {
    let path = scenario_path("panda_excitation.toml");
    let mut source = ScenarioSource::load(&path).unwrap();
    source
        .set("trajectory.sines=[{ joint = \"panda_joint1\", amplitude = 0.1, period = 3.0 }]")
        .unwrap();
    let e = run_variant(&source, &path, None, &RunOptions::default())
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("trajectory.excitation"), "{e}");
    let mut source = ScenarioSource::load(&path).unwrap();
    source.set("trajectory.excitation.period=7.0").unwrap();
    let e = run_variant(&source, &path, None, &RunOptions::default())
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("trajectory.excitation"), "{e}");
}
