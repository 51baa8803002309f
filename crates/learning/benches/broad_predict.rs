//! One-sample prediction of the broad network at the observer's size: L = 1000 nodes,
//! d_in = 21 ([q, q', q''] of 7 joints), d_out = 7, friction features on the velocities
//! (docs/method.md sections 5 and 7). The observer calls this at 1 kHz.
//! Also: the vectorised exp against libm's on 1000 values (one prediction's worth).

use admittance_learning::broad::{exp_nonpositive_slice, fit, BroadConfig, Dataset};
use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

fn bench_predict(c: &mut Criterion) {
    let j = 7;
    let rows = 5000;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let x: Vec<f64> = (0..rows * 3 * j)
        .map(|_| rng.random_range(-1.5..1.5))
        .collect();
    let y: Vec<f64> = x
        .chunks(3 * j)
        .flat_map(|r| {
            (0..j).map(move |i| {
                (r[i] + 0.5 * r[j + i]).sin() + 0.3 * r[2 * j + i] + 0.2 * (r[j + i] / 0.02).tanh()
            })
        })
        .collect();
    let train = Dataset::new(&x, &y, 3 * j, j).unwrap();
    let mut cfg = BroadConfig::for_arm(j);
    cfg.nodes = 1000;
    cfg.lambda_grid = vec![1e-4];
    let (model, _) = fit(&train, None, &cfg).unwrap();
    let mut ws = model.workspace();
    let mut out = vec![0.0; j];
    let inputs: Vec<&[f64]> = x.chunks(3 * j).take(256).collect();
    let mut i = 0;
    c.bench_function("broad_predict_into_L1000_d21_n7", |b| {
        b.iter(|| {
            i = (i + 1) % inputs.len();
            model
                .predict_into(black_box(inputs[i]), &mut out, &mut ws)
                .unwrap();
            black_box(&out);
        })
    });

    let vals: Vec<f64> = (0..1000).map(|i| -(i as f64) * 0.003).collect();
    let mut buf = vals.clone();
    c.bench_function("exp_fast_1000", |b| {
        b.iter(|| {
            buf.copy_from_slice(&vals);
            exp_nonpositive_slice(black_box(&mut buf));
            black_box(&buf);
        })
    });
    c.bench_function("exp_libm_1000", |b| {
        b.iter(|| {
            for (o, v) in buf.iter_mut().zip(&vals) {
                *o = black_box(*v).exp();
            }
            black_box(&buf);
        })
    });
}

criterion_group!(benches, bench_predict);
criterion_main!(benches);
