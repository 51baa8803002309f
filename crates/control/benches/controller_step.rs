//! Cost of one control step (issue 3 bar: at most 10 us median with 512-node networks on
//! 7 joints). Baxter's left arm, inputs along experiment A's trajectory (s0 moving, the
//! other joints at the paper's fixed angles, small tracking errors), adaptation and
//! relevance tracking on.

use std::hint::black_box;
use std::sync::Arc;

use admittance_control::*;
use admittance_dynamics::Model;
use criterion::{criterion_group, criterion_main, Criterion};

fn baxter() -> Arc<Model> {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/baxter_left_arm.urdf");
    Arc::new(Model::from_urdf_file(&path, Some("base"), Some("left_hand")).expect("Baxter model"))
}

/// 1000 samples (1 s at 1 kHz, one period of every signal, so that the errors have zero
/// mean over the loop and the adapting weights stay on a bounded orbit instead of drifting
/// to the torque limits) of (q, qdot, q_ref, qdot_ref, qddot_ref): s0 follows
/// `0.5 sin(2 pi t)`, the other joints sit at experiment A's angles, and the measurement
/// carries a small periodic tracking error.
fn samples() -> Vec<[[f64; 7]; 5]> {
    let fixed = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    let w = 2.0 * std::f64::consts::PI;
    (0..1000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            let mut s = [[0.0; 7]; 5];
            s[2] = fixed;
            s[2][0] = 0.5 * (w * t).sin();
            s[3][0] = 0.5 * w * (w * t).cos();
            s[4][0] = -0.5 * w * w * (w * t).sin();
            let (r, rd) = (s[2], s[3]);
            let [q_meas, v_meas, ..] = &mut s;
            for i in 0..7 {
                let phase = w * t + i as f64;
                q_meas[i] = r[i] - 0.005 * phase.sin();
                v_meas[i] = rd[i] - 0.005 * w * phase.cos();
            }
            s
        })
        .collect()
}

fn bench_controller(c: &mut Criterion, name: &str, ctrl: &mut dyn Controller) {
    let data = samples();
    let est = [0.0; 7];
    let mut tau = [0.0; 7];
    let mut k = 0usize;
    let step = |ctrl: &mut dyn Controller, k: usize, tau: &mut [f64; 7]| {
        let s = &data[k];
        let input = ControlInput {
            time: k as f64 * 1e-3,
            q: &s[0],
            qdot: &s[1],
            q_ref: &s[2],
            qdot_ref: &s[3],
            qddot_ref: &s[4],
            external_torque_estimate: &est,
        };
        ctrl.step(black_box(&input), 1e-3, tau)
    };
    // 20 s of warm-up so that the weights are on their periodic orbit.
    for j in 0..20_000 {
        let _ = step(ctrl, j % 1000, &mut tau);
    }
    assert!(tau.iter().all(|t| t.is_finite()));
    c.bench_function(name, |b| {
        b.iter(|| {
            k = (k + 1) % 1000;
            let status = step(ctrl, k, &mut tau);
            black_box((status, tau[0]))
        })
    });
    eprintln!("{name}: torque after the run {tau:?}");
}

fn bench(c: &mut Criterion) {
    let model = baxter();
    let mut nn = NeuralController::new(model.clone(), &NeuralControllerConfig::default()).unwrap();
    assert_eq!(
        (
            nn.node_count(NetworkId::F),
            nn.node_count(NetworkId::Deadzone)
        ),
        (512, 512)
    );
    bench_controller(c, "nn_512x2_7dof/step", &mut nn);
    let with_e2 = NeuralControllerConfig {
        f: FNetworkConfig::Lumped {
            include_e2: true,
            network: NetworkConfig::default(),
        },
        ..Default::default()
    };
    let mut nn = NeuralController::new(model.clone(), &with_e2).unwrap();
    bench_controller(c, "nn_512x2_7dof_e2/step", &mut nn);
    let mut nn = NeuralController::new(
        model.clone(),
        &NeuralControllerConfig {
            deadzone_compensation: false,
            ..Default::default()
        },
    )
    .unwrap();
    bench_controller(c, "nn_512_7dof_uncompensated/step", &mut nn);
    let split = NeuralControllerConfig {
        f: FNetworkConfig::Split {
            m: NetworkConfig::default(),
            c: NetworkConfig::default(),
            g: NetworkConfig::default(),
        },
        ..Default::default()
    };
    let mut nn = NeuralController::new(model.clone(), &split).unwrap();
    bench_controller(c, "nn_split_512x4_7dof/step", &mut nn);
    let pd = PdConfig {
        kp: 50.0.into(),
        kd: 5.0.into(),
        gravity_compensation: true,
        safe_hold: SafeHoldConfig::default(),
    };
    let mut pd = PdController::new(model.clone(), &pd).unwrap();
    bench_controller(c, "pd_gravity_7dof/step", &mut pd);
    let ct = ComputedTorqueConfig {
        kp: 100.0.into(),
        kd: 20.0.into(),
        safe_hold: SafeHoldConfig::default(),
    };
    let mut ct = ComputedTorqueController::new(model.clone(), &ct).unwrap();
    bench_controller(c, "computed_torque_7dof/step", &mut ct);

    let mut adm = Admittance::new(7, &AdmittanceConfig::paper()).unwrap();
    let data = samples();
    let est = [0.3, -0.2, 0.1, 0.0, 0.05, -0.1, 0.2];
    let mut k = 0usize;
    c.bench_function("admittance_7dof/step", |b| {
        b.iter(|| {
            k = (k + 1) % data.len();
            let s = &data[k];
            let input = AdmittanceInput {
                q_d: &s[2],
                qdot_d: &s[3],
                qddot_d: &s[4],
                external_torque_estimate: &est,
            };
            black_box(adm.step(black_box(&input), 1e-3))
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
