//! Per-step cost of the Gaussian RBF layer (docs/method.md section 3): 512 nodes, d = 28 / 22,
//! n = 7 outputs, as in the controller's two networks.

use admittance_learning::rbf::{GaussianRbfLayer, GrowthParams, Placement, RbfLayerConfig};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

/// 512 random centres in [-1, 1]^d. `width` 3 keeps every node above the cut-off (the worst
/// case: 512 exponentials per step); with width 0.5 almost every node is cut off.
fn layer(dim: usize, width: f64) -> GaussianRbfLayer {
    let config = RbfLayerConfig {
        lower: vec![-1.0; dim],
        upper: vec![1.0; dim],
        placement: Placement::Random {
            count: 512,
            seed: 7,
        },
        width,
        capacity: 612,
        outputs: 7,
        ..RbfLayerConfig::default()
    };
    GaussianRbfLayer::from_config(&config).expect("valid config")
}

/// A smooth trajectory of inputs inside the box.
fn inputs(dim: usize, count: usize) -> Vec<Vec<f64>> {
    (0..count)
        .map(|k| {
            let t = k as f64 * 1e-3;
            (0..dim)
                .map(|j| 0.8 * (t * (1.0 + 0.1 * j as f64) + j as f64).sin())
                .collect()
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let e = [0.1, -0.2, 0.05, 0.3, -0.1, 0.02, 0.07];
    for (dim, width, tag) in [
        (28, 3.0, "all_active"),
        (22, 3.0, "all_active"),
        (28, 0.5, "sparse"),
    ] {
        let zs = inputs(dim, 256);
        let mut net = layer(dim, width);
        let mut out = [0.0; 7];
        let mut k = 0usize;
        c.bench_function(&format!("rbf512_d{dim}_n7_{tag}/evaluate_adapt"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                net.evaluate(black_box(&zs[k]), &mut out).unwrap();
                net.adapt(black_box(&e), 1e-3).unwrap();
                black_box(out[0])
            })
        });
        c.bench_function(
            &format!("rbf512_d{dim}_n7_{tag}/evaluate_adapt_fused"),
            |b| {
                b.iter(|| {
                    k = (k + 1) & 255;
                    net.evaluate_adapt(black_box(&zs[k]), black_box(&e), 1e-3, &mut out)
                        .unwrap();
                    black_box(out[0])
                })
            },
        );
        if dim != 28 {
            continue;
        }
        c.bench_function(&format!("rbf512_d{dim}_n7_{tag}/evaluate"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                net.evaluate(black_box(&zs[k]), &mut out).unwrap();
                black_box(out[0])
            })
        });
        c.bench_function(&format!("rbf512_d{dim}_n7_{tag}/adapt"), |b| {
            b.iter(|| net.adapt(black_box(&e), 1e-3).unwrap())
        });
        c.bench_function(&format!("rbf512_d{dim}_n7_{tag}/track_relevance"), |b| {
            b.iter(|| net.track_relevance().unwrap())
        });
        let far = GrowthParams::new(4, f64::INFINITY, 0.0);
        c.bench_function(
            &format!("rbf512_d{dim}_n7_{tag}/maybe_grow_at_last_input_m4"),
            |b| b.iter(|| net.maybe_grow_at_last_input(black_box(&far)).unwrap()),
        );
        c.bench_function(&format!("rbf512_d{dim}_n7_{tag}/maybe_grow_m4"), |b| {
            b.iter(|| net.maybe_grow(black_box(&zs[3]), black_box(&far)).unwrap())
        });
        c.bench_function(&format!("rbf512_d{dim}_n7_{tag}/predict"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                net.predict(black_box(&zs[k]), &mut out).unwrap();
                black_box(out[0])
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
