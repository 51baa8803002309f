//! The real-time contract of a robot's loop: after construction, `RobotLoop::step`
//! allocates nothing (issue 32), on every path: waiting for the first angles, the pose
//! hold, the caller's trajectory, measured velocities, NaN and implausible samples (the
//! gates of issue 34), the wrench and every observer kind. The counting allocator of
//! `admittance-testkit` (per thread) wraps the system one for this test binary.

use std::path::Path;

use admittance_dynamics::Model;
use admittance_loop::{RobotConfig, RobotInput, RobotLoop};
use admittance_testkit::count_allocations as count;

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

const URDF: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../models/baxter_left_arm.urdf"
);
const POSE: [f64; 7] = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];

fn config(observer: &str) -> RobotConfig {
    let text = format!(
        r#"format = "admittance-loop"
version = 1
[arm]
urdf = "arm.urdf"
[controller]
kind = "pd"
pd = {{ kp = 50.0, kd = 5.0, gravity_compensation = true }}
[admittance]
damping = 3.0
stiffness = 5.0
[observer]
{observer}
"#
    );
    RobotConfig::from_toml(&text, Path::new("loop.toml")).unwrap()
}

fn network() -> admittance_control::BroadModel {
    use admittance_learning::broad::{fit, BroadConfig, Dataset};
    let rows = 300;
    let inputs: Vec<f64> = (0..rows * 21)
        .map(|k| ((k * 7919) % 1000) as f64 * 1e-3 - 0.5)
        .collect();
    let targets: Vec<f64> = (0..rows * 7)
        .map(|k| ((k * 104729) % 1000) as f64 * 1e-3)
        .collect();
    let data = Dataset::new(&inputs, &targets, 21, 7).unwrap();
    let config = BroadConfig {
        nodes: 50,
        centre_subsample: 300,
        lambda_grid: vec![1e-6],
        threads: 1,
        ..BroadConfig::for_arm(7)
    };
    fit(&data, None, &config).unwrap().0
}

/// Steps `l` through every path; returns the allocations counted during the steps.
fn exercise(l: &mut RobotLoop) -> usize {
    let zeros = [0.0; 7];
    let mut q = POSE;
    let mut tau = [0.5; 7];
    let mut qdot = [0.01; 7];
    count(|| {
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            for i in 0..7 {
                q[i] = POSE[i] + 0.05 * (t * (1.0 + i as f64)).sin();
                qdot[i] = 0.05 * (1.0 + i as f64) * (t * (1.0 + i as f64)).cos();
                tau[i] = 0.5 * (3.0 * t).sin();
            }
            if k < 3 {
                q[4] = f64::NAN; // waiting for the first angles
            }
            if k == 700 {
                q[3] = 1e20; // implausible angle
            }
            if k == 800 {
                tau[1] = 1e300; // implausible torque
            }
            if (900..903).contains(&k) {
                q[2] = f64::NAN;
            }
            let desired = (k > 1500).then_some([&POSE[..], &zeros[..], &zeros[..]]);
            let status = l.step(&RobotInput {
                time: t,
                q: &q,
                qdot: (k > 2500).then_some(&qdot[..]),
                tau: (k < 2000).then_some(&tau[..]),
                desired,
            });
            std::hint::black_box(status);
        }
    })
}

#[test]
fn a_robot_step_allocates_nothing() {
    let model = Model::from_urdf_file(URDF.as_ref(), Some("base"), Some("left_hand")).unwrap();
    for (observer, trained) in [
        ("kind = \"none\"", None),
        (
            "kind = \"momentum\"\ninput_filter_hz = 10.0\ncutoff_hz = 5.0",
            None,
        ),
        (
            "kind = \"learned\"\ninput_filter_hz = 10.0",
            Some(network()),
        ),
        ("kind = \"hybrid\"\ncutoff_hz = 5.0", Some(network())),
    ] {
        let mut l = RobotLoop::new(
            model.clone(),
            &config(observer),
            Path::new("."),
            trained,
            None,
        )
        .unwrap();
        l.enable_wrench(0.0).unwrap();
        assert_eq!(exercise(&mut l), 0, "{observer}");
        assert_eq!(l.implausible_samples(), 2, "{observer}");
        assert!(l.torque().iter().all(|t| t.is_finite()));
    }
    // With contact detection and the touched link's wrench: a floor low enough that the
    // exercise's motion and faults raise and drop the flags.
    let n = 7;
    let noise: Vec<f64> = (0..n * 20_000)
        .map(|k| 1e-3 * ((k * 7919 % 1000) as f64 / 1000.0 - 0.5))
        .collect();
    let zeros = vec![0.0; noise.len()];
    let floor =
        admittance_control::calibrate_contact(&noise, &zeros, &zeros, n, 1e-3, 1.0).unwrap();
    let mut l = RobotLoop::new(
        model.clone(),
        &config("kind = \"momentum\"\ninput_filter_hz = 10.0"),
        Path::new("."),
        None,
        Some(floor),
    )
    .unwrap();
    assert_eq!(exercise(&mut l), 0, "with a contact floor");
    assert!(l.contact_wrench().is_some());
    // The counter itself works.
    assert!(count(|| drop(std::hint::black_box(vec![1u8; 16]))) > 0);
}
