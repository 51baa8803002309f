//! A frozen encoder on a moving joint: the loop must report a stale measurement (and
//! hold) within `controller.safe_hold.stale_steps` periods, whatever the admittance model
//! makes of the apparent stop meanwhile.

mod common;

use admittance_ffi::*;

/// Steps experiment B's desired motion (s0: 1.0 sin(2 pi t / 12) around the pose) as the
/// measurement (16-bit encoder) and as the desired trajectory, freezing joint 0's reading
/// for `frozen` periods from step `from`; returns the steps with a stale fault.
fn run(from: usize, frozen: usize) -> (Vec<usize>, f64) {
    let (_tmp, dir) = common::deploy("momentum");
    let mut l = RobotLoop::load(&dir, &[]).unwrap();
    let n = l.dof();
    let dt = l.dt();
    let res = std::f64::consts::TAU / 65536.0;
    let w = std::f64::consts::TAU / 12.0;
    let (mut q, mut qd, qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut held = 0.0;
    let mut stale = Vec::new();
    let mut speed = 0.0;
    for k in 0..from + frozen + 20 {
        let t = k as f64 * dt;
        q.copy_from_slice(&common::POSE);
        q[0] += (w * t).sin();
        qd[0] = w * (w * t).cos();
        let q_d = q.clone();
        for x in q.iter_mut() {
            *x = (*x / res).round() * res;
        }
        if k == from {
            held = q[0];
            speed = qd[0];
        }
        if (from..from + frozen).contains(&k) {
            q[0] = held;
        }
        let status = l.step(&RobotInput {
            time: t,
            q: &q,
            qdot: None,
            tau: None,
            desired: Some([&q_d, &qd, &qdd]),
        });
        let r = report_of(&status, false);
        if r.fault == ADM_FAULT_STALE_MEASUREMENT {
            assert_eq!(r.fault_joint, 0);
            stale.push(k);
        }
    }
    (stale, speed)
}

#[test]
fn a_frozen_encoder_on_a_moving_joint_is_reported() {
    // s0 moves at 0.49 rad/s at 0.7 s (1.0 sin(2 pi t / 12)), past the 0.5 s warm-up.
    let (stale, speed) = run(700, 40);
    assert!((speed - 0.49).abs() < 0.01, "{speed}");
    assert!(
        !stale.is_empty(),
        "40 frozen periods at {speed:.2} rad/s not reported"
    );
    // Within the 30 periods of the default rule (plus the first repeat).
    assert!(stale[0] <= 700 + 31, "first reported at {}", stale[0]);
    // Released when the reading moves again.
    assert!(stale.iter().all(|&k| k < 700 + 40 + 2), "{stale:?}");
    // A short freeze (10 periods) is not a fault.
    let (stale, _) = run(700, 10);
    assert!(stale.is_empty(), "{stale:?}");
}
