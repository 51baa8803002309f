//! The safe behaviour on faults ("hold with damping") of every controller: NaN q, NaN
//! qdot, stale samples, non-finite references, wrong lengths, a diverged network; finite
//! torque within limits; adaptation frozen; recovery.

use crate::common;
use std::sync::Arc;

use admittance_control::*;
use admittance_dynamics::{gravity_torque, Data, Model};
use common::*;

fn controllers(model: &Arc<Model>) -> Vec<Box<dyn Controller>> {
    let hold = SafeHoldConfig {
        damping: 2.0.into(),
        stale_steps: 5,
        ..SafeHoldConfig::default()
    };
    vec![
        Box::new(
            NeuralController::new(
                model.clone(),
                &NeuralControllerConfig {
                    safe_hold: hold.clone(),
                    ..Default::default()
                },
            )
            .unwrap(),
        ),
        Box::new(
            PdController::new(
                model.clone(),
                &PdConfig {
                    kp: 50.0.into(),
                    kd: 5.0.into(),
                    gravity_compensation: false,
                    safe_hold: hold.clone(),
                },
            )
            .unwrap(),
        ),
        Box::new(
            PdController::new(
                model.clone(),
                &PdConfig {
                    kp: 50.0.into(),
                    kd: 5.0.into(),
                    gravity_compensation: true,
                    safe_hold: hold.clone(),
                },
            )
            .unwrap(),
        ),
        Box::new(
            ComputedTorqueController::new(
                model.clone(),
                &ComputedTorqueConfig {
                    kp: 50.0.into(),
                    kd: 10.0.into(),
                    safe_hold: hold,
                },
            )
            .unwrap(),
        ),
    ]
}

struct Sample {
    q: Vec<f64>,
    qdot: Vec<f64>,
    q_ref: Vec<f64>,
    qdot_ref: Vec<f64>,
    qddot_ref: Vec<f64>,
    est: Vec<f64>,
}

impl Sample {
    fn at(k: usize) -> Sample {
        let t = k as f64 * 1e-3;
        let (mut q, mut v, mut a) = (vec![0.0; 2], vec![0.0; 2], vec![0.0; 2]);
        sine(t, &mut q, &mut v, &mut a);
        Sample {
            q: q.iter().map(|x| x + 0.01).collect(),
            qdot: v.clone(),
            q_ref: q,
            qdot_ref: v,
            qddot_ref: a,
            est: vec![0.0; 2],
        }
    }
    fn input(&self) -> ControlInput<'_> {
        ControlInput {
            time: 0.0,
            q: &self.q,
            qdot: &self.qdot,
            q_ref: &self.q_ref,
            qdot_ref: &self.qdot_ref,
            qddot_ref: &self.qddot_ref,
            external_torque_estimate: &self.est,
        }
    }
}

/// The documented hold: G_nominal(q_hold) - K_hold qdot (qdot -> 0 if not finite), clamped.
fn expected_hold(model: &Model, q_hold: &[f64], qdot: &[f64], k_hold: f64) -> Vec<f64> {
    let mut data = Data::new(model);
    let g = gravity_torque(model, &mut data, q_hold).unwrap().clone();
    let limits: Vec<f64> = model.effort_limits().collect();
    (0..2)
        .map(|i| {
            let v = if qdot.len() == 2 && qdot[i].is_finite() {
                qdot[i]
            } else {
                0.0
            };
            (g[i] - k_hold * v).clamp(-limits[i], limits[i])
        })
        .collect()
}

fn check_valid(tau: &[f64], model: &Model) {
    for (t, l) in tau.iter().zip(model.effort_limits()) {
        assert!(t.is_finite() && t.abs() <= l, "torque {t} (limit {l})");
    }
}

#[test]
fn nan_position_triggers_the_hold_and_recovers() {
    let model = two_link();
    for mut c in controllers(&model) {
        let mut tau = [0.0; 2];
        let mut k = 0;
        for _ in 0..10 {
            assert!(
                c.step(&Sample::at(k).input(), 1e-3, &mut tau).is_ok(),
                "{}",
                c.name()
            );
            k += 1;
        }
        let last_valid_q = Sample::at(k - 1).q;
        let mut s = Sample::at(k);
        s.q[1] = f64::NAN;
        let status = c.step(&s.input(), 1e-3, &mut tau);
        assert_eq!(
            status.fault(),
            Some(Fault::NonFiniteMeasurement {
                argument: "q",
                joint: 1
            }),
            "{}",
            c.name()
        );
        check_valid(&tau, &model);
        let expect = expected_hold(&model, &last_valid_q, &s.qdot, 2.0);
        for i in 0..2 {
            assert!(
                (tau[i] - expect[i]).abs() < 1e-12,
                "{}: hold {tau:?} vs {expect:?}",
                c.name()
            );
        }
        // Infinity too.
        s.q[1] = f64::INFINITY;
        assert!(!c.step(&s.input(), 1e-3, &mut tau).is_ok());
        check_valid(&tau, &model);
        // Recovers at the first valid sample.
        k += 1;
        assert!(
            c.step(&Sample::at(k).input(), 1e-3, &mut tau).is_ok(),
            "{} recovers",
            c.name()
        );
        check_valid(&tau, &model);
    }
}

#[test]
fn nan_velocity_triggers_the_hold_with_zero_velocity() {
    let model = two_link();
    for mut c in controllers(&model) {
        let mut tau = [0.0; 2];
        assert!(c.step(&Sample::at(0).input(), 1e-3, &mut tau).is_ok());
        let mut s = Sample::at(1);
        s.qdot[0] = f64::NAN;
        let status = c.step(&s.input(), 1e-3, &mut tau);
        assert_eq!(
            status.fault(),
            Some(Fault::NonFiniteMeasurement {
                argument: "qdot",
                joint: 0
            })
        );
        // q itself was valid: it is the hold position; the NaN velocity counts as zero.
        let expect = expected_hold(&model, &s.q, &s.qdot, 2.0);
        assert!(
            (tau[0] - expect[0]).abs() < 1e-12 && (tau[1] - expect[1]).abs() < 1e-12,
            "{}",
            c.name()
        );
        assert!(c.step(&Sample::at(2).input(), 1e-3, &mut tau).is_ok());
    }
}

#[test]
fn stale_samples_trigger_the_hold_and_recover() {
    let model = two_link();
    for mut c in controllers(&model) {
        let mut tau = [0.0; 2];
        for k in 0..20 {
            assert!(c.step(&Sample::at(k).input(), 1e-3, &mut tau).is_ok());
        }
        // The sensor freezes: q repeats while the reference keeps moving.
        let frozen_q = Sample::at(19).q;
        let mut statuses = Vec::new();
        for k in 20..30 {
            let mut s = Sample::at(k);
            s.q = frozen_q.clone();
            statuses.push(c.step(&s.input(), 1e-3, &mut tau));
            check_valid(&tau, &model);
        }
        // stale_steps = 5: the 5th repeated sample is the first fault.
        assert!(
            statuses[..4].iter().all(|s| s.is_ok()),
            "{}: {statuses:?}",
            c.name()
        );
        assert_eq!(
            statuses[4].fault(),
            Some(Fault::StaleMeasurement { joint: 0, steps: 5 })
        );
        assert!(statuses[4..]
            .iter()
            .all(|s| matches!(s.fault(), Some(Fault::StaleMeasurement { .. }))));
        let s = Sample::at(29);
        let expect = expected_hold(&model, &frozen_q, &s.qdot, 2.0);
        assert!((tau[0] - expect[0]).abs() < 1e-12 && (tau[1] - expect[1]).abs() < 1e-12);
        // A fresh sample ends the fault.
        assert!(
            c.step(&Sample::at(30).input(), 1e-3, &mut tau).is_ok(),
            "{} recovers",
            c.name()
        );
    }
}

/// Issue 14: one joint frozen while the others move, and repeated 10 ms dropouts, were not
/// detected (staleness needed the whole position vector to repeat; at least 50 steps).
#[test]
fn one_frozen_joint_and_short_dropouts_are_stale_and_named() {
    let model = two_link();
    for mut c in controllers(&model) {
        let mut tau = [0.0; 2];
        // Joint 1 freezes for 100 ms at t = 0.5 s (it moves at about 0.9 rad/s there);
        // joint 0 keeps reporting fresh samples.
        let frozen = Sample::at(500).q[1];
        let mut stale = Vec::new();
        for k in 400..600 {
            let mut s = Sample::at(k);
            if (500..600).contains(&k) {
                s.q[1] = frozen;
            }
            let status = c.step(&s.input(), 1e-3, &mut tau);
            check_valid(&tau, &model);
            if let Some(Fault::StaleMeasurement { joint, .. }) = status.fault() {
                assert_eq!(joint, 1, "{}", c.name());
                stale.push(k);
            }
        }
        // The 5th repeated sample (k = 505) is the first fault, every later one too.
        assert_eq!(stale, (505..600).collect::<Vec<_>>(), "{}", c.name());
        // Twenty dropouts of 10 ms: each is detected.
        let mut detected = 0;
        for d in 0..20 {
            let start = 1000 + 50 * d;
            let held = Sample::at(start).q.clone();
            let mut seen = false;
            for k in start..start + 50 {
                let mut s = Sample::at(k);
                if k < start + 10 {
                    s.q = held.clone();
                }
                seen |= matches!(
                    c.step(&s.input(), 1e-3, &mut tau).fault(),
                    Some(Fault::StaleMeasurement { .. })
                );
            }
            detected += usize::from(seen);
        }
        assert_eq!(detected, 20, "{}", c.name());
    }
}

/// A frozen reading of a joint that was moving is stale even when its reference slows
/// meanwhile (in the loop a frozen encoder reads like a contact to the observer, and the
/// admittance model slows the reference: 40 frozen periods at 0.49 rad/s went unreported);
/// a joint that slows to rest and stays there is not.
#[test]
fn a_joint_frozen_while_moving_is_stale_though_its_reference_slows() {
    let model = two_link();
    for mut c in controllers(&model) {
        let mut tau = [0.0; 2];
        for k in 400..500 {
            assert!(c.step(&Sample::at(k).input(), 1e-3, &mut tau).is_ok());
        }
        let frozen = Sample::at(500).q[1];
        let mut stale = Vec::new();
        for k in 500..530 {
            let mut s = Sample::at(k);
            s.q[1] = frozen;
            // The reference of the frozen joint stops at once.
            s.qdot_ref[1] = 0.0;
            if let Some(Fault::StaleMeasurement { joint, .. }) =
                c.step(&s.input(), 1e-3, &mut tau).fault()
            {
                assert_eq!(joint, 1);
                stale.push(k);
            }
        }
        assert_eq!(stale, (505..530).collect::<Vec<_>>(), "{}", c.name());

        // Slowing to rest (speed falling linearly to zero over 200 periods) with the
        // reference at rest, then resting: no fault.
        c.reset();
        let q0 = Sample::at(0).q.clone();
        for k in 0..400 {
            let mut s = Sample::at(0);
            let t = (k.min(200)) as f64 * 1e-3;
            s.q[1] = q0[1] + 0.5 * (t - t * t / 0.4);
            s.qdot_ref = vec![0.0; 2];
            s.q_ref = s.q.clone();
            let status = c.step(&s.input(), 1e-3, &mut tau);
            assert!(status.is_ok(), "{} at {k}: {status:?}", c.name());
        }
    }
}

#[test]
fn a_robot_at_rest_is_not_stale() {
    // Identical samples with no motion expected (zero reference and measured velocity) are fine.
    let model = two_link();
    for mut c in controllers(&model) {
        let s = Sample {
            q: vec![0.1, 0.2],
            qdot: vec![0.0; 2],
            q_ref: vec![0.1, 0.2],
            qdot_ref: vec![0.0; 2],
            qddot_ref: vec![0.0; 2],
            est: vec![0.0; 2],
        };
        let mut tau = [0.0; 2];
        for _ in 0..100 {
            assert!(c.step(&s.input(), 1e-3, &mut tau).is_ok());
        }
    }
}

#[test]
fn bad_references_lengths_and_steps_are_faults() {
    let model = two_link();
    for mut c in controllers(&model) {
        let mut tau = [0.0; 2];
        assert!(c.step(&Sample::at(0).input(), 1e-3, &mut tau).is_ok());
        let mut s = Sample::at(1);
        s.qddot_ref[1] = f64::NAN;
        assert_eq!(
            c.step(&s.input(), 1e-3, &mut tau).fault(),
            Some(Fault::NonFiniteReference {
                argument: "qddot_ref",
                joint: 1
            })
        );
        check_valid(&tau, &model);
        let mut s = Sample::at(2);
        s.q_ref[0] = f64::NEG_INFINITY;
        assert_eq!(
            c.step(&s.input(), 1e-3, &mut tau).fault(),
            Some(Fault::NonFiniteReference {
                argument: "q_ref",
                joint: 0
            })
        );
        let mut s = Sample::at(3);
        s.est[0] = f64::NAN;
        assert_eq!(
            c.step(&s.input(), 1e-3, &mut tau).fault(),
            Some(Fault::NonFiniteEstimate { joint: 0 })
        );
        let mut s = Sample::at(4);
        s.qdot_ref = vec![0.0; 3];
        assert_eq!(
            c.step(&s.input(), 1e-3, &mut tau).fault(),
            Some(Fault::WrongLength {
                argument: "qdot_ref",
                expected: 2,
                found: 3
            })
        );
        check_valid(&tau, &model);
        assert_eq!(
            c.step(&Sample::at(5).input(), 0.0, &mut tau).fault(),
            Some(Fault::InvalidTimeStep)
        );
        assert_eq!(
            c.step(&Sample::at(5).input(), f64::NAN, &mut tau).fault(),
            Some(Fault::InvalidTimeStep)
        );
        // A wrong torque buffer: never panics, the extra entry is zeroed.
        let mut long = [7.0; 3];
        assert_eq!(
            c.step(&Sample::at(6).input(), 1e-3, &mut long).fault(),
            Some(Fault::WrongLength {
                argument: "torque",
                expected: 2,
                found: 3
            })
        );
        assert_eq!(long[2], 0.0);
        assert!(long.iter().all(|t| t.is_finite()));
        let mut short = [7.0; 1];
        assert!(!c.step(&Sample::at(7).input(), 1e-3, &mut short).is_ok());
        assert!(short[0].is_finite());
        // Recovers.
        assert!(c.step(&Sample::at(8).input(), 1e-3, &mut tau).is_ok());
    }
}

#[test]
fn adaptation_is_frozen_while_faulted() {
    let model = two_link();
    let mut c = NeuralController::new(model.clone(), &NeuralControllerConfig::default()).unwrap();
    let mut tau = [0.0; 2];
    for k in 0..50 {
        assert!(c.step(&Sample::at(k).input(), 1e-3, &mut tau).is_ok());
    }
    let wf = c.network(NetworkId::F).unwrap().weights().to_vec();
    let wt = c.network(NetworkId::Deadzone).unwrap().weights().to_vec();
    for k in 50..100 {
        let mut s = Sample::at(k);
        s.qdot[1] = f64::NAN;
        assert!(!c.step(&s.input(), 1e-3, &mut tau).is_ok());
    }
    assert_eq!(c.network(NetworkId::F).unwrap().weights(), &wf[..]);
    assert_eq!(c.network(NetworkId::Deadzone).unwrap().weights(), &wt[..]);
    assert_eq!(c.safe_hold().fault_count(), 50);
    assert!(c.step(&Sample::at(100).input(), 1e-3, &mut tau).is_ok());
    assert_ne!(
        c.network(NetworkId::F).unwrap().weights(),
        &wf[..],
        "adaptation resumes"
    );
}

#[test]
fn a_diverged_network_gives_the_hold_not_nan() {
    let model = two_link();
    let mut c = NeuralController::new(model.clone(), &NeuralControllerConfig::default()).unwrap();
    let mut tau = [0.0; 2];
    assert!(c.step(&Sample::at(0).input(), 1e-3, &mut tau).is_ok());
    c.network_mut(NetworkId::F)
        .unwrap()
        .weights_mut()
        .fill(f64::NAN);
    let status = c.step(&Sample::at(1).input(), 1e-3, &mut tau);
    assert!(
        matches!(
            status.fault(),
            Some(Fault::NonFiniteOutput { .. }) | Some(Fault::Internal(_))
        ),
        "{status:?}"
    );
    check_valid(&tau, &model);
    // The diverged network was zeroed: the next step runs the law again.
    assert!(c
        .network(NetworkId::F)
        .unwrap()
        .weights()
        .iter()
        .all(|w| *w == 0.0));
    assert!(c.step(&Sample::at(2).input(), 1e-3, &mut tau).is_ok());
    // Huge (finite) weights: the output is clamped, never NaN.
    c.network_mut(NetworkId::F)
        .unwrap()
        .weights_mut()
        .fill(1e300);
    let _ = c.step(&Sample::at(2).input(), 1e-3, &mut tau);
    check_valid(&tau, &model);
    c.reset();
    assert!(
        c.step(&Sample::at(3).input(), 1e-3, &mut tau).is_ok(),
        "reset restores the initial weights"
    );
}

#[test]
fn hold_is_clamped_on_a_heavy_arm() {
    // Baxter's s1 gravity (about -52.9 N m at q = 0) exceeds its 50 N m limit: clamped.
    let model = baxter();
    let mut pd = PdController::new(
        model.clone(),
        &PdConfig {
            kp: 10.0.into(),
            kd: 1.0.into(),
            gravity_compensation: true,
            safe_hold: SafeHoldConfig::default(),
        },
    )
    .unwrap();
    let zero = [0.0; 7];
    let mut q = [0.0; 7];
    let mut tau = [0.0; 7];
    let input = ControlInput {
        time: 0.0,
        q: &zero,
        qdot: &zero,
        q_ref: &zero,
        qdot_ref: &zero,
        qddot_ref: &zero,
        external_torque_estimate: &zero,
    };
    assert!(pd.step(&input, 1e-3, &mut tau).is_ok());
    q[3] = f64::NAN;
    let bad = ControlInput { q: &q, ..input };
    assert!(!pd.step(&bad, 1e-3, &mut tau).is_ok());
    let limits: Vec<f64> = model.effort_limits().collect();
    assert_eq!(tau[1], -limits[1]);
    for (t, l) in tau.iter().zip(&limits) {
        assert!(t.is_finite() && t.abs() <= *l);
    }
}

#[test]
fn before_any_valid_sample_the_hold_is_pure_damping() {
    let model = two_link();
    let mut c = PdController::new(
        model.clone(),
        &PdConfig {
            kp: 1.0.into(),
            kd: 1.0.into(),
            gravity_compensation: false,
            safe_hold: SafeHoldConfig {
                damping: 2.0.into(),
                ..SafeHoldConfig::default()
            },
        },
    )
    .unwrap();
    let mut s = Sample::at(0);
    s.q[0] = f64::NAN;
    s.qdot = vec![0.5, -0.25];
    let mut tau = [9.0; 2];
    assert!(!c.step(&s.input(), 1e-3, &mut tau).is_ok());
    assert_eq!(tau, [-1.0, 0.5]);
}
