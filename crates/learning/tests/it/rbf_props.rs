//! Property tests of the Gaussian RBF layer (docs/method.md sections 3 and 4).

use admittance_learning::rbf::{GaussianRbfLayer, GrowthParams, LayerOptions};
use proptest::prelude::*;

const D: usize = 3;
const N: usize = 2;

fn layer_from(centres: &[f64], widths: &[f64], capacity: usize, window: usize) -> GaussianRbfLayer {
    let options = LayerOptions {
        relevance_window: window,
        min_activation: 0.0,
        ..LayerOptions::default()
    };
    let mut layer = GaussianRbfLayer::empty(D, N, capacity, options).unwrap();
    for (u, &w) in centres.chunks(D).zip(widths) {
        layer.add_node(u, w).unwrap();
    }
    layer
}

fn coords(count: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-3.0f64..3.0, count * D)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, failure_persistence: None, ..ProptestConfig::default() })]

    /// Eq. 9: activations lie in [0, 1], equal exp(-||Z - u||^2 / eta^2) to rounding, and
    /// are exactly 1 at a centre; predict agrees with evaluate.
    #[test]
    fn activations_follow_eq9(
        centres in coords(12),
        widths in prop::collection::vec(0.05f64..4.0, 12),
        z in prop::collection::vec(-4.0f64..4.0, D),
        weights in prop::collection::vec(-5.0f64..5.0, 12 * N),
    ) {
        let mut layer = layer_from(&centres, &widths, 16, 10);
        layer.weights_mut().copy_from_slice(&weights);
        let mut out = [0.0; N];
        layer.evaluate(&z, &mut out).unwrap();
        for (i, &s) in layer.activations().iter().enumerate() {
            let u = &centres[i * D..(i + 1) * D];
            let d2: f64 = u.iter().zip(&z).map(|(a, b)| (a - b) * (a - b)).sum();
            let x = d2 / (widths[i] * widths[i]);
            let expected = (-x).exp();
            prop_assert!((0.0..=1.0).contains(&s));
            if x > 708.0 {
                // Below exp(-708) (the normal range) activations are flushed to zero.
                prop_assert_eq!(s, 0.0);
            } else {
                // One rounding of the exponent x costs x ulp of relative error in exp(-x).
                prop_assert!((s - expected).abs() <= 1e-15 * (4.0 + x) * expected, "{s} vs {expected}");
            }
        }
        let mut reference = [0.0; N];
        for (i, &s) in layer.activations().iter().enumerate() {
            for j in 0..N {
                reference[j] += s * weights[i * N + j];
            }
        }
        let mut p = [0.0; N];
        layer.predict(&z, &mut p).unwrap();
        for j in 0..N {
            prop_assert!((out[j] - reference[j]).abs() <= 1e-12 * (1.0 + reference[j].abs()));
            prop_assert!((p[j] - out[j]).abs() <= 1e-12 * (1.0 + out[j].abs()));
        }
        layer.activate(&centres[..D]).unwrap();
        prop_assert_eq!(layer.activations()[0], 1.0);
    }

    /// Discard never increases the node count, removes exactly the nodes that are old
    /// enough and below the threshold, and the survivors keep their (centre, width, weight
    /// row, relevance), in order.
    #[test]
    fn discard_compacts_and_preserves_survivors(
        centres in coords(20),
        widths in prop::collection::vec(0.1f64..2.0, 20),
        path in prop::collection::vec(-3.0f64..3.0, 8 * D),
        threshold in 0.0f64..1.0,
        late in 0usize..20,
    ) {
        let window = 4;
        let mut layer = layer_from(&centres[..(20 - late.min(5)) * D], &widths, 24, window);
        for (i, w) in layer.weights_mut().iter_mut().enumerate() {
            *w = i as f64;
        }
        for (k, z) in path.chunks(D).enumerate() {
            layer.activate(z).unwrap();
            layer.track_relevance().unwrap();
            // Some nodes arrive late and are younger than the window.
            if k == 5 {
                for i in (20 - late.min(5))..20 {
                    layer.add_node(&centres[i * D..(i + 1) * D], widths[i]).unwrap();
                }
            }
        }
        let before = layer.clone();
        let removed = layer.discard(threshold);
        prop_assert!(layer.len() <= before.len());
        prop_assert_eq!(layer.len() + removed, before.len());
        let mut j = 0;
        for i in 0..before.len() {
            let rel = before.relevance(i).unwrap();
            let old = before.observed_steps(i).unwrap() >= window as u64;
            let should_go = old && rel < threshold;
            if should_go {
                continue;
            }
            prop_assert_eq!(layer.centre(j), before.centre(i));
            prop_assert_eq!(layer.weight_row(j), before.weight_row(i));
            prop_assert_eq!(layer.widths()[j], before.widths()[i]);
            prop_assert_eq!(layer.relevance(j), Some(rel));
            prop_assert_eq!(layer.activations()[j], before.activations()[i]);
            j += 1;
        }
        prop_assert_eq!(j, layer.len());
    }

    /// Growth from any sequence of inputs keeps the count within capacity and every pair of
    /// centres at least `min_spacing` apart; every added node starts with zero weight.
    #[test]
    fn growth_respects_capacity_and_spacing(
        inputs in coords(60),
        m in 1usize..6,
        xi in 0.0f64..2.0,
        spacing in 0.05f64..1.0,
        fraction in 0.2f64..=1.0,
    ) {
        let capacity = 25;
        let mut layer = GaussianRbfLayer::empty(D, N, capacity, LayerOptions::default()).unwrap();
        let params = GrowthParams { neighbours: m, distance_threshold: xi, min_spacing: spacing, step_fraction: fraction };
        for z in inputs.chunks(D) {
            let before = layer.len();
            let grown = layer.maybe_grow(z, &params).unwrap();
            prop_assert_eq!(layer.len(), before + grown.added() as usize);
            prop_assert!(layer.len() <= capacity);
            if grown.added() {
                prop_assert!(layer.weight_row(before).unwrap().iter().all(|&w| w == 0.0));
            }
            // Train a little so that later weights are non-zero.
            layer.activate(z).unwrap();
            layer.adapt(&[1.0, -1.0], 1e-2).unwrap();
        }
        let c = layer.centres();
        for a in 0..layer.len() {
            for b in 0..a {
                let d2: f64 = (0..D).map(|k| (c[a * D + k] - c[b * D + k]).powi(2)).sum();
                prop_assert!(d2.sqrt() >= spacing * (1.0 - 1e-12), "{a} {b}: {}", d2.sqrt());
            }
        }
    }

    /// The fused step equals evaluate followed by adapt, bit for bit.
    #[test]
    fn fused_step_is_exactly_evaluate_then_adapt(
        centres in coords(9),
        z in prop::collection::vec(-3.0f64..3.0, D),
        e in prop::collection::vec(-2.0f64..2.0, N),
        dt in 0.0f64..0.1,
    ) {
        let mut a = layer_from(&centres, &[0.8; 9], 9, 1);
        for (i, w) in a.weights_mut().iter_mut().enumerate() {
            *w = (i as f64).sin();
        }
        let mut b = a.clone();
        let (mut oa, mut ob) = ([0.0; N], [0.0; N]);
        a.evaluate_adapt(&z, &e, dt, &mut oa).unwrap();
        b.evaluate(&z, &mut ob).unwrap();
        b.adapt(&e, dt).unwrap();
        prop_assert_eq!(oa, ob);
        prop_assert_eq!(a.weights(), b.weights());
    }
}
