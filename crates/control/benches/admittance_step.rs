//! Cost of one admittance step on Baxter's 7 joints: the joint-space `Admittance` (the
//! paper's C_d = 3, G_d = 5 with saturation) beside the `TaskSpaceAdmittance` (default
//! configuration: six task axes, wrench estimate, admittance, second-order inverse
//! kinematics with the null-space posture, joint-limit saturation), on the same inputs:
//! s0 follows `0.5 sin(2 pi t)`, the other joints sit at experiment A's pose, the measured
//! position lags a little, and the estimate is the joint torque of a 5 N push at the hand.
//!
//! `cargo bench -p admittance-control --bench admittance_step`

use std::hint::black_box;
use std::sync::Arc;

use admittance_control::*;
use admittance_dynamics::{tip_jacobian, Data, Model};
use criterion::{criterion_group, criterion_main, Criterion};

fn baxter() -> Arc<Model> {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/baxter_left_arm.urdf");
    Arc::new(Model::from_urdf_file(&path, Some("base"), Some("left_hand")).expect("Baxter model"))
}

/// One sample: q_d, q_d', q_d'', measured q, estimate.
type Sample = [[f64; 7]; 5];

/// 1000 samples (1 s at 1 kHz, one period).
fn samples(model: &Model) -> Vec<Sample> {
    let fixed = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    let w = 2.0 * std::f64::consts::PI;
    let mut data = Data::new(model);
    (0..1000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            let mut s = [[0.0; 7]; 5];
            s[0] = fixed;
            s[0][0] = 0.5 * (w * t).sin();
            s[1][0] = 0.5 * w * (w * t).cos();
            s[2][0] = -0.5 * w * w * (w * t).sin();
            let [q_d, _, _, q, tau] = &mut s;
            for (i, (q, d)) in q.iter_mut().zip(q_d.iter()).enumerate() {
                *q = d - 0.005 * (w * t + i as f64).sin();
            }
            let j = tip_jacobian(model, &mut data, q).unwrap();
            for (i, t) in tau.iter_mut().enumerate() {
                // tau = J^T f with f = 5 N along y.
                *t = 5.0 * j[(1, i)];
            }
            s
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let model = baxter();
    let data = samples(&model);
    let mut joint = Admittance::new(7, &AdmittanceConfig::paper()).unwrap();
    let mut task =
        TaskSpaceAdmittance::new(model.clone(), &TaskSpaceAdmittanceConfig::default()).unwrap();
    fn input(s: &Sample) -> ReferenceInput<'_> {
        ReferenceInput {
            q_d: &s[0],
            qdot_d: &s[1],
            qddot_d: &s[2],
            q: &s[3],
            external_torque_estimate: &s[4],
        }
    }
    // One period of warm-up: both are past their start.
    for s in &data {
        assert!(task.step(&input(s), 1e-3).is_ok());
        assert!(joint.step_reference(&input(s), 1e-3).is_ok());
    }
    let mut group = c.benchmark_group("admittance_7dof");
    let mut k = 0usize;
    group.bench_function("joint_space/step", |b| {
        b.iter(|| {
            k = (k + 1) % data.len();
            let s = &data[k];
            let direct = AdmittanceInput {
                q_d: &s[0],
                qdot_d: &s[1],
                qddot_d: &s[2],
                external_torque_estimate: &s[4],
            };
            black_box(joint.step(black_box(&direct), 1e-3))
        })
    });
    group.bench_function("task_space/step", |b| {
        b.iter(|| {
            k = (k + 1) % data.len();
            black_box(task.step(black_box(&input(&data[k])), 1e-3))
        })
    });
    group.finish();
    assert!(task.q_r().iter().all(|v| v.is_finite()));
    eprintln!(
        "task space after the run: wrench {:?}, damping (wrench, ik) {} {}",
        task.wrench_estimate(),
        task.wrench_damping(),
        task.ik_damping()
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
