//! The real-time contract: after construction, no controller step, admittance step or
//! observer update allocates (issue 3, "Bars"), including fault steps, the dynamic-node
//! hooks (discard, growth) and the 512-node networks on Baxter's 7 joints. The counting
//! allocator of `admittance-testkit` (per thread) wraps the system one for this test binary.

mod common;

use admittance_control::*;
use admittance_testkit::count_allocations as count;

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

struct Inputs {
    q: Vec<f64>,
    qdot: Vec<f64>,
    q_ref: Vec<f64>,
    qdot_ref: Vec<f64>,
    qddot_ref: Vec<f64>,
    est: Vec<f64>,
}

impl Inputs {
    fn new(n: usize) -> Self {
        Inputs {
            q: vec![0.0; n],
            qdot: vec![0.0; n],
            q_ref: vec![0.0; n],
            qdot_ref: vec![0.0; n],
            qddot_ref: vec![0.0; n],
            est: vec![0.0; n],
        }
    }
    fn set(&mut self, k: usize) {
        let t = k as f64 * 1e-3;
        for i in 0..self.q.len() {
            let w = 1.0 + 0.2 * i as f64;
            self.q_ref[i] = 0.3 * (w * t).sin() + 0.1 * i as f64;
            self.qdot_ref[i] = 0.3 * w * (w * t).cos();
            self.qddot_ref[i] = -0.3 * w * w * (w * t).sin();
            self.q[i] = self.q_ref[i] - 0.01 * (t + i as f64).cos();
            self.qdot[i] = self.qdot_ref[i] + 0.02 * (3.0 * t).sin();
            self.est[i] = 0.1 * (t + i as f64).sin();
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

fn exercise(c: &mut dyn Controller, n: usize) -> usize {
    let mut inp = Inputs::new(n);
    let mut tau = vec![0.0; n];
    inp.set(0);
    let _ = c.step(&inp.input(), 1e-3, &mut tau); // warm-up (not counted)
    let short = vec![0.0; n - 1];
    count(|| {
        for k in 1..400 {
            inp.set(k);
            // Faults of every kind on some steps.
            match k % 50 {
                10 => inp.q[0] = f64::NAN,
                11 => inp.qdot[n - 1] = f64::INFINITY,
                12 => inp.qddot_ref[0] = f64::NAN,
                13 => inp.est[0] = f64::NAN,
                _ => {}
            }
            let _ = c.step(&inp.input(), 1e-3, &mut tau);
            assert!(tau.iter().all(|t| t.is_finite()));
        }
        // Stale samples.
        inp.set(500);
        for _ in 0..60 {
            let _ = c.step(&inp.input(), 1e-3, &mut tau);
        }
        // Wrong lengths.
        let bad = ControlInput {
            qdot_ref: &short,
            ..inp.input()
        };
        let _ = c.step(&bad, 1e-3, &mut tau);
        let _ = c.step(&inp.input(), 1e-3, &mut tau[..n - 1]);
    })
}

#[test]
fn no_step_allocates_after_construction() {
    let baxter = common::baxter();
    let two = common::two_link();
    let n = baxter.nq();

    // The paper's controller, 512-node lumped and deadzone networks on 7 joints, with the
    // dynamic-node hooks exercised in the loop.
    let mut nn = NeuralController::new(baxter.clone(), &NeuralControllerConfig::default()).unwrap();
    assert_eq!(
        (
            nn.node_count(NetworkId::F),
            nn.node_count(NetworkId::Deadzone)
        ),
        (512, 512)
    );
    assert_eq!(exercise(&mut nn, n), 0, "neural controller step");
    let hooks = count(|| {
        nn.request_growth(
            NetworkId::F,
            GrowthRequest {
                nodes: 30,
                interval_steps: 1,
                params: GrowthParams::new(4, 0.0, 0.0),
            },
        )
        .unwrap();
        nn.request_growth(
            NetworkId::Deadzone,
            GrowthRequest {
                nodes: 5,
                interval_steps: 2,
                params: GrowthParams::new(4, 0.0, 0.0),
            },
        )
        .unwrap();
    });
    assert_eq!(hooks, 0, "growth requests");
    assert_eq!(
        exercise(&mut nn, n),
        0,
        "neural controller step while growing"
    );
    assert!(nn.growth_progress(NetworkId::F).added > 0);
    let discard = count(|| {
        nn.discard(NetworkId::F, 0.9);
        nn.discard_f(0.05);
        nn.discard(NetworkId::Deadzone, 0.05);
    });
    assert_eq!(discard, 0, "discard");
    let mut out = vec![0.0; n];
    let (q, v) = (vec![0.1; n], vec![0.0; n]);
    assert_eq!(
        count(|| nn.predict_f(&q, &v, &v, &v, &v, &mut out).unwrap()),
        0,
        "predict_f"
    );
    assert_eq!(
        count(|| {
            let _ = nn.weight_norm(NetworkId::F);
            let _ = nn.node_count(NetworkId::Deadzone);
        }),
        0
    );

    // Variants: paper's e2 input, uncompensated, split form.
    let with_e2 = NeuralControllerConfig {
        f: FNetworkConfig::Lumped {
            include_e2: true,
            network: NetworkConfig::default(),
        },
        ..Default::default()
    };
    let mut nn_e2 = NeuralController::new(baxter.clone(), &with_e2).unwrap();
    assert_eq!(exercise(&mut nn_e2, n), 0, "include_e2");
    let mut nn_u = NeuralController::new(
        baxter.clone(),
        &NeuralControllerConfig {
            deadzone_compensation: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(exercise(&mut nn_u, n), 0, "nn_uncompensated");
    let small = || NetworkConfig {
        placement: Placement::Random { count: 64, seed: 2 },
        ..NetworkConfig::default()
    };
    let split = NeuralControllerConfig {
        f: FNetworkConfig::Split {
            m: small(),
            c: small(),
            g: small(),
        },
        ..Default::default()
    };
    let mut nn_s = NeuralController::new(baxter.clone(), &split).unwrap();
    assert_eq!(exercise(&mut nn_s, n), 0, "split form");
    assert_eq!(
        count(|| nn_s.predict_f(&q, &v, &v, &v, &v, &mut out).unwrap()),
        0,
        "split predict_f"
    );

    // Baselines.
    let pd = PdConfig {
        kp: 50.0.into(),
        kd: 5.0.into(),
        gravity_compensation: false,
        safe_hold: SafeHoldConfig::default(),
    };
    let mut c = PdController::new(baxter.clone(), &pd).unwrap();
    assert_eq!(exercise(&mut c, n), 0, "pd");
    let mut c = PdController::new(
        baxter.clone(),
        &PdConfig {
            gravity_compensation: true,
            ..pd
        },
    )
    .unwrap();
    assert_eq!(exercise(&mut c, n), 0, "pd_gravity");
    let ct = ComputedTorqueConfig {
        kp: 100.0.into(),
        kd: 20.0.into(),
        safe_hold: SafeHoldConfig::default(),
    };
    let mut c = ComputedTorqueController::new(baxter.clone(), &ct).unwrap();
    assert_eq!(exercise(&mut c, n), 0, "computed torque");
    let mut c = ComputedTorqueController::new(two.clone(), &ct).unwrap();
    assert_eq!(exercise(&mut c, 2), 0, "computed torque, 2 joints");

    // Admittance, first and second order, with saturation; faults included.
    for inertia in [None, Some(JointValues::Uniform(0.5))] {
        let cfg = AdmittanceConfig {
            inertia,
            ..AdmittanceConfig::paper()
        };
        let mut adm = Admittance::new(n, &cfg).unwrap();
        let mut inp = Inputs::new(n);
        let allocs = count(|| {
            for k in 0..500 {
                inp.set(k);
                if k % 100 == 7 {
                    inp.est[2] = f64::NAN;
                }
                let a = AdmittanceInput {
                    q_d: &inp.q_ref,
                    qdot_d: &inp.qdot_ref,
                    qddot_d: &inp.qddot_ref,
                    external_torque_estimate: &inp.est,
                };
                let _ = adm.step(&a, 1e-3);
            }
            let a = AdmittanceInput {
                q_d: &inp.q_ref[..3],
                qdot_d: &inp.qdot_ref,
                qddot_d: &inp.qddot_ref,
                external_torque_estimate: &inp.est,
            };
            let _ = adm.step(&a, 1e-3);
        });
        assert_eq!(allocs, 0, "admittance step");
    }

    // The task-space admittance (wrench estimate, admittance, inverse kinematics,
    // saturation), behind the shared trait too, with faults of every kind and a reset; on
    // the Baxter arm and on the planar two-joint arm with two task axes.
    for (model, axes) in [
        (common::baxter(), TaskAxis::ALL.to_vec()),
        (common::two_link(), vec![TaskAxis::X, TaskAxis::Z]),
    ] {
        let n = model.nq();
        let cfg = TaskSpaceAdmittanceConfig {
            task_axes: axes,
            linear: AxisAdmittanceConfig {
                inertia: Some(2.0.into()),
                ..AxisAdmittanceConfig::default_linear()
            },
            ..TaskSpaceAdmittanceConfig::default()
        };
        let mut task = TaskSpaceAdmittance::new(model, &cfg).unwrap();
        let mut inp = Inputs::new(n);
        inp.set(0);
        fn input(inp: &Inputs) -> TaskSpaceInput<'_> {
            TaskSpaceInput {
                q_d: &inp.q_ref,
                qdot_d: &inp.qdot_ref,
                qddot_d: &inp.qddot_ref,
                q: &inp.q,
                external_torque_estimate: &inp.est,
            }
        }
        let _ = task.step(&input(&inp), 1e-3); // warm-up (not counted)
        let short = vec![0.0; n - 1];
        let allocs = count(|| {
            for k in 1..500 {
                inp.set(k);
                inp.est.iter_mut().for_each(|e| *e *= 40.0);
                match k % 100 {
                    7 => inp.est[0] = f64::NAN,
                    8 => inp.q[n - 1] = f64::INFINITY,
                    9 => inp.qddot_ref[0] = f64::NAN,
                    _ => {}
                }
                let status = task.step(&input(&inp), 1e-3);
                assert!(status.is_ok() || k % 100 >= 7);
                let _ = CompliantReference::step_reference(&mut task, &input(&inp), 1e-3);
                assert!(task.q_r().iter().all(|v| v.is_finite()));
            }
            let _ = task.step(
                &TaskSpaceInput {
                    q: &short,
                    ..input(&inp)
                },
                1e-3,
            );
            let _ = task.step(&input(&inp), -1.0);
            // The singular pose of the planar arm (and Baxter's stretched pose).
            inp.q_ref.fill(0.0);
            inp.q.fill(0.0);
            let _ = task.step(&input(&inp), 1e-3);
            task.reset();
        });
        assert_eq!(allocs, 0, "task-space admittance step ({n} joints)");
    }

    // Observers.
    let z = vec![0.0; n];
    let obs_in = ObserverInput {
        time: 0.0,
        q: &z,
        qdot: &z,
        qddot: &z,
        tau_commanded: &z,
    };
    let mut none = NoObserver::new(n);
    let mut oracle = OracleObserver::new(n);
    let mut est = vec![0.0; n];
    let allocs = count(|| {
        for k in 0..100 {
            oracle.set_true_value(&[k as f64; 7]);
            let _ = oracle.update(&obs_in, 1e-3, &mut est);
            let _ = none.update(&obs_in, 1e-3, &mut est);
        }
    });
    assert_eq!(allocs, 0, "observers");
    let q = [0.1, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    let v = [0.2, -0.1, 0.3, 0.1, -0.2, 0.1, 0.05];
    let bad = [f64::NAN; 7];
    // 100 updates with a non-finite sample at the 50th (a fault step), then a reset.
    let mut exercise_observer = |observer: &mut dyn Observer, qddot: &[f64]| {
        count(|| {
            for k in 0..100 {
                let input = ObserverInput {
                    time: 0.0,
                    q: if k == 50 { &bad } else { &q },
                    qdot: &v,
                    qddot,
                    tau_commanded: &v,
                };
                let _ = observer.update(&input, 1e-3, &mut est);
            }
            observer.reset();
        })
    };
    let mut momentum =
        MomentumObserver::new(common::baxter(), &MomentumObserverConfig::default()).unwrap();
    assert_eq!(
        exercise_observer(&mut momentum, &z),
        0,
        "momentum observer (with a fault step)"
    );
    let model = {
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
    };
    let mut learned = LearnedObserver::new(model.clone(), 20.0).unwrap();
    assert_eq!(
        exercise_observer(&mut learned, &v),
        0,
        "learned observer (with a fault step)"
    );
    let mut hybrid = HybridObserver::new(
        MomentumObserver::new(common::baxter(), &MomentumObserverConfig::default()).unwrap(),
        model,
    )
    .unwrap();
    assert_eq!(
        exercise_observer(&mut hybrid, &v),
        0,
        "hybrid observer (with a fault step)"
    );

    // The counter itself works.
    assert!(count(|| drop(std::hint::black_box(vec![1u8; 16]))) > 0);
}

/// The contact detector (issue 31) and an admittance with a deadband allocate nothing per
/// update, including wrong-length and non-finite inputs.
#[test]
fn no_contact_update_allocates() {
    let n = 7;
    let dt = 0.01;
    let samples = 2000;
    let estimate: Vec<f64> = (0..samples * n)
        .map(|k| ((k * 7919) % 1000) as f64 / 500.0 - 1.0)
        .collect();
    let qdot: Vec<f64> = (0..samples * n).map(|k| (k as f64 * 1e-3).sin()).collect();
    let floor = calibrate_contact(&estimate, &qdot, &qdot, n, dt, 1.0).unwrap();
    let mut det = ContactDetector::new(&floor).unwrap();
    let mut adm = Admittance::new(n, &AdmittanceConfig::paper())
        .unwrap()
        .with_deadband(&floor.contact_thresholds)
        .unwrap();
    let zero = vec![0.0; n];
    let mut push = vec![0.0; n];
    let mut flags = 0;
    let allocations = count(|| {
        for k in 0..500 {
            push[3] = k as f64 * 0.1;
            let s = det.update(&push, &zero, &zero);
            flags += usize::from(s.contact);
            let input = AdmittanceInput {
                q_d: &zero,
                qdot_d: &zero,
                qddot_d: &zero,
                external_torque_estimate: &push,
            };
            assert!(adm.step(&input, 1e-3).is_ok());
        }
        push[0] = f64::NAN;
        std::hint::black_box(det.update(&push, &zero, &zero));
        std::hint::black_box(det.update(&push[..3], &zero, &zero));
    });
    assert_eq!(allocations, 0, "contact detector / deadband admittance");
    assert!(flags > 0);
}
