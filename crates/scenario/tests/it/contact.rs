//! `[contact]` in a scenario (issue 31): `scenarios/panda_contact.toml` shortened, with its
//! data scenarios shortened too: the floor is calibrated at the start of the run on free
//! motion the identification did not fit, the detector runs on the loop's estimate, the
//! run's metrics score it against the true external torque, and the floor as the
//! admittance's deadband keeps an untouched arm on its reference.

use std::path::{Path, PathBuf};

use crate::common;
use common::{column, metric, number, per_joint, scenario_path};

use admittance_scenario::{run_variant, RunOptions, ScenarioSource, VariantRun};

/// A data scenario of `scenarios/`, `seconds` long, written into `dir` (its URDF path made
/// absolute).
fn short_data(dir: &Path, name: &str, seconds: f64) -> PathBuf {
    let text = std::fs::read_to_string(scenario_path(name)).unwrap();
    let models = scenario_path("../models");
    let mut source =
        ScenarioSource::parse(&text.replace("../models", models.to_str().unwrap()), name).unwrap();
    source.set(&format!("duration={seconds}")).unwrap();
    let out = dir.join(name);
    std::fs::write(&out, source.text_as_run(None)).unwrap();
    out
}

/// `panda_contact.toml`: 16 s, the evaluation from 4 s, the data 20-30 s long, no cache;
/// `pushes`: two 20 N pushes (down at the hand from 6 s, sideways at link 5 from 10 s)
/// instead of the file's (a `--set` also replaces what a variant sets).
fn run(variant: &str) -> VariantRun {
    let dir = tempfile::tempdir().unwrap();
    let train = short_data(dir.path(), "panda_free_motion_validation.toml", 30.0);
    let validation = short_data(dir.path(), "panda_free_motion.toml", 20.0);
    let calibration = short_data(dir.path(), "panda_excitation.toml", 30.0);
    let path = scenario_path("panda_contact.toml");
    let mut source = ScenarioSource::load(&path).unwrap();
    let pushes = "[{frame = \"panda_hand_tcp\", points = [[6.0, 0.0, 0.0, 0.0], [6.2, 0.0, 0.0, -20.0], [6.8, 0.0, 0.0, -20.0], [7.0, 0.0, 0.0, 0.0]], t_start = 6.0, t_end = 7.0}, {frame = \"panda_link5\", points = [[10.0, 0.0, 0.0, 0.0], [10.2, 0.0, 20.0, 0.0], [10.8, 0.0, 20.0, 0.0], [11.0, 0.0, 0.0, 0.0]], t_start = 10.0, t_end = 11.0}]";
    let pushes = if variant == "pushes" { pushes } else { "[]" };
    for s in [
        "duration=16.0".to_string(),
        "evaluation_start=4.0".to_string(),
        format!("plant.environment.tip_force_profiles={pushes}"),
        format!("observer.training.data=\"{}\"", train.display()),
        format!("observer.training.validation=\"{}\"", validation.display()),
        "observer.training.cache=false".to_string(),
        format!("contact.calibration=\"{}\"", calibration.display()),
    ] {
        source.set(&s).unwrap_or_else(|e| panic!("{s}: {e}"));
    }
    run_variant(&source, &path, Some(variant), &RunOptions::default())
        .unwrap_or_else(|e| panic!("{variant}: {e}"))
}

#[test]
fn pushes_are_flagged_and_an_untouched_arm_stays_on_its_reference() {
    let pushed = run("pushes");
    let floor = pushed.contact_floor.as_ref().expect("the run's floor");
    assert!(floor
        .contact_thresholds
        .iter()
        .all(|c| c.is_finite() && *c > 0.0));
    assert_eq!(
        per_joint(&pushed, "contact_thresholds"),
        floor.contact_thresholds
    );
    assert_eq!(number(&pushed, "contact_pushes"), 2.0);
    // 20 N on the hand and on link 5 load several joints far beyond their levels: both
    // flagged, within 50 ms of the 2x crossing, the last loaded joint named.
    assert_eq!(number(&pushed, "contact_pushes_detected"), 2.0);
    let over = number(&pushed, "contact_over_twice");
    assert!(over >= 1.0);
    assert_eq!(number(&pushed, "contact_over_twice_within_50ms"), over);
    assert!(number(&pushed, "contact_isolation") > 0.0);
    // The flags and levels are in the series, and the flag is down at the start.
    let flag = column(&pushed, "contact");
    assert_eq!(flag[0], 0.0);
    assert!(flag.contains(&1.0));
    let link = column(&pushed, "contact_link");
    assert!(link.iter().all(|l| (-1.0..7.0).contains(l)));
    // A level never falls below the floor's level once the joint moves (its standstill
    // level less the drop away from rest).
    let moving = floor.contact_thresholds[0] * (1.0 - floor.moving_drop[0]);
    assert!(column(&pushed, "contact_level.panda_joint1")
        .iter()
        .all(|l| *l >= moving * (1.0 - 1e-12)));

    // Nobody touches the arm: with the floor as the deadband the reference does not move
    // from the desired motion (bar: within 1 mrad); without it, the false torque moves it.
    let still = run("untouched");
    assert_eq!(number(&still, "contact_pushes"), 0.0);
    let with = per_joint(&still, "reference_offset_max_abs");
    assert!(
        with.iter().all(|d| *d < 1e-3),
        "drift with the deadband {with:?}"
    );
    let without = per_joint(&run("untouched_no_deadband"), "reference_offset_max_abs");
    let (w, wo) = (
        with.iter().cloned().fold(0.0, f64::max),
        without.iter().cloned().fold(0.0, f64::max),
    );
    assert!(wo > w, "without the deadband {wo} rad, with {w} rad");
    assert!(metric(&still, "contact_false_alarms_per_hour").is_number());
}
