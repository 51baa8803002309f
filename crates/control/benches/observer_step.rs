//! Cost of one observer update (issue 4 bar: at most 10 us median for the learned
//! observer with 1000 nodes on 7 joints). Baxter's left arm; the networks are fitted here
//! on a small synthetic free-motion set (the cost of a step depends on the node count and
//! the input width, not on the data), and the inputs sweep a slow motion of every joint.
//! Also the momentum observer and the hybrid observer (momentum + 1000-node residual
//! network with friction-shaped inputs) on the same samples.

use std::hint::black_box;
use std::sync::Arc;

use admittance_control::*;
use admittance_dynamics::Model;
use admittance_learning::broad::{fit, BroadConfig, BroadModel, Dataset, FrictionFeatures};
use criterion::{criterion_group, criterion_main, Criterion};

const N: usize = 7;

fn baxter() -> Arc<Model> {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/baxter_left_arm.urdf");
    Arc::new(Model::from_urdf_file(&path, Some("base"), Some("left_hand")).expect("Baxter model"))
}

/// `(q, qdot, qddot, tau)` along a multi-sine motion of every joint, 1 kHz.
fn samples(count: usize) -> Vec<[[f64; N]; 4]> {
    let centre = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    (0..count)
        .map(|k| {
            let t = k as f64 * 1e-3;
            let mut s = [[0.0; N]; 4];
            for i in 0..N {
                let w = 0.5 + 0.13 * i as f64;
                let a = 0.3;
                s[0][i] = centre[i] + a * (w * t).sin();
                s[1][i] = a * w * (w * t).cos();
                s[2][i] = -a * w * w * (w * t).sin();
                s[3][i] =
                    2.0 * s[0][i] + 0.5 * s[1][i] + 0.1 * s[2][i] + 0.3 * (s[1][i] / 0.01).tanh();
            }
            s
        })
        .collect()
}

fn network(friction: bool) -> BroadModel {
    let data = samples(20_000);
    let mut x = Vec::with_capacity(data.len() * 3 * N);
    let mut y = Vec::with_capacity(data.len() * N);
    for s in &data {
        x.extend_from_slice(&s[0]);
        x.extend_from_slice(&s[1]);
        x.extend_from_slice(&s[2]);
        y.extend_from_slice(&s[3]);
    }
    let set = Dataset::new(&x, &y, 3 * N, N).expect("data");
    let config = BroadConfig {
        nodes: 1000,
        friction: if friction {
            FrictionFeatures::joint_velocities(N)
        } else {
            FrictionFeatures::none()
        },
        centre_subsample: 10_000,
        lambda_grid: vec![1e-6],
        ..BroadConfig::default()
    };
    fit(&set, None, &config).expect("fit").0
}

fn bench_observer(c: &mut Criterion, name: &str, observer: &mut dyn Observer) {
    let data = samples(1000);
    let mut estimate = [0.0; N];
    let mut k = 0usize;
    c.bench_function(name, |b| {
        b.iter(|| {
            let s = &data[k % data.len()];
            let input = ObserverInput {
                time: k as f64 * 1e-3,
                q: &s[0],
                qdot: &s[1],
                qddot: &s[2],
                tau_commanded: &s[3],
            };
            let status = observer.update(black_box(&input), 1e-3, &mut estimate);
            k += 1;
            let _ = black_box((status, &estimate));
        })
    });
}

fn observers(c: &mut Criterion) {
    let mut learned = LearnedObserver::new(network(false), 10.0).expect("learned");
    bench_observer(c, "observer_step/learned_1000_nodes", &mut learned);
    let mut learned_friction = LearnedObserver::new(network(true), 10.0).expect("learned");
    bench_observer(
        c,
        "observer_step/learned_friction_1000_nodes",
        &mut learned_friction,
    );
    let model = baxter();
    let config = MomentumObserverConfig::default();
    let mut momentum = MomentumObserver::new(model.clone(), &config).expect("momentum");
    bench_observer(c, "observer_step/momentum", &mut momentum);
    let mut hybrid = HybridObserver::new(
        MomentumObserver::new(model, &config).expect("momentum"),
        network(true),
    )
    .expect("hybrid");
    bench_observer(c, "observer_step/hybrid_1000_nodes", &mut hybrid);
}

criterion_group!(benches, observers);
criterion_main!(benches);
