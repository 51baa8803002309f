//! Shared helpers of the broad-network tests.
#![allow(dead_code)]

use admittance_learning::broad::{BroadConfig, FrictionFeatures, WidthRule};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Smooth test function of 3 inputs, 2 outputs.
pub fn target(x: &[f64]) -> [f64; 2] {
    [
        (1.3 * x[0]).sin() * (0.7 * x[1]).cos() + 0.3 * x[2],
        (x[0] * x[1]).tanh() + 0.2 * x[2] * x[2] - 0.5,
    ]
}

/// `rows` uniform samples in [-2, 2]^3 with the test function plus noise of std `noise`.
pub fn data(rows: usize, seed: u64, noise: f64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut x = Vec::with_capacity(rows * 3);
    let mut y = Vec::with_capacity(rows * 2);
    for _ in 0..rows {
        let r: [f64; 3] = [
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
        ];
        let t = target(&r);
        x.extend_from_slice(&r);
        y.push(t[0] + noise * rng.random_range(-1.0..1.0));
        y.push(t[1] + noise * rng.random_range(-1.0..1.0));
    }
    (x, y)
}

/// A small configuration: `nodes` nodes, single-threaded unless said otherwise.
pub fn small_config(nodes: usize) -> BroadConfig {
    BroadConfig {
        nodes,
        friction: FrictionFeatures::none(),
        centre_subsample: 2000,
        seed: 11,
        widths: WidthRule::Knn { k: 6, scale: 2.0 },
        lambda_grid: vec![1e-8, 1e-6, 1e-4, 1e-2],
        block_rows: 256,
        threads: 1,
        ..BroadConfig::default()
    }
}

/// Relative Frobenius difference ||a - b|| / ||b||.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    num / den.max(1e-300)
}
