//! The library in a 1 kHz control loop: the paper's neural controller tracking a compliant
//! reference from the admittance model, driven by a momentum observer's external-torque
//! estimate. The wiring of one period is `admittance_loop::ClosedLoop`, built by
//! `ClosedLoop::from_config` from a `LoopConfig` (the keys of a scenario file's
//! `[controller]`, `[admittance]` and `[observer]` tables), the same code the scenario
//! runner steps. Everything is built once; each tick calls `SignalChain::sample` and
//! `ClosedLoop::step`, which never allocate and never panic. A robot program needs
//! `admittance-loop` (and `admittance-dynamics` for the model) only.
//!
//! The "robot" here is the project's simulated Baxter arm (`admittance_sim::Plant`) with a
//! push of 2 N m on s0 from 1 s to 2 s; on a real arm, its driver's encoder reading goes
//! into `SignalChain::sample` (low-pass, differentiation) and `ClosedLoop::torque` goes to
//! its torque interface.
//!
//! Run: `cargo run --release -p admittance-cli --example control_loop`

use admittance_control::{AdmittanceConfig, JointValues, NeuralControllerConfig, StepStatus};
use admittance_dynamics::Model;
use admittance_loop::{
    ClosedLoop, ControllerConfig, ControllerKind, JointAdmittanceConfig, LoopConfig, LoopInput,
    ObserverConfig, ObserverKind, SignalChain,
};
use admittance_sim::{JointTorqueProfileConfig, Plant, PlantConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/baxter_left_arm.urdf"
    );
    let model = Model::from_urdf_file(urdf.as_ref(), Some("base"), Some("left_hand"))?;
    let n = model.nq();
    let pose = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];

    // The stand-in robot: true dynamics at 5 kHz, a person pushing s0 from 1 s to 2 s.
    let mut robot_config = PlantConfig {
        initial_q: pose.to_vec(),
        ..PlantConfig::default()
    };
    robot_config.spring.enabled = true; // Baxter's s1 counterbalance
    robot_config
        .environment
        .joint_torque_profiles
        .push(JointTorqueProfileConfig {
            joint: "left_s0".into(),
            points: vec![[0.0, 2.0]],
            t_start: 1.0,
            t_end: 2.0,
        });
    let mut robot = Plant::new(&model, &robot_config)?;

    // Built once, before the loop: the signal chain (40 Hz low-pass before
    // differentiating), and the controller, the admittance model and the observer, wired
    // by the closed loop.
    let config: LoopConfig = LoopConfig {
        control_rate_hz: 1000.0,
        controller: ControllerConfig {
            kind: ControllerKind::Neural,
            // K2 per joint (the wrist's inertia is small), as in scenarios/deadzone.toml.
            neural: NeuralControllerConfig {
                k2: JointValues::PerJoint(vec![20.0, 30.0, 15.0, 10.0, 2.0, 2.0, 0.2]),
                ..NeuralControllerConfig::default()
            },
            pd: None,
            computed_torque: None,
            // The momentum observer's estimate acts through the admittance model only:
            // passed into the law as well it closes a loop through the command it is
            // computed from (docs/experiments.md measures both).
            subtract_estimate: false,
        },
        admittance: Some(JointAdmittanceConfig {
            enabled: true,
            config: AdmittanceConfig::paper(),
        }),
        task_admittance: None,
        observer: ObserverConfig {
            kind: ObserverKind::Momentum,
            cutoff_hz: 5.0, // estimate low-passed at 5 Hz
            warmup: 0.5,    // held at zero for the first 0.5 s (the filters start up)
            ..ObserverConfig::default()
        },
    };
    let dt = 1.0 / config.control_rate_hz;
    let mut signals = SignalChain::new(n, 40.0, config.control_rate_hz)?;
    let mut closed_loop = ClosedLoop::from_config(&model, &config, None)?;
    let (mut q_d, mut qdot_d, mut qddot_d) = (pose.to_vec(), vec![0.0; n], vec![0.0; n]);
    let no_truth = vec![0.0; n]; // a real robot does not know the true external torque

    for tick in 0..3000 {
        let time = tick as f64 * dt;
        // The desired motion: s0 = 0.3 sin(t).
        (q_d[0], qdot_d[0], qddot_d[0]) = (0.3 * time.sin(), 0.3 * time.cos(), -0.3 * time.sin());
        // Every 1 ms: read the encoders, step the loop, send the torque.
        let measurement = signals.sample(time, robot.q(), closed_loop.torque())?;
        let status = closed_loop.step(&LoopInput {
            time,
            q_d: &q_d,
            qdot_d: &qdot_d,
            qddot_d: &qddot_d,
            measurement,
            true_external_torque: &no_truth,
        });
        if let StepStatus::Fault(f) = status.controller {
            eprintln!("controller fault at {time:.3} s: {f:?} (safe hold applied)");
        }
        robot.step_control(closed_loop.torque())?;
        if tick % 500 == 0 {
            println!(
                "t = {time:.1} s  q_d[s0] = {:+.3}  q_r[s0] = {:+.3}  q[s0] = {:+.3}  tau_ext_hat[s0] = {:+.2} N m",
                q_d[0],
                closed_loop.q_r()[0],
                robot.q()[0],
                closed_loop.external_torque_estimate()[0]
            );
        }
    }
    Ok(())
}
