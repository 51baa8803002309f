//! `RobotLoop` (issue 32) and its plausibility gates (issue 34): no command before every
//! joint has an angle, the first pose held without a desired motion, one absurd sample
//! flagged and forgotten, and the deployment folder's checks.

use std::path::Path;

use admittance_dynamics::{rnea, Data, Model};
use admittance_loop::{
    write_deployment, Deployment, Implausible, RobotConfig, RobotInput, RobotLoop,
};

const URDF: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../models/baxter_left_arm.urdf"
);
const POSE: [f64; 7] = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];

const LOOP_TOML: &str = r#"format = "admittance-loop"
version = 1
[arm]
urdf = "arm.urdf"
base = "base"
tip = "left_hand"
[controller]
kind = "pd"
pd = { kp = 50.0, kd = 5.0, gravity_compensation = true }
[admittance]
damping = 3.0
stiffness = 5.0
[observer]
kind = "momentum"
input_filter_hz = 10.0
cutoff_hz = 5.0
momentum = { gain = 50.0 }
"#;

fn model() -> Model {
    Model::from_urdf_file(URDF.as_ref(), Some("base"), Some("left_hand")).unwrap()
}

fn robot_loop(overrides: &[&str]) -> RobotLoop {
    let config = RobotConfig::from_toml_with(LOOP_TOML, Path::new("loop.toml"), overrides).unwrap();
    RobotLoop::new(model(), &config, Path::new("."), None, None).unwrap()
}

/// `ident` saved as `dir/name` (its path as text).
fn save_identification(
    dir: &Path,
    model: &Model,
    ident: &admittance_dynamics::Identification,
    name: &str,
) -> String {
    let path = dir.join(name);
    ident.save(&path, model, Default::default()).unwrap();
    path.to_str().unwrap().to_string()
}

/// The loop of `LOOP_TOML` with its momentum observer on the identification file `file`.
fn loop_on_identification(model: &Model, file: &str) -> RobotLoop {
    let config = RobotConfig::from_toml_with(
        LOOP_TOML,
        Path::new("loop.toml"),
        &[&format!("observer.identification = \"{file}\"")],
    )
    .unwrap();
    RobotLoop::new(model.clone(), &config, Path::new("."), None, None).unwrap()
}

/// One 1 kHz step with measured angles and torques.
fn step_measured(
    l: &mut RobotLoop,
    k: usize,
    q: &[f64],
    tau: &[f64],
) -> admittance_loop::RobotStatus {
    l.step(&RobotInput {
        time: k as f64 * 1e-3,
        q,
        qdot: None,
        tau: Some(tau),
        desired: None,
    })
}

/// A slow motion around the pose with the torque its inverse dynamics needs.
fn motion(model: &Model, data: &mut Data, k: usize) -> ([f64; 7], [f64; 7]) {
    let t = k as f64 * 1e-3;
    let (mut q, mut v, mut a) = ([0.0; 7], [0.0; 7], [0.0; 7]);
    for i in 0..7 {
        let w = 1.0 + 0.3 * i as f64;
        q[i] = POSE[i] + 0.1 * (w * t).sin();
        v[i] = 0.1 * w * (w * t).cos();
        a[i] = -0.1 * w * w * (w * t).sin();
    }
    let mut tau = [0.0; 7];
    tau.copy_from_slice(rnea(model, data, &q, &v, &a).unwrap().as_slice());
    (q, tau)
}

#[test]
fn nothing_is_commanded_before_every_joint_has_an_angle_then_the_pose_is_held() {
    let mut l = robot_loop(&[]);
    let mut q = POSE;
    q[6] = f64::NAN;
    for k in 0..5 {
        let s = l.step(&RobotInput {
            time: k as f64 * 1e-3,
            q: &q,
            qdot: None,
            tau: None,
            desired: None,
        });
        assert!(s.waiting_for_angles && !s.is_ok());
        assert!(l.torque().iter().all(|&t| t == 0.0));
    }
    // A short slice is the same: joints without a value have no angle.
    let s = l.step(&RobotInput {
        time: 0.005,
        q: &POSE[..3],
        qdot: None,
        tau: None,
        desired: None,
    });
    assert!(s.waiting_for_angles);
    for k in 6..400 {
        let s = l.step(&RobotInput {
            time: k as f64 * 1e-3,
            q: &POSE,
            qdot: None,
            tau: None,
            desired: None,
        });
        assert!(!s.waiting_for_angles && s.holding_pose, "step {k}");
    }
    assert!(l.torque().iter().any(|&t| t != 0.0));
    // The hold is where the arm was (the first full sample), not a scenario's trajectory.
    let q_r = l.reference()[0];
    for i in 0..6 {
        assert!((q_r[i] - POSE[i]).abs() < 1e-9, "joint {i}: {}", q_r[i]);
    }
    // Joint 6 delivered its first angle at step 5 (POSE); held since.
    assert!((q_r[6] - POSE[6]).abs() < 1e-9);
}

#[test]
fn each_gate_flags_its_sample_and_the_estimate_forgets_it() {
    let model = model();
    let mut data = Data::new(&model);
    let steps = 3000;
    let samples: Vec<_> = (0..steps).map(|k| motion(&model, &mut data, k)).collect();
    let run = |overrides: &[&str], hit: bool| {
        let mut l = robot_loop(overrides);
        let mut out = Vec::new();
        for (k, (q, tau)) in samples.iter().enumerate() {
            let (mut q, mut tau) = (*q, *tau);
            if hit {
                match k {
                    1000 => tau[1] = 1e300,
                    1200 => q[3] = 1e20,
                    1400 => q[2] += 0.5, // 0.5 rad in 1 ms: no motor moves so
                    _ => {}
                }
            }
            let s = step_measured(&mut l, k, &q, &tau);
            out.push((
                s,
                l.external_torque_estimate().to_vec(),
                l.torque().to_vec(),
            ));
        }
        (out, l.implausible_samples())
    };
    let (clean, none) = run(&[], false);
    assert_eq!(none, 0);
    assert!(clean
        .iter()
        .skip(1)
        .all(|(s, _, _)| s.implausible.is_none()));
    let (hit, count) = run(&[], true);
    assert_eq!(count, 3);
    for (k, gate, joint) in [
        (1000, Implausible::Torque, 1),
        (1200, Implausible::Angle, 3),
        (1400, Implausible::Jump, 2),
    ] {
        let g = hit[k]
            .0
            .implausible
            .unwrap_or_else(|| panic!("step {k} not flagged"));
        assert_eq!((g.gate, g.joint), (gate, joint), "step {k}");
    }
    let gap = |k: usize| -> f64 {
        (0..7)
            .map(|i| (hit[k].1[i] - clean[k].1[i]).abs())
            .fold(0.0, f64::max)
    };
    let during = (1000..steps).map(gap).fold(0.0, f64::max);
    let after = (2400..steps).map(gap).fold(0.0, f64::max);
    eprintln!("momentum: estimate off the clean run by {during:.3e} N m at most, {after:.3e} N m 1 s after the last");
    assert!(during < 0.5, "{during}");
    assert!(after < 1e-3, "{after}");
    assert!(hit
        .iter()
        .all(|(_, _, tau)| tau.iter().all(|t| t.is_finite())));
    // Without the gates the same samples poison the estimate: the test can fail.
    let (open, _) = run(&["signals.gates.enabled = false"], true);
    let poisoned = (1000..steps)
        .map(|k| {
            (0..7)
                .map(|i| (open[k].1[i] - clean[k].1[i]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(poisoned > 1e3 || poisoned.is_nan(), "ungated: {poisoned}");
}

#[test]
fn a_deployment_folder_is_verified_file_by_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("deploy");
    let files = vec![
        ("loop.toml".to_string(), LOOP_TOML.as_bytes().to_vec()),
        ("arm.urdf".to_string(), std::fs::read(URDF).unwrap()),
    ];
    write_deployment(&dir, &files, serde_json::json!({"tool": "test"})).unwrap();
    let d = Deployment::load(&dir).unwrap();
    assert_eq!(
        d.file_names().collect::<Vec<_>>(),
        ["arm.urdf", "loop.toml"]
    );
    let l = RobotLoop::load(&dir, &["signals.filter_cutoff_hz = 10"]).unwrap();
    assert_eq!(l.dof(), 7);
    // A setting out of range names its key.
    let e = RobotLoop::load(&dir, &["signals.filter_cutoff_hz = 600"])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("signals.filter_cutoff_hz"), "{e}");
    // Not a folder someone else wrote over: refused.
    let other = tmp.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    assert!(write_deployment(&other, &files, serde_json::Value::Null).is_err());
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "mine"
    );
    // A loop file naming a file the manifest does not list.
    let mut listed = files.clone();
    listed[0].1 = LOOP_TOML
        .replace("[observer]", "[observer]\nidentification = \"ident.json\"")
        .into_bytes();
    write_deployment(&dir, &listed, serde_json::Value::Null).unwrap();
    let e = Deployment::load(&dir).err().unwrap().to_string();
    assert!(
        e.contains("observer.identification") && e.contains("ident.json"),
        "{e}"
    );
    // An edited file.
    write_deployment(&dir, &files, serde_json::Value::Null).unwrap();
    std::fs::write(dir.join("loop.toml"), LOOP_TOML.replace("50.0", "60.0")).unwrap();
    let e = Deployment::load(&dir).err().unwrap().to_string();
    assert!(
        e.contains("loop.toml") && e.contains("does not match the manifest"),
        "{e}"
    );
    // Not a deployment folder.
    let e = Deployment::load(tmp.path()).err().unwrap().to_string();
    assert!(e.contains("manifest.json"), "{e}");
}

#[test]
fn the_identifications_torque_delay_is_applied_at_run_time() {
    // Torques that arrive 20 ms after the motion they belong to, as a torque filter would
    // make them. An identification records that delay; the loop pairs them back.
    let tmp = tempfile::tempdir().unwrap();
    let model = model();
    let mut ident = admittance_dynamics::Identification::from_model(model.clone());
    let save = |ident: &admittance_dynamics::Identification, name: &str| {
        save_identification(tmp.path(), &model, ident, name)
    };
    let plain = save(&ident, "plain.json");
    ident.summary.delay_s = vec![0.02; 7];
    let delayed = save(&ident, "delayed.json");
    let false_torque = |file: &str| {
        let mut l = loop_on_identification(&model, file);
        let mut data = Data::new(&model);
        let mut sum = 0.0;
        for k in 0..4000 {
            let (q, _) = motion(&model, &mut data, k);
            let (_, tau) = motion(&model, &mut data, k.saturating_sub(20));
            let s = step_measured(&mut l, k, &q, &tau);
            assert!(s.is_ok() || k < 10, "step {k}");
            if k >= 2000 {
                sum += l
                    .external_torque_estimate()
                    .iter()
                    .map(|e| e * e)
                    .sum::<f64>();
            }
        }
        (sum / 2000.0).sqrt()
    };
    let (without, with) = (false_torque(&plain), false_torque(&delayed));
    assert!(
        with < 0.5 * without,
        "false torque {with} with the delay, {without} without"
    );
}

#[test]
fn a_repeated_reading_of_a_moving_joint_is_reported_from_its_first_stale_sample() {
    // The driver repeats joint 2's last packet for 15 ms while the arm moves: the status
    // says so from the signal chain's first stale sample (10 ms), before the safe hold's
    // 30 steps would act, and not when the readings move again.
    let model = model();
    let mut l = robot_loop(&[]);
    let mut data = Data::new(&model);
    let mut frozen_q = 0.0;
    let mut flagged = Vec::new();
    for k in 0..600 {
        let (mut q, tau) = motion(&model, &mut data, k);
        // Joint 2 faster (about 0.5 rad/s at the freeze): a joint that slow cannot stop
        // within a period, so a repeated reading is not a reversal.
        q[2] = POSE[2] + 0.5 * (3.0 * k as f64 * 1e-3).sin();
        if (400..415).contains(&k) {
            if k == 400 {
                frozen_q = q[2];
            }
            q[2] = frozen_q;
        }
        let s = step_measured(&mut l, k, &q, &tau);
        if s.stale_input {
            flagged.push(k);
        }
        assert!(
            s.controller_fault.is_none(),
            "step {k}: {:?}",
            s.controller_fault
        );
    }
    assert!(!flagged.is_empty(), "never flagged");
    assert!(
        flagged.iter().all(|k| (405..415).contains(k)),
        "{flagged:?}"
    );
}

/// A floor calibrated on 60 s of a made-up false torque, uniform in +-0.05 N m.
fn noise_floor() -> admittance_control::ContactFloor {
    let (n, samples) = (7, 60_000);
    let mut state = 12345u64;
    let estimates: Vec<f64> = (0..n * samples)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            0.1 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        })
        .collect();
    let zeros = vec![0.0; n * samples];
    admittance_control::calibrate_contact(&estimates, &zeros, &zeros, n, 1e-3, 1.0).unwrap()
}

#[test]
fn with_the_floor_as_its_deadband_an_untouched_arm_stays_on_its_reference() {
    let floor = noise_floor();
    let lowest = floor
        .contact_thresholds
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min);
    let highest = floor.contact_thresholds.iter().cloned().fold(0.0, f64::max);
    let model = model();
    let mut data = Data::new(&model);
    // The measured torque misses a constant half of the lowest level on every joint (a model
    // error inside the floor) for 3 s, then a push of five times the highest level on joint 2.
    let mut run = |deadband: bool| -> (f64, f64) {
        let with = format!("contact.deadband={deadband}");
        let config = RobotConfig::from_toml_with(
            LOOP_TOML,
            Path::new("loop.toml"),
            &["contact.floor=\"floor.json\"", &with],
        )
        .unwrap();
        let mut l = RobotLoop::new(
            model.clone(),
            &config,
            Path::new("."),
            None,
            Some(floor.clone()),
        )
        .unwrap();
        let (mut untouched, mut pushed) = (0.0f64, 0.0f64);
        for k in 0..4000 {
            let q = POSE;
            let mut tau = [0.0; 7];
            tau.copy_from_slice(
                rnea(&model, &mut data, &q, &[0.0; 7], &[0.0; 7])
                    .unwrap()
                    .as_slice(),
            );
            for t in tau.iter_mut() {
                *t -= 0.5 * lowest;
            }
            if k >= 3000 {
                tau[1] -= 5.0 * highest;
            }
            let status = step_measured(&mut l, k, &q, &tau);
            // The touched link's wrench is zero until the push is flagged, then explains
            // joint 2's estimate from the two joints before the link.
            let contact = status.contact.expect("a floor was given");
            let wrench = l.contact_wrench().expect("a floor was given").0;
            if k < 3000 {
                assert!(
                    !contact.contact && wrench.iter().all(|w| *w == 0.0),
                    "step {k}"
                );
            } else if k == 3999 {
                assert!(contact.contact && contact.link == 1, "{contact:?}");
                // At the link's origin, on joint 2's axis, the smallest wrench that
                // explains a torque on joint 2 is a moment of about that torque.
                let moment = wrench[3..].iter().map(|m| m * m).sum::<f64>().sqrt();
                assert!(moment > 0.5 * 5.0 * highest, "{wrench:?}");
            }
            let offset = (l.reference()[0][1] - POSE[1]).abs();
            if k < 3000 {
                untouched = untouched.max(
                    l.reference()[0]
                        .iter()
                        .zip(POSE)
                        .fold(0.0, |m, (r, p)| m.max((r - p).abs())),
                );
            } else {
                pushed = pushed.max(offset);
            }
        }
        (untouched, pushed)
    };
    let (still, moved) = run(true);
    assert!(still < 1e-9, "drift with the deadband: {still} rad");
    // Its excess over the level (at least 3.75 levels) at a stiffness of 5 N m/rad, damped
    // over the second it lasts: still more than a tenth of a level's worth of radians.
    assert!(
        moved > 0.1 * highest,
        "the push moved joint 2 by {moved} rad"
    );
    let (drift, _) = run(false);
    assert!(
        drift > 1e-3,
        "without the deadband the false torque moves the arm: {drift} rad"
    );
}

/// Issue 34's attack campaign: a robot that reports velocities can report an absurd one. 20
/// samples of -1e300 rad/s on joint 2 are flagged as implausible velocities, the chain's own
/// velocity stands in for them, and the estimate stays with a clean run's.
#[test]
fn an_absurd_measured_velocity_is_flagged_and_not_integrated() {
    let model = model();
    let mut data = Data::new(&model);
    let run = |absurd: bool, data: &mut Data| {
        let mut l = robot_loop(&[]);
        let mut out = Vec::new();
        for k in 0..3000 {
            let (q, tau) = motion(&model, data, k);
            let t = k as f64 * 1e-3;
            let mut v = [0.0; 7];
            for (i, vi) in v.iter_mut().enumerate() {
                let w = 1.0 + 0.3 * i as f64;
                *vi = 0.1 * w * (w * t).cos();
            }
            if absurd && (1000..1020).contains(&k) {
                v[1] = -1e300;
            }
            let s = l.step(&RobotInput {
                time: t,
                q: &q,
                qdot: Some(&v),
                tau: Some(&tau),
                desired: None,
            });
            out.push((s.implausible, l.external_torque_estimate().to_vec()));
        }
        (out, l.implausible_samples())
    };
    let (clean, none) = run(false, &mut data);
    assert_eq!(none, 0);
    let (hit, count) = run(true, &mut data);
    assert_eq!(count, 20);
    for (g, _) in &hit[1000..1020] {
        let g = g.expect("flagged");
        assert_eq!((g.gate, g.joint), (Implausible::Velocity, 1));
    }
    let gap = (1000..3000)
        .map(|k| {
            (0..7)
                .map(|i| (hit[k].1[i] - clean[k].1[i]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(gap < 0.5, "estimate off a clean run by {gap} N m");
}

/// Issue 32, item 5: a component's key and hint reach the loop's one-line text (what
/// `adm_last_error`, Python and the command line show) under the component's table.
#[test]
fn a_components_key_and_hint_reach_the_loops_text() {
    let config = RobotConfig::from_toml_with(
        LOOP_TOML,
        Path::new("loop.toml"),
        &["admittance.saturation={ rho = 1.5, centre = 0.0, half_range = 1.0 }"],
    )
    .unwrap();
    let e = RobotLoop::new(model(), &config, Path::new("."), None, None)
        .err()
        .expect("rho 1.5 is refused");
    assert_eq!(e.key(), "admittance.saturation.rho", "{e}");
    assert!(
        e.text().ends_with("; hint: the paper uses 0.95"),
        "{}",
        e.text()
    );
}

/// Issue 32, item 5: a bad setting of a deployment folder is the one keyed shape, located
/// in its `loop.toml` by the reader, as one line with its fix (what `adm_last_error`,
/// Python and the command line show).
#[test]
fn a_bad_setting_of_a_deployment_is_located_in_its_loop_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("deploy");
    let file = dir.join("loop.toml").display().to_string();
    let deploy = |loop_toml: String| {
        let files = vec![
            ("loop.toml".to_string(), loop_toml.into_bytes()),
            ("arm.urdf".to_string(), std::fs::read(URDF).unwrap()),
        ];
        write_deployment(&dir, &files, serde_json::Value::Null).unwrap();
    };
    deploy(LOOP_TOML.replace("\ncutoff_hz = 5.0", "\ncutof_hz = 5.0"));
    let e = RobotLoop::load(&dir, &[]).err().expect("a misspelt key");
    assert_eq!(e.key(), "observer.cutof_hz", "{e}");
    let text = e.text();
    assert!(
        text.starts_with(&format!(
            "{file}: key `observer.cutof_hz`: unknown field `cutof_hz`"
        )) && text
            .ends_with("; hint: remove the key or fix its spelling; the expected keys are listed"),
        "{text}"
    );
    deploy(LOOP_TOML.to_string());
    let e = RobotLoop::load(&dir, &["signals.filter_cutoff_hz = 600"])
        .err()
        .expect("a cut-off above half the rate");
    assert_eq!(e.key(), "signals.filter_cutoff_hz", "{e}");
    assert_eq!(
        e.text(),
        format!(
            "{file}: key `signals.filter_cutoff_hz`: is 600, must be in [0, 500) Hz (half the control rate); hint: 0 disables the filter; 20 Hz is the default"
        )
    );
}

#[test]
fn an_angle_outside_the_identifications_training_range_is_flagged() {
    // The slow motion moves every joint 0.1 rad about the pose; an identification fitted on
    // joint 3 within +-0.05 rad of it sees that joint leave its range for part of the
    // motion, and nothing else. Without a recorded range nothing is ever flagged.
    let tmp = tempfile::tempdir().unwrap();
    let model = model();
    let mut ident = admittance_dynamics::Identification::from_model(model.clone());
    let save = |ident: &admittance_dynamics::Identification, name: &str| {
        save_identification(tmp.path(), &model, ident, name)
    };
    let unrecorded = save(&ident, "unrecorded.json");
    ident.summary.training_range = POSE.iter().map(|&p| [p - 1.0, p + 1.0]).collect();
    ident.summary.training_range[3] = [POSE[3] - 0.05, POSE[3] + 0.05];
    let narrow = save(&ident, "narrow.json");
    let flagged = |file: &str, joint3_only: bool| {
        let mut l = loop_on_identification(&model, file);
        let mut data = Data::new(&model);
        let mut count = 0;
        for k in 0..3000 {
            let (q, tau) = motion(&model, &mut data, k);
            let s = step_measured(&mut l, k, &q, &tau);
            // Beyond the range by more than the margin, 2 % of its 0.1 rad span.
            let outside = (q[3] - POSE[3]).abs() - 0.05 > 0.02 * 0.1;
            if joint3_only {
                assert_eq!(s.outside_training_range, outside, "step {k}");
            }
            count += usize::from(s.outside_training_range);
        }
        count
    };
    assert_eq!(flagged(&unrecorded, false), 0);
    assert!(flagged(&narrow, true) > 100);
}

#[test]
fn a_speed_beyond_the_identifications_training_speeds_is_flagged() {
    // The slow motion moves joint 3 at up to 0.19 rad/s; an identification trained on it at
    // up to 0.1 rad/s (every other joint at up to 1 rad/s) sees that joint faster than
    // trained (beyond the margin: 0.15 rad/s) for part of the motion, and nothing else. Without recorded speeds nothing is
    // ever flagged.
    let tmp = tempfile::tempdir().unwrap();
    let model = model();
    let mut ident = admittance_dynamics::Identification::from_model(model.clone());
    let save = |ident: &admittance_dynamics::Identification, name: &str| {
        save_identification(tmp.path(), &model, ident, name)
    };
    let unrecorded = save(&ident, "unrecorded.json");
    ident.summary.training_speed = vec![1.0; 7];
    ident.summary.training_speed[3] = 0.1;
    let slow = save(&ident, "slow.json");
    let flagged = |file: &str, joint3_only: bool| {
        let mut l = loop_on_identification(&model, file);
        let mut data = Data::new(&model);
        let (mut count, mut checked) = (0, 0);
        for k in 0..3000 {
            let (q, tau) = motion(&model, &mut data, k);
            let s = step_measured(&mut l, k, &q, &tau);
            // The exact speed; the observer's is filtered (10 Hz and the chain's 20 Hz, about
            // 0.01 rad/s behind at this speed), so steps near the threshold and the filters'
            // start are not judged.
            let w = 1.9;
            let speed = (0.1 * w * (w * k as f64 * 1e-3).cos()).abs();
            let threshold = 0.1 * (1.0 + admittance_dynamics::TRAINING_SPEED_MARGIN);
            if joint3_only && k > 300 && (speed - threshold).abs() > 0.02 {
                assert_eq!(
                    s.faster_than_training,
                    speed > threshold,
                    "step {k}: {speed}"
                );
                checked += 1;
            }
            count += usize::from(s.faster_than_training);
        }
        assert!(!joint3_only || checked > 1000, "{checked}");
        count
    };
    assert_eq!(flagged(&unrecorded, false), 0);
    assert!(flagged(&slow, true) > 300);
}

/// The arm with its last wrist joint made continuous (no position limits).
fn continuous_w2_model() -> Model {
    let text = std::fs::read_to_string(URDF).unwrap().replace(
        r#"<joint name="left_w2" type="revolute">"#,
        r#"<joint name="left_w2" type="continuous">"#,
    );
    Model::from_urdf_str(&text, URDF, Some("base"), Some("left_hand")).unwrap()
}

#[test]
fn a_continuous_joint_reported_wrapped_at_pi_runs_as_if_unwrapped() {
    // Baxter's last wrist joint made continuous, turning through +-pi at 0.8 rad/s.
    let model = continuous_w2_model();
    let mut data = Data::new(&model);
    let config = RobotConfig::from_toml_with(LOOP_TOML, Path::new("loop.toml"), &[]).unwrap();
    let wrap = |x: f64| x.sin().atan2(x.cos());
    let run = |wrapped: bool, data: &mut Data| {
        let mut l = RobotLoop::new(model.clone(), &config, Path::new("."), None, None).unwrap();
        let mut out = Vec::new();
        for k in 0..3000 {
            let (mut q, _) = motion(&model, data, k);
            let t = k as f64 * 1e-3;
            q[6] = 3.0 + 0.8 * t;
            let v = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.8];
            let mut tau = [0.0; 7];
            tau.copy_from_slice(rnea(&model, data, &q, &v, &[0.0; 7]).unwrap().as_slice());
            // The caller's desired angle 0.05 rad ahead, wrapped as the driver wraps.
            let mut q_d = q;
            q_d[6] += 0.05;
            if wrapped {
                q[6] = wrap(q[6]);
                q_d[6] = wrap(q_d[6]);
            }
            let s = l.step(&RobotInput {
                time: t,
                q: &q,
                qdot: None,
                tau: Some(&tau),
                desired: Some([&q_d, &v, &[0.0; 7]]),
            });
            out.push((
                s.implausible,
                l.torque().to_vec(),
                l.external_torque_estimate().to_vec(),
            ));
        }
        out
    };
    let straight = run(false, &mut data);
    let wrapped = run(true, &mut data);
    let mut gap: f64 = 0.0;
    for (k, (a, b)) in straight.iter().zip(&wrapped).enumerate() {
        assert_eq!(b.0, None, "step {k}: {:?}", b.0);
        for i in 0..7 {
            gap = gap
                .max((a.1[i] - b.1[i]).abs())
                .max((a.2[i] - b.2[i]).abs());
        }
    }
    eprintln!("wrapped against unwrapped: commands and estimates within {gap:.2e}");
    assert!(gap < 1e-6, "{gap}");
}

#[test]
fn a_continuous_joint_turned_past_pi_stays_inside_a_training_range_a_turn_wide() {
    // Baxter's last wrist joint made continuous, fitted over a turn of it ([-3.2, 3.2]), then
    // turned from 3 rad through +-pi, reported wrapped: the loop's branch runs on past pi,
    // where every angle is one the fit saw. A revolute joint's range holds no such turn.
    let model = continuous_w2_model();
    let tmp = tempfile::tempdir().unwrap();
    let mut ident = admittance_dynamics::Identification::from_model(model.clone());
    ident.summary.training_range = POSE.iter().map(|&p| [p - 1.0, p + 1.0]).collect();
    ident.summary.training_range[6] = [-3.2, 3.2];
    let file = save_identification(tmp.path(), &model, &ident, "turn.json");
    let mut l = loop_on_identification(&model, &file);
    let mut data = Data::new(&model);
    let wrap = |x: f64| x.sin().atan2(x.cos());
    let (mut flagged, mut past_pi) = (0, 0);
    for k in 0..3000 {
        let (mut q, tau) = motion(&model, &mut data, k);
        let angle = 3.0 + 0.8 * k as f64 * 1e-3;
        past_pi += usize::from(angle > 3.2 * 1.02);
        q[6] = wrap(angle);
        let s = step_measured(&mut l, k, &q, &tau);
        assert_eq!(s.implausible, None, "step {k}");
        flagged += usize::from(s.outside_training_range);
    }
    assert!(past_pi > 2000, "{past_pi}");
    assert_eq!(flagged, 0);
    // The same range for a joint that cannot turn: the angles past it are outside.
    let range = ident.summary.training_range[6];
    assert!(admittance_dynamics::outside_training_range(
        &[range],
        &[4.0],
        &[false]
    ));
    assert!(!admittance_dynamics::outside_training_range(
        &[range],
        &[4.0],
        &[true]
    ));
}
