//! The task-space admittance (issue 16 part 1; docs/method.md section 2, task-space variant): the
//! admittance equation at the hand, the wrench estimate `J^#T tau_ext_hat`, hand guiding,
//! singular poses, the null-space posture, the joint saturation, exactness without a
//! wrench, faults, and the surface shared with the joint-space model.

use crate::common;
use std::sync::Arc;

use admittance_control::*;
use admittance_dynamics::{forward_kinematics, tip_jacobian, Data, Model, Transform};
use common::{baxter, two_link};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3, Vector6};

const DT: f64 = 1e-3;
/// Experiment A's pose of the Baxter arm (well away from singularities: smallest singular
/// value of the hand Jacobian about 0.2).
const PAPER_POSE: [f64; 7] = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];

fn hand(model: &Model, q: &[f64]) -> Transform {
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, q).unwrap();
    *data.tip_placement(model)
}

/// `tau = J(q)^T f`: the joint torque of a wrench `f` at the hand.
fn torque_of(model: &Model, q: &[f64], f: &Vector6<f64>) -> Vec<f64> {
    let mut data = Data::new(model);
    let j = tip_jacobian(model, &mut data, q).unwrap();
    (0..model.nq()).map(|c| j.column(c).dot(f)).collect()
}

/// The rotation vector of `a b^T`.
fn rotation_between(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Vector3<f64> {
    let r = nalgebra::Rotation3::from_matrix_unchecked(a * b.transpose());
    r.scaled_axis()
}

fn no_saturation() -> TaskSpaceAdmittanceConfig {
    TaskSpaceAdmittanceConfig {
        saturation: TaskSaturationConfig::None,
        ..TaskSpaceAdmittanceConfig::default()
    }
}

/// Steps `adm` with a constant desired pose `q_d`, the measured position following the
/// reference (`q = q_r` of the previous step: perfect tracking), and the estimate of the
/// wrench `force(k)` at the measured position; calls `each` after every step.
fn push(
    adm: &mut TaskSpaceAdmittance,
    model: &Model,
    q_d: &[f64],
    steps: usize,
    force: impl Fn(usize) -> Vector6<f64>,
    mut each: impl FnMut(usize, &TaskSpaceAdmittance),
) {
    let n = model.nq();
    let zero = vec![0.0; n];
    let mut q = q_d.to_vec();
    for k in 0..steps {
        let tau = torque_of(model, &q, &force(k));
        let input = TaskSpaceInput {
            q_d,
            qdot_d: &zero,
            qddot_d: &zero,
            q: &q,
            external_torque_estimate: &tau,
        };
        assert!(adm.step(&input, DT).is_ok(), "step {k}");
        q.copy_from_slice(adm.q_r());
        each(k, adm);
    }
}

#[test]
fn the_wrench_estimate_inverts_the_jacobian_transpose_and_the_hand_obeys_the_admittance() {
    let model = baxter();
    let f = Vector6::new(10.0, -5.0, 8.0, 0.5, 0.0, -0.3);
    // Held at the paper's pose (the measured q does not move: a stiff environment), the
    // estimate is constant and each axis is C_d dx' + G_d dx = f from rest:
    // dx(t) = f / G_d (1 - exp(-G_d t / C_d)).
    let tau = torque_of(&model, &PAPER_POSE, &f);
    let mut adm = TaskSpaceAdmittance::new(model.clone(), &no_saturation()).unwrap();
    let zero = [0.0; 7];
    let (c, g) = (
        [60.0, 60.0, 60.0, 6.0, 6.0, 6.0],
        [100.0, 100.0, 100.0, 10.0, 10.0, 10.0],
    );
    let x_d = hand(&model, &PAPER_POSE);
    for k in 0..3000 {
        let input = TaskSpaceInput {
            q_d: &PAPER_POSE,
            qdot_d: &zero,
            qddot_d: &zero,
            q: &PAPER_POSE,
            external_torque_estimate: &tau,
        };
        assert!(adm.step(&input, DT).is_ok());
        let w = adm.wrench_estimate();
        for i in 0..6 {
            assert!((w[i] - f[i]).abs() < 1e-9 * f.norm(), "wrench {w:?}");
        }
        assert_eq!(adm.wrench_damping(), 0.0);
        let t = (k + 1) as f64 * DT;
        let dx = adm.deviation();
        for i in 0..6 {
            let exact = f[i] / g[i] * (1.0 - (-g[i] * t / c[i]).exp());
            assert!(
                (dx[i] - exact).abs() < 1e-12,
                "axis {i} at {t} s: {} vs {exact}",
                dx[i]
            );
            let rate = (f[i] - g[i] * exact) / c[i];
            assert!((adm.compliant_twist()[i] - rate).abs() < 1e-10);
        }
        // x_r = x_d (+) dx: position added, rotation Exp(dtheta) R_d.
        let pose = adm.compliant_pose();
        let dp = pose.translation - x_d.translation;
        let dtheta = rotation_between(&pose.rotation, &x_d.rotation);
        for i in 0..3 {
            assert!((dp[i] - dx[i]).abs() < 1e-12 && (dtheta[i] - dx[3 + i]).abs() < 1e-12);
        }
    }
    // The joints follow: FK(q_r) is x_r.
    let reached = hand(&model, adm.q_r());
    let pose = adm.compliant_pose();
    assert!((reached.translation - pose.translation).norm() < 1e-5);
    assert!(rotation_between(&reached.rotation, &pose.rotation).norm() < 1e-5);
}

/// Largest deviation error against the exact solution of `m x'' + c x' + g x = f` from rest
/// (underdamped here) over 2 s with step `dt`.
fn second_order_error(dt: f64) -> f64 {
    let model = baxter();
    let cfg = TaskSpaceAdmittanceConfig {
        linear: AxisAdmittanceConfig {
            damping: 10.0.into(),
            stiffness: 100.0.into(),
            inertia: Some(2.0.into()),
        },
        angular: AxisAdmittanceConfig {
            damping: 0.5.into(),
            stiffness: 10.0.into(),
            inertia: Some(0.05.into()),
        },
        ..no_saturation()
    };
    let mut adm = TaskSpaceAdmittance::new(model.clone(), &cfg).unwrap();
    let f = Vector6::new(0.0, 6.0, 0.0, 0.0, 0.4, 0.0);
    let tau = torque_of(&model, &PAPER_POSE, &f);
    let zero = [0.0; 7];
    let exact = |m: f64, c: f64, g: f64, f: f64, t: f64| {
        // Underdamped: x = x_ss (1 - e^{-a t} (cos(w t) + a / w sin(w t))).
        let (a, w) = (c / (2.0 * m), (g / m - (c / (2.0 * m)).powi(2)).sqrt());
        f / g * (1.0 - (-a * t).exp() * ((w * t).cos() + a / w * (w * t).sin()))
    };
    let mut worst: f64 = 0.0;
    let steps = (2.0 / dt).round() as usize;
    for k in 0..steps {
        let input = TaskSpaceInput {
            q_d: &PAPER_POSE,
            qdot_d: &zero,
            qddot_d: &zero,
            q: &PAPER_POSE,
            external_torque_estimate: &tau,
        };
        assert!(adm.step(&input, dt).is_ok());
        let t = (k + 1) as f64 * dt;
        worst = worst
            .max((adm.deviation()[1] - exact(2.0, 10.0, 100.0, 6.0, t)).abs() / 0.06)
            .max((adm.deviation()[4] - exact(0.05, 0.5, 10.0, 0.4, t)).abs() / 0.04);
    }
    worst
}

#[test]
fn with_inertia_the_hand_converges_to_the_second_order_admittance() {
    // Backward Euler is first order: the error (relative to the steady state) is small and
    // halves with the step.
    let (coarse, fine) = (second_order_error(2e-3), second_order_error(1e-3));
    assert!(fine < 0.02, "relative error {fine}");
    let ratio = coarse / fine;
    assert!(
        (1.7..2.3).contains(&ratio),
        "error ratio {ratio} for a halved step"
    );
}

#[test]
fn a_pushed_hand_yields_in_the_pushed_direction() {
    let model = baxter();
    let x_d = hand(&model, &PAPER_POSE);
    // A 10 N push along +y: the hand moves along +y by about f / G_d = 0.1 m.
    let mut adm =
        TaskSpaceAdmittance::new(model.clone(), &TaskSpaceAdmittanceConfig::default()).unwrap();
    push(
        &mut adm,
        &model,
        &PAPER_POSE,
        4000,
        |_| Vector6::new(0.0, 10.0, 0.0, 0.0, 0.0, 0.0),
        |_, _| {},
    );
    let x = hand(&model, adm.q_r());
    let d = x.translation - x_d.translation;
    assert!(d.y > 0.098 && d.y < 0.1, "moved {d}");
    assert!(d.x.abs() < 1e-4 && d.z.abs() < 1e-4, "moved {d}");
    assert!(rotation_between(&x.rotation, &x_d.rotation).norm() < 1e-4);
    // A 1 N m moment about z turns the hand about z by about 0.1 rad, in place.
    let mut adm =
        TaskSpaceAdmittance::new(model.clone(), &TaskSpaceAdmittanceConfig::default()).unwrap();
    push(
        &mut adm,
        &model,
        &PAPER_POSE,
        4000,
        |_| Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        |_, _| {},
    );
    let x = hand(&model, adm.q_r());
    let turn = rotation_between(&x.rotation, &x_d.rotation);
    assert!(
        turn.z > 0.098 && turn.z < 0.1 && turn.x.abs() < 1e-4 && turn.y.abs() < 1e-4,
        "{turn}"
    );
    assert!((x.translation - x_d.translation).norm() < 1e-4);
    // A planar two-joint arm with the task on x and z: a push along +x moves the hand +x.
    let arm = two_link();
    let cfg = TaskSpaceAdmittanceConfig {
        task_axes: vec![TaskAxis::X, TaskAxis::Z],
        ..TaskSpaceAdmittanceConfig::default()
    };
    let mut adm = TaskSpaceAdmittance::new(arm.clone(), &cfg).unwrap();
    // (Elbow bent 90 degrees: the smallest singular value, 0.2, is above the damping
    // threshold, so the estimate is exact.)
    let q_d = [0.3, 1.6];
    push(
        &mut adm,
        &arm,
        &q_d,
        4000,
        |_| Vector6::new(5.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        |_, adm| {
            // On a two-joint arm the wrench is estimated on the task axes x and z.
            let w = adm.wrench_estimate();
            assert!(
                (w[0] - 5.0).abs() < 1e-9 && w[2].abs() < 1e-9 && w[4] == 0.0,
                "{w:?}"
            );
        },
    );
    let d = hand(&arm, adm.q_r()).translation - hand(&arm, &q_d).translation;
    assert!(d.x > 0.049 && d.x < 0.05 && d.z.abs() < 1e-4, "moved {d}");
}

#[test]
fn zero_stiffness_is_hand_guiding() {
    let model = baxter();
    let cfg = TaskSpaceAdmittanceConfig {
        linear: AxisAdmittanceConfig {
            damping: 60.0.into(),
            stiffness: 0.0.into(),
            inertia: None,
        },
        ..TaskSpaceAdmittanceConfig::default()
    };
    let mut adm = TaskSpaceAdmittance::new(model.clone(), &cfg).unwrap();
    // A person pushes with 10 N along x for 1 s, then lets go for 2 s.
    let pushing = |k: usize| k < 1000;
    let mut hand_at_release = None;
    let mut hand_before_end = None;
    push(
        &mut adm,
        &model,
        &PAPER_POSE,
        3000,
        |k| Vector6::new(if pushing(k) { 10.0 } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0),
        |k, adm| {
            let t = (k + 1) as f64 * DT;
            let dx = adm.deviation()[0];
            if pushing(k) {
                // Drifts with the force: dx = f t / C_d.
                assert!((dx - 10.0 * t / 60.0).abs() < 1e-9, "{dx} at {t}");
                assert!((adm.compliant_twist()[0] - 10.0 / 60.0).abs() < 1e-9);
            } else {
                // Released: stops where it was.
                assert!((dx - 10.0 / 60.0).abs() < 1e-9, "{dx} at {t}");
                assert!(adm.compliant_twist()[0].abs() < 1e-12);
            }
            if k == 1999 {
                hand_at_release = Some(hand(&model, adm.q_r()).translation);
            }
            if k == 2999 {
                hand_before_end = Some(hand(&model, adm.q_r()).translation);
            }
        },
    );
    let x_d = hand(&model, &PAPER_POSE).translation;
    let end = hand_before_end.unwrap();
    assert!(
        ((end - x_d) - Vector3::new(10.0 / 60.0, 0.0, 0.0)).norm() < 1e-4,
        "{}",
        end - x_d
    );
    // The hand stays still in the last second.
    assert!((end - hand_at_release.unwrap()).norm() < 1e-4);
    assert!(
        adm.qdot_r().iter().all(|v| v.abs() < 1e-3),
        "{:?}",
        adm.qdot_r()
    );
}

/// The norm of `J^+T tau` with the plain (undamped) pseudo-inverse.
fn undamped_wrench_norm(model: &Model, q: &[f64], rows: &[usize], tau: &[f64]) -> f64 {
    let mut data = Data::new(model);
    let j = tip_jacobian(model, &mut data, q).unwrap();
    let js = DMatrix::from_fn(rows.len(), model.nq(), |r, c| j[(rows[r], c)]);
    let pinv_t = js.pseudo_inverse(0.0).unwrap().transpose();
    (pinv_t * DVector::from_column_slice(tau)).norm()
}

fn smallest_singular_value(model: &Model, q: &[f64], rows: &[usize]) -> f64 {
    let mut data = Data::new(model);
    let j = tip_jacobian(model, &mut data, q).unwrap();
    let js = DMatrix::from_fn(rows.len(), model.nq(), |r, c| j[(rows[r], c)]);
    js.singular_values().min()
}

#[test]
fn a_singular_pose_keeps_the_estimate_and_the_reference_bounded() {
    // The planar arm stretched out (q2 = 0) is singular for the hand position: the two
    // columns of J are parallel, the smallest singular value is 0.
    let arm = two_link();
    let cfg = TaskSpaceAdmittanceConfig {
        task_axes: vec![TaskAxis::X, TaskAxis::Z],
        ..TaskSpaceAdmittanceConfig::default()
    };
    let tau = [3.0, -2.0];
    let tau_norm = (13.0f64).sqrt();
    let threshold = cfg.wrench_damping.threshold;
    // Near the singularity the plain pseudo-inverse explodes.
    assert!(undamped_wrench_norm(&arm, &[0.3, 1e-6], &[0, 2], &tau) > 1e5 * tau_norm);
    for q in [[0.3, 0.0], [0.3, 1e-6], [0.3, 0.01], [-1.0, 0.0]] {
        let mut adm = TaskSpaceAdmittance::new(arm.clone(), &cfg).unwrap();
        let input = TaskSpaceInput {
            q_d: &q,
            qdot_d: &[0.0; 2],
            qddot_d: &[0.0; 2],
            q: &q,
            external_torque_estimate: &tau,
        };
        assert!(adm.step(&input, DT).is_ok());
        let w = Vector6::from_column_slice(adm.wrench_estimate());
        // Bounded by |tau| / threshold (max_damping = threshold).
        assert!(
            w.iter().all(|v| v.is_finite()) && w.norm() <= tau_norm / threshold * (1.0 + 1e-9),
            "{q:?}: {w}"
        );
        assert!(smallest_singular_value(&arm, &q, &[0, 2]) < 0.01);
        assert!(
            adm.wrench_damping() > 0.09,
            "damping {}",
            adm.wrench_damping()
        );
        assert!(adm.q_r().iter().all(|v| v.is_finite()));
    }
    // Baxter stretched out (q = 0: smallest singular value 0.024, below the threshold 0.1).
    let model = baxter();
    let tau7 = [2.0, -1.0, 0.5, 3.0, -0.2, 0.4, 0.1];
    let norm7 = tau7.iter().map(|t| t * t).sum::<f64>().sqrt();
    let mut adm =
        TaskSpaceAdmittance::new(model.clone(), &TaskSpaceAdmittanceConfig::default()).unwrap();
    let zero = [0.0; 7];
    let input = TaskSpaceInput {
        q_d: &zero,
        qdot_d: &zero,
        qddot_d: &zero,
        q: &zero,
        external_torque_estimate: &tau7,
    };
    assert!(adm.step(&input, DT).is_ok());
    let w = Vector6::from_column_slice(adm.wrench_estimate());
    assert!(w.norm() <= norm7 / 0.1 * (1.0 + 1e-9), "{w}");
    assert!(adm.wrench_damping() > 0.0 && adm.ik_damping() > 0.0);
    assert!(undamped_wrench_norm(&model, &zero, &[0, 1, 2, 3, 4, 5], &tau7) > w.norm());

    // Closed loop on the planar arm: the desired motion sweeps through the singularity
    // (q2 = 0.5 sin(2 t)) while a steady torque pushes; everything stays finite and bounded.
    let mut adm = TaskSpaceAdmittance::new(arm.clone(), &cfg).unwrap();
    let mut q = [0.3, 0.5];
    let mut worst_wrench: f64 = 0.0;
    let mut worst_speed: f64 = 0.0;
    for k in 0..6000 {
        let t = k as f64 * DT;
        let q_d = [0.3, 0.5 * (2.0 * t).sin()];
        let qd_d = [0.0, (2.0 * t).cos()];
        let qdd_d = [0.0, -2.0 * (2.0 * t).sin()];
        let input = TaskSpaceInput {
            q_d: &q_d,
            qdot_d: &qd_d,
            qddot_d: &qdd_d,
            q: &q,
            external_torque_estimate: &tau,
        };
        assert!(adm.step(&input, DT).is_ok(), "step {k}");
        q = [adm.q_r()[0], adm.q_r()[1]];
        worst_wrench = worst_wrench.max(Vector6::from_column_slice(adm.wrench_estimate()).norm());
        worst_speed = worst_speed.max(adm.qdot_r().iter().fold(0.0, |m: f64, v| m.max(v.abs())));
        assert!(adm
            .q_r()
            .iter()
            .chain(adm.qdot_r())
            .chain(adm.qddot_r())
            .all(|v| v.is_finite()));
        assert!(adm.q_r().iter().all(|v| v.abs() < 3.0), "{:?}", adm.q_r());
    }
    assert!(
        worst_wrench <= tau_norm / threshold * (1.0 + 1e-9),
        "{worst_wrench}"
    );
    assert!(worst_speed < 20.0, "joint speed {worst_speed} rad/s");
}

/// `|N dq|` and `|dq|` with `N = I - J^+ J` at `q_a`: the part of the joint deviation that
/// does not move the hand.
fn null_space_part(model: &Model, q_a: &[f64], q_d: &[f64]) -> (f64, f64) {
    let mut data = Data::new(model);
    let j = tip_jacobian(model, &mut data, q_a).unwrap();
    let j = DMatrix::from_fn(6, model.nq(), |r, c| j[(r, c)]);
    let dq = DVector::from_iterator(q_a.len(), q_a.iter().zip(q_d).map(|(a, d)| a - d));
    let pinv = j.clone().pseudo_inverse(1e-12).unwrap();
    ((&dq - pinv * (&j * &dq)).norm(), dq.norm())
}

#[test]
fn a_redundant_arm_holds_its_posture_in_the_null_space() {
    let model = baxter();
    let f = Vector6::new(10.0, -5.0, 8.0, 0.5, 0.0, -0.3);
    let mut parts = Vec::new();
    for posture in [true, false] {
        let mut cfg = TaskSpaceAdmittanceConfig::default();
        if !posture {
            cfg.inverse_kinematics.posture_position_gain = 0.0;
            cfg.inverse_kinematics.posture_velocity_gain = 0.0;
        }
        let mut adm = TaskSpaceAdmittance::new(model.clone(), &cfg).unwrap();
        push(&mut adm, &model, &PAPER_POSE, 4000, |_| f, |_, _| {});
        // The hand reached x_r either way.
        let reached = hand(&model, adm.q_r()).translation;
        assert!((reached - adm.compliant_pose().translation).norm() < 1e-5);
        parts.push(null_space_part(&model, adm.q_a(), &PAPER_POSE));
    }
    let ((held, moved), (free, _)) = (parts[0], parts[1]);
    // With the posture term the joints move only as much as the hand needs.
    assert!(held < 1e-3 * moved, "null-space part {held} of {moved}");
    // Without it, the self-motion wanders off (the test would catch a missing term).
    assert!(
        free > 0.1,
        "null-space part without the posture term {free}"
    );
}

#[test]
fn the_saturation_keeps_q_r_inside_the_joint_limits() {
    let model = baxter();
    let limits: Vec<(f64, f64)> = model.position_limits().collect();
    // Hand guiding in rotation, turned about the tool axis by a steady -3 N m: the wrist
    // roll w2 (at -0.5 rad, limit -3.059) is driven past its limit within about 3 s.
    let cfg = TaskSpaceAdmittanceConfig {
        angular: AxisAdmittanceConfig {
            damping: 3.0.into(),
            stiffness: 0.0.into(),
            inertia: None,
        },
        ..TaskSpaceAdmittanceConfig::default()
    };
    let tool_axis = hand(&model, &PAPER_POSE).rotation.column(2).into_owned();
    let moment = tool_axis * -3.0;
    let mut adm = TaskSpaceAdmittance::new(model.clone(), &cfg).unwrap();
    let sat = adm.saturation().unwrap().clone();
    let mut beyond = 0;
    let mut previous: Option<Vec<f64>> = None;
    push(
        &mut adm,
        &model,
        &PAPER_POSE,
        6000,
        |_| Vector6::new(0.0, 0.0, 0.0, moment.x, moment.y, moment.z),
        |k, adm| {
            for (i, ((lo, hi), (r, a))) in limits
                .iter()
                .zip(adm.q_r().iter().zip(adm.q_a()))
                .enumerate()
            {
                assert!(
                    *r > *lo && *r < *hi,
                    "step {k} joint {i}: q_r {r} outside ({lo}, {hi})"
                );
                if *a <= *lo || *a >= *hi {
                    beyond += 1;
                }
                // Chain rule: q_r' = sat'(q_a) q_a'.
                let (_, slope, _) = sat.apply(i, *a);
                assert!(
                    (adm.qdot_r()[i] - slope * adm.qdot_a()[i]).abs()
                        <= 1e-12 * (1.0 + adm.qdot_a()[i].abs())
                );
            }
            if let Some(p) = &previous {
                // q_r' is the rate of q_r.
                for (i, ((r, before), v)) in adm.q_r().iter().zip(p).zip(adm.qdot_r()).enumerate() {
                    let rate = (r - before) / DT;
                    assert!(
                        (rate - v).abs() < 0.02 + 0.02 * rate.abs(),
                        "step {k} joint {i}: {rate} vs {v}"
                    );
                }
            }
            previous = Some(adm.q_r().to_vec());
        },
    );
    assert!(
        beyond > 100,
        "the push should drive q_a beyond a limit ({beyond} samples)"
    );
}

#[test]
fn without_a_wrench_the_reference_is_the_desired_trajectory_bit_for_bit() {
    let model = baxter();
    let mut task = TaskSpaceAdmittance::new(model.clone(), &no_saturation()).unwrap();
    let mut task_saturated =
        TaskSpaceAdmittance::new(model.clone(), &TaskSpaceAdmittanceConfig::default()).unwrap();
    // The joint-space model with the same joint-limit saturation.
    let (lower, upper): (Vec<f64>, Vec<f64>) = model.position_limits().unzip();
    let mut joint = Admittance::new(
        7,
        &AdmittanceConfig {
            saturation: Some(SaturationConfig::from_limits(0.95, &lower, &upper)),
            ..AdmittanceConfig::paper()
        },
    )
    .unwrap();
    let zero = [0.0; 7];
    let (mut q_d, mut qd_d, mut qdd_d) = ([0.0; 7], [0.0; 7], [0.0; 7]);
    for k in 0..3000 {
        let t = k as f64 * DT;
        for i in 0..7 {
            let w = 1.0 + 0.4 * i as f64;
            q_d[i] = PAPER_POSE[i] + 0.4 * (w * t).sin();
            qd_d[i] = 0.4 * w * (w * t).cos();
            qdd_d[i] = -0.4 * w * w * (w * t).sin();
        }
        let input = ReferenceInput {
            q_d: &q_d,
            qdot_d: &qd_d,
            qddot_d: &qdd_d,
            q: &q_d,
            external_torque_estimate: &zero,
        };
        assert!(task.step(&input, DT).is_ok());
        assert_eq!(task.q_a(), &q_d[..]);
        assert_eq!(task.qdot_a(), &qd_d[..]);
        assert_eq!(task.qddot_a(), &qdd_d[..]);
        assert_eq!(task.q_r(), &q_d[..]);
        assert!(task_saturated.step(&input, DT).is_ok());
        assert!(joint.step_reference(&input, DT).is_ok());
        assert_eq!(task_saturated.q_r(), CompliantReference::q_r(&joint));
        assert_eq!(task_saturated.qdot_r(), CompliantReference::qdot_r(&joint));
        assert_eq!(
            task_saturated.qddot_r(),
            CompliantReference::qddot_r(&joint)
        );
    }
}

#[test]
fn a_fault_holds_the_reference_and_leaves_the_state_alone() {
    let model = baxter();
    let cfg = TaskSpaceAdmittanceConfig::default();
    let mut faulted = TaskSpaceAdmittance::new(model.clone(), &cfg).unwrap();
    let mut clean = TaskSpaceAdmittance::new(model.clone(), &cfg).unwrap();
    let zero = [0.0; 7];
    let tau = torque_of(
        &model,
        &PAPER_POSE,
        &Vector6::new(5.0, 0.0, -5.0, 0.0, 0.3, 0.0),
    );
    let good = TaskSpaceInput {
        q_d: &PAPER_POSE,
        qdot_d: &zero,
        qddot_d: &zero,
        q: &PAPER_POSE,
        external_torque_estimate: &tau,
    };
    // Before any good step a fault holds q_d.
    let mut nan_q = PAPER_POSE;
    nan_q[3] = f64::NAN;
    let status = faulted.step(&TaskSpaceInput { q: &nan_q, ..good }, DT);
    assert_eq!(
        status.fault(),
        Some(Fault::NonFiniteMeasurement {
            argument: "q",
            joint: 3
        })
    );
    assert_eq!(faulted.q_r(), &PAPER_POSE[..]);
    let mut nan_tau = tau.clone();
    nan_tau[6] = f64::INFINITY;
    let mut bad_q_d = PAPER_POSE;
    bad_q_d[0] = f64::NAN;
    let short = [0.0; 6];
    for k in 0..300 {
        assert!(clean.step(&good, DT).is_ok());
        assert!(faulted.step(&good, DT).is_ok());
        if k % 50 == 7 {
            let before = faulted.q_r().to_vec();
            let faults = [
                faulted.step(&TaskSpaceInput { q: &nan_q, ..good }, DT),
                faulted.step(
                    &TaskSpaceInput {
                        external_torque_estimate: &nan_tau,
                        ..good
                    },
                    DT,
                ),
                faulted.step(
                    &TaskSpaceInput {
                        q_d: &bad_q_d,
                        ..good
                    },
                    DT,
                ),
                faulted.step(
                    &TaskSpaceInput {
                        qdot_d: &short,
                        ..good
                    },
                    DT,
                ),
                faulted.step(&good, 0.0),
                faulted.step(&good, f64::NAN),
            ];
            assert_eq!(
                faults[1].fault(),
                Some(Fault::NonFiniteEstimate { joint: 6 })
            );
            assert_eq!(
                faults[2].fault(),
                Some(Fault::NonFiniteReference {
                    argument: "q_d",
                    joint: 0
                })
            );
            assert_eq!(
                faults[3].fault(),
                Some(Fault::WrongLength {
                    argument: "qdot_d",
                    expected: 7,
                    found: 6
                })
            );
            assert_eq!(faults[4].fault(), Some(Fault::InvalidTimeStep));
            assert!(faults.iter().all(|s| !s.is_ok()));
            // Held: same q_r, zero rates.
            assert_eq!(faulted.q_r(), &before[..]);
            assert!(faulted
                .qdot_r()
                .iter()
                .chain(faulted.qddot_r())
                .all(|v| *v == 0.0));
        }
    }
    // An estimate so large that the wrench overflows is a fault too, and held.
    let huge = [1e308; 7];
    let before = faulted.q_r().to_vec();
    let status = faulted.step(
        &TaskSpaceInput {
            external_torque_estimate: &huge,
            ..good
        },
        DT,
    );
    assert!(
        matches!(status.fault(), Some(Fault::NonFiniteOutput { .. })),
        "{status:?}"
    );
    assert_eq!(faulted.q_r(), &before[..]);
    let status = clean.step(
        &TaskSpaceInput {
            external_torque_estimate: &[1e300; 7],
            ..good
        },
        DT,
    );
    assert!(clean.q_r().iter().all(|v| v.is_finite()), "{status:?}");
    clean.reset();
    faulted.reset();
    for _ in 0..10 {
        assert!(clean.step(&good, DT).is_ok() && faulted.step(&good, DT).is_ok());
    }
    // The faulted steps changed nothing: both models are in the same state.
    assert_eq!(faulted.q_r(), clean.q_r());
    assert_eq!(faulted.deviation(), clean.deviation());
    assert_eq!(faulted.wrench_estimate(), clean.wrench_estimate());
    // Reset returns to the start.
    faulted.reset();
    assert!(faulted.deviation().iter().all(|v| *v == 0.0));
    let mut fresh = TaskSpaceAdmittance::new(model, &cfg).unwrap();
    assert!(fresh.step(&good, DT).is_ok() && faulted.step(&good, DT).is_ok());
    assert_eq!(faulted.q_r(), fresh.q_r());
}

#[test]
fn both_admittance_models_sit_behind_one_trait() {
    let model = baxter();
    let joint_cfg = AdmittanceConfig::paper();
    let mut models: Vec<Box<dyn CompliantReference>> = vec![
        Box::new(Admittance::new(7, &joint_cfg).unwrap()),
        Box::new(
            TaskSpaceAdmittance::new(model.clone(), &TaskSpaceAdmittanceConfig::default()).unwrap(),
        ),
    ];
    let mut inherent = Admittance::new(7, &joint_cfg).unwrap();
    let zero = [0.0; 7];
    let tau = [0.5, -0.2, 0.1, 0.3, 0.0, 0.1, -0.1];
    for _ in 0..500 {
        let input = ReferenceInput {
            q_d: &PAPER_POSE,
            qdot_d: &zero,
            qddot_d: &zero,
            q: &PAPER_POSE,
            external_torque_estimate: &tau,
        };
        for m in models.iter_mut() {
            assert_eq!(m.dof(), 7);
            assert!(m.step_reference(&input, DT).is_ok());
            assert!(m.saturation().is_some());
        }
        let direct = AdmittanceInput {
            q_d: &PAPER_POSE,
            qdot_d: &zero,
            qddot_d: &zero,
            external_torque_estimate: &tau,
        };
        assert!(inherent.step(&direct, DT).is_ok());
        assert_eq!(models[0].q_r(), inherent.q_r());
        assert_eq!(models[0].qdot_r(), inherent.qdot_r());
    }
    // Both yield: the references moved away from q_d.
    for m in &models {
        assert!(m
            .q_r()
            .iter()
            .zip(&PAPER_POSE)
            .any(|(r, d)| (r - d).abs() > 1e-3));
    }
    for m in models.iter_mut() {
        m.reset();
        assert!(m.q_r().iter().all(|v| *v == 0.0));
    }
}

#[test]
fn configurations_parse_and_bad_ones_name_their_key() {
    let text = r#"
        task_axes = ["x", "y", "z", "rz"]
        compliant_axes = ["x", "y"]
        [linear]
        damping = [60, 60, 80]
        stiffness = [0, 0, 300]
        inertia = 2.0
        [angular]
        damping = 6
        stiffness = 10
        [wrench_damping]
        threshold = 0.05
        [inverse_kinematics]
        position_gain = 900
        velocity_gain = 60
        [saturation]
        kind = "joint_limits"
        rho = 0.9
    "#;
    let cfg: TaskSpaceAdmittanceConfig = toml::from_str(text).unwrap();
    assert_eq!(cfg.linear.stiffness, AxisValues::PerAxis([0.0, 0.0, 300.0]));
    assert_eq!(cfg.wrench_damping.max_damping, 0.1);
    assert_eq!(cfg.inverse_kinematics.posture_position_gain, 100.0);
    assert_eq!(
        cfg.saturation,
        TaskSaturationConfig::JointLimits { rho: 0.9 }
    );
    assert!(TaskSpaceAdmittance::new(baxter(), &cfg).is_ok());
    // Defaults from an empty table, and what is written reads back.
    let empty: TaskSpaceAdmittanceConfig = toml::from_str("").unwrap();
    assert_eq!(empty, TaskSpaceAdmittanceConfig::default());
    let json = serde_json::to_string(&cfg).unwrap();
    assert_eq!(
        serde_json::from_str::<TaskSpaceAdmittanceConfig>(&json).unwrap(),
        cfg
    );
    let explicit: TaskSpaceAdmittanceConfig =
        toml::from_str("[saturation]\nkind = \"explicit\"\nrho = 0.95\nhalf_range = 1.1\n")
            .unwrap();
    let adm = TaskSpaceAdmittance::new(baxter(), &explicit).unwrap();
    assert_eq!(adm.saturation().unwrap().half_range(), &[1.1; 7]);
    let none: TaskSpaceAdmittanceConfig =
        toml::from_str("[saturation]\nkind = \"none\"\n").unwrap();
    assert!(TaskSpaceAdmittance::new(baxter(), &none)
        .unwrap()
        .saturation()
        .is_none());

    // Parse errors say what is wrong where.
    for (bad, says) in [
        ("speed = 3", "unknown field `speed`"),
        ("task_axes = [\"w\"]", "unknown variant `w`"),
        (
            "[linear]\ndamping = [1, 2]\nstiffness = 1",
            "list of three numbers [x, y, z], found a list of 2",
        ),
        (
            "[linear]\ndamping = \"x\"\nstiffness = 1",
            "found the string \"x\"",
        ),
        (
            "[saturation]\nkind = \"joint_limits\"\nhalf_range = 1",
            "unknown field `half_range`",
        ),
    ] {
        let e = toml::from_str::<TaskSpaceAdmittanceConfig>(bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{bad}: {e}");
    }
    // Construction errors name the key.
    let d = TaskSpaceAdmittanceConfig::default;
    let cases: Vec<(TaskSpaceAdmittanceConfig, &str)> = vec![
        (
            TaskSpaceAdmittanceConfig {
                task_axes: vec![],
                ..d()
            },
            "task_axes",
        ),
        (
            TaskSpaceAdmittanceConfig {
                task_axes: vec![TaskAxis::X],
                compliant_axes: Some(vec![TaskAxis::Y]),
                ..d()
            },
            "compliant_axes",
        ),
        (
            TaskSpaceAdmittanceConfig {
                linear: AxisAdmittanceConfig {
                    damping: 0.0.into(),
                    ..AxisAdmittanceConfig::default_linear()
                },
                ..d()
            },
            "linear.damping",
        ),
        (
            TaskSpaceAdmittanceConfig {
                angular: AxisAdmittanceConfig {
                    stiffness: [1.0, 1.0, -1.0].into(),
                    ..AxisAdmittanceConfig::default_angular()
                },
                ..d()
            },
            "angular.stiffness[2]",
        ),
        (
            TaskSpaceAdmittanceConfig {
                angular: AxisAdmittanceConfig {
                    inertia: Some(f64::NAN.into()),
                    ..AxisAdmittanceConfig::default_angular()
                },
                ..d()
            },
            "angular.inertia",
        ),
        (
            TaskSpaceAdmittanceConfig {
                wrench_damping: SingularityDampingConfig {
                    threshold: 0.0,
                    max_damping: 0.1,
                },
                ..d()
            },
            "wrench_damping.threshold",
        ),
        (
            TaskSpaceAdmittanceConfig {
                inverse_kinematics: InverseKinematicsConfig {
                    velocity_gain: -1.0,
                    ..InverseKinematicsConfig::default()
                },
                ..d()
            },
            "inverse_kinematics.velocity_gain",
        ),
        (
            TaskSpaceAdmittanceConfig {
                inverse_kinematics: InverseKinematicsConfig {
                    damping: SingularityDampingConfig {
                        threshold: 0.1,
                        max_damping: f64::INFINITY,
                    },
                    ..InverseKinematicsConfig::default()
                },
                ..d()
            },
            "inverse_kinematics.damping.max_damping",
        ),
        (
            TaskSpaceAdmittanceConfig {
                saturation: TaskSaturationConfig::JointLimits { rho: 1.0 },
                ..d()
            },
            "saturation.rho",
        ),
    ];
    for (cfg, key) in cases {
        let e = TaskSpaceAdmittance::new(baxter(), &cfg)
            .map(|_| ())
            .unwrap_err();
        assert_eq!(e.key, key, "{e}");
    }
    let _: Arc<Model> = baxter();
}
