//! After construction, the plant step and the sensor sample do not allocate: a counting
//! global allocator watches a closed loop with every feature on (friction, deadzone,
//! spring, payload, every environment, noisy sensors with faults), under both integrators
//! and both solvers.

mod common;

use admittance_dynamics::{forward_kinematics, Data};
use admittance_sim::*;
use admittance_testkit::count_allocations;
use common::*;

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

fn everything(integrator: Integrator, solver: Solver) -> PlantConfig {
    let model = baxter();
    let q0 = vec![0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    let mut data = Data::new(&model);
    forward_kinematics(&model, &mut data, &q0).unwrap();
    let p = data.tip_placement(&model).translation;
    let mut cfg = PlantConfig {
        integrator,
        solver,
        initial_q: q0,
        inertia_scale: 1.1,
        ..PlantConfig::default()
    };
    cfg.payload = Some(PayloadConfig {
        mass: 0.5,
        com: [0.0, 0.0, 0.05],
        ..Default::default()
    });
    cfg.friction = vec![FrictionConfig {
        joint: "*".into(),
        viscous: 0.3,
        coulomb: 0.4,
        v_s: 0.01,
    }];
    cfg.deadzones = vec![DeadzoneConfig {
        joint: "left_s0".into(),
        d_left: -0.49,
        d_right: 0.49,
        ..Default::default()
    }];
    cfg.spring.enabled = true;
    cfg.environment.joint_springs = vec![JointSpringConfig {
        joints: vec!["left_s0".into(), "left_e1".into()],
        mass: vec![0.01],
        damping: vec![0.15],
        stiffness: vec![1.1],
        t_start: 0.05,
        t_end: 0.15,
        ..Default::default()
    }];
    cfg.environment.walls = vec![WallConfig {
        point: [p.x, p.y, p.z - 0.001],
        normal: [0.0, 0.0, 1.0],
        ..Default::default()
    }];
    cfg.environment.joint_torque_profiles = vec![JointTorqueProfileConfig {
        joint: "left_w0".into(),
        points: vec![[0.0, 0.0], [0.1, 1.0], [0.2, 0.0]],
        ..Default::default()
    }];
    cfg.environment.tip_force_profiles = vec![TipForceProfileConfig {
        points: vec![[0.0, 0.0, 0.0, 0.0], [0.2, 5.0, 0.0, -3.0]],
        ..Default::default()
    }];
    cfg.sensors = SensorConfig {
        resolution_rad: 1e-5,
        noise_std: 1e-4,
        seed: 3,
        faults: vec![
            FaultConfig {
                kind: FaultKind::Nan,
                joints: vec!["left_e0".into()],
                t_start: 0.1,
                t_end: 0.103,
                value: None,
            },
            FaultConfig {
                kind: FaultKind::Stale,
                joints: vec![],
                t_start: 0.12,
                t_end: 0.124,
                value: None,
            },
            FaultConfig {
                kind: FaultKind::AngleSpike,
                joints: vec!["left_w0".into()],
                t_start: 0.13,
                t_end: 0.135,
                value: Some(1e20),
            },
            FaultConfig {
                kind: FaultKind::TorqueSpike,
                joints: vec!["left_w1".into()],
                t_start: 0.14,
                t_end: 0.145,
                value: None,
            },
        ],
        ..Default::default()
    };
    cfg
}

#[test]
fn plant_step_and_sensor_sample_do_not_allocate() {
    let model = baxter();
    let speed_settings = [
        (false, 1e-12, FrictionSolve::Newton),
        (true, 1e-6, FrictionSolve::Newton),
        (true, 1e-12, FrictionSolve::Linearized),
    ];
    for integrator in INTEGRATORS {
        for (solver, (hold, tol, friction_solve)) in [Solver::Auto, Solver::Cholesky]
            .into_iter()
            .flat_map(|s| speed_settings.map(|h| (s, h)))
        {
            let mut cfg = everything(integrator, solver);
            cfg.hold_mass_matrix = hold;
            cfg.newton_tolerance = tol;
            cfg.friction_solve = friction_solve;
            let mut plant = Plant::new(&model, &cfg).unwrap();
            let mut sensors = Sensors::new(&model, &cfg.sensors, cfg.control_rate_hz).unwrap();
            // The robot program's gates screen the readings (the spikes are refused there).
            let mut gates = admittance_loop::PlausibilityGates::new(
                &model,
                &admittance_loop::GateConfig::default(),
                1.0 / cfg.control_rate_hz,
            )
            .unwrap();
            let target = cfg.initial_q.clone();
            let mut tau = [0.0; 7];
            // One period outside the count (nothing is lazily allocated, but be fair).
            plant.step_control(&tau).unwrap();
            let mut spiked = 0;
            let count = count_allocations(|| {
                for k in 0..250 {
                    if k == 100 {
                        tau[2] = f64::NAN;
                    }
                    plant.step_control(&tau).unwrap();
                    plant.step(&tau).unwrap();
                    let t = plant.time();
                    if (0.13..0.135).contains(&t) || (0.14..0.145).contains(&t) {
                        spiked += 1;
                    }
                    let m = sensors
                        .sample_screened(plant.time(), plant.q(), &tau, |t, q, tau| {
                            gates.check(t, q, Some(tau));
                        })
                        .unwrap();
                    for i in 0..7 {
                        let q = if m.q[i].is_finite() {
                            m.q[i]
                        } else {
                            m.q_filtered[i]
                        };
                        tau[i] = 30.0 * (target[i] - q) - 3.0 * m.qdot[i];
                    }
                    std::hint::black_box(plant.energy());
                }
            });
            assert_eq!(
                count, 0,
                "{integrator} / {solver:?} / hold {hold}: {count} allocations in 250 control periods"
            );
            assert!(plant.q().iter().all(|q| q.is_finite()));
            assert!(spiked > 1);
            assert_eq!(gates.faults(), spiked, "every spiked sample is refused");
            assert!(
                plant.counters().newton_iterations > 0 && plant.counters().nonfinite_commands > 0
            );
        }
    }
    // The counter itself sees this thread's allocations.
    assert!(count_allocations(|| drop(std::hint::black_box(vec![1u8; 16]))) > 0);
}
