//! The per-step methods of the Gaussian RBF layer allocate nothing after construction
//! (docs/method.md section 4: dynamic nodes with no allocation inside the control step).
//!
//! The counting allocator of `admittance-testkit` wraps `System`; only allocations made by
//! this test's thread inside the measured closure are counted, so the test harness cannot
//! interfere.

use admittance_learning::rbf::{
    GaussianRbfLayer, GrowthParams, Integrator, Placement, RbfLayerConfig,
};
use admittance_testkit::count_allocations as allocations;

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

#[test]
fn counting_allocator_counts() {
    let n = allocations(|| {
        let v = vec![1u8; 100];
        std::hint::black_box(&v);
    });
    assert_eq!(n, 1);
}

#[test]
fn per_step_methods_do_not_allocate() {
    for integrator in [Integrator::ExactDecay, Integrator::Euler] {
        let config = RbfLayerConfig {
            lower: vec![-1.0; 28],
            upper: vec![1.0; 28],
            placement: Placement::Random {
                count: 512,
                seed: 5,
            },
            width: 1.5,
            capacity: 640,
            outputs: 7,
            integrator,
            relevance_window: 50,
            ..RbfLayerConfig::default()
        };
        let mut layer = GaussianRbfLayer::from_config(&config).unwrap();
        let zs: Vec<Vec<f64>> = (0..300)
            .map(|k| {
                (0..28)
                    .map(|j| 0.9 * (0.02 * k as f64 + 0.3 * j as f64).sin())
                    .collect()
            })
            .collect();
        let far: Vec<Vec<f64>> = (0..200)
            .map(|k| {
                (0..28)
                    .map(|j| 3.0 + 0.5 * ((k * 28 + j) as f64).sin())
                    .collect()
            })
            .collect();
        let e = [0.1, -0.2, 0.3, 0.0, 0.05, -0.1, 0.2];
        let bad_e = [f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let mut bad_z = zs[0].clone();
        bad_z[3] = f64::INFINITY;
        let grow = GrowthParams::new(4, 1.0, 0.3);
        let grow_half = GrowthParams {
            step_fraction: 0.5,
            ..grow
        };
        let mut out = [0.0; 7];
        let mut acts = vec![0.0; 640];
        let mut sink = 0.0;

        let count = allocations(|| {
            for (k, z) in zs.iter().enumerate() {
                layer.evaluate(z, &mut out).unwrap();
                layer.adapt(&e, 1e-3).unwrap();
                layer.evaluate_adapt(z, &e, 1e-3, &mut out).unwrap();
                layer.activate(z).unwrap();
                layer.output(&mut out).unwrap();
                layer.track_relevance().unwrap();
                layer.predict(z, &mut out).unwrap();
                layer.activations_at(z, &mut acts).unwrap();
                sink += layer.weight_norm() + out[0];
                if k % 60 == 59 {
                    sink += layer.discard(0.05) as f64;
                }
                // Error paths.
                assert!(layer.adapt(&bad_e, 1e-3).is_err());
                assert!(layer.adapt(&e[..3], 1e-3).is_err());
                assert!(layer.evaluate_adapt(z, &bad_e, 1e-3, &mut out).is_err());
                assert!(layer.evaluate(&bad_z, &mut out).is_err());
                assert!(layer.track_relevance().is_err());
                layer.activate(z).unwrap();
            }
            for (k, z) in far.iter().enumerate() {
                sink += layer.maybe_grow(z, &grow).unwrap().added() as u8 as f64;
                sink += layer.maybe_grow(z, &grow_half).unwrap().added() as u8 as f64;
                layer.activate(z).unwrap();
                sink += layer.maybe_grow_at_last_input(&grow).unwrap().added() as u8 as f64;
                layer.adapt(&e, 1e-3).unwrap();
                if k % 50 == 0 {
                    let _ = layer.add_node(z, 0.7);
                    layer.remove_node(k % 7);
                }
            }
            // Fill to capacity, then growth and addition are refused (no allocation either).
            while layer.len() < layer.capacity() {
                layer.add_node(&far[0], 0.5).unwrap();
            }
            assert!(layer.add_node(&far[1], 0.5).is_err());
            assert!(!layer.maybe_grow(&[9.0; 28], &grow).unwrap().added());
            layer.reset_relevance();
            layer.reset_weights();
            layer.set_gains(5.0, 0.1).unwrap();
            sink += layer.discard(0.5) as f64;
        });
        std::hint::black_box(sink);
        assert_eq!(
            count, 0,
            "{integrator:?}: {count} allocations in the per-step methods"
        );
    }
}
