//! Unit tests of the RBF layer internals (config parsing, relevance buckets, kernel builds).

use super::kernels::Isa;
use super::*;

fn line_layer(points: usize, width: f64, window: usize) -> GaussianRbfLayer {
    let config = RbfLayerConfig {
        lower: vec![0.0],
        upper: vec![(points - 1) as f64],
        placement: Placement::Lattice {
            points: vec![points],
        },
        width,
        capacity: points + 4,
        outputs: 2,
        relevance_window: window,
        ..RbfLayerConfig::default()
    };
    GaussianRbfLayer::from_config(&config).unwrap()
}

#[test]
fn config_parses_json_and_rejects_unknown_fields() {
    let text = r#"{
        "lower": [-1.5, -1.3], "upper": [1.5, 1.3],
        "placement": { "kind": "lattice", "points": [5, 4] },
        "width": 0.6, "capacity": 64, "outputs": 7, "gamma": 33.3, "sigma": 0.035,
        "integrator": "euler", "relevance_window": 2000,
        "growth": { "neighbours": 4, "distance_threshold": 0.8, "min_spacing": 0.2 }
    }"#;
    let c = RbfLayerConfig::from_json(text).unwrap();
    assert_eq!(c.input_dim(), 2);
    assert_eq!(c.integrator, Integrator::Euler);
    assert_eq!(c.growth.unwrap().step_fraction, 1.0);
    let layer = GaussianRbfLayer::from_config(&c).unwrap();
    assert_eq!(layer.len(), 20);
    assert_eq!(layer.capacity(), 64);
    assert_eq!(layer.growth_params().unwrap().neighbours, 4);
    assert_eq!(layer.relevance_window(), 2000);

    // Defaults fill the optional fields.
    let minimal = r#"{ "lower": [0], "upper": [1], "placement": { "kind": "random", "count": 3, "seed": 9 },
                       "width": 0.5, "capacity": 3, "outputs": 1, "gamma": 1, "sigma": 0 }"#;
    let c = RbfLayerConfig::from_json(minimal).unwrap();
    assert_eq!(c.integrator, Integrator::ExactDecay);
    assert_eq!(c.relevance_window, 1000);
    assert_eq!(c.max_neighbours, 16);
    assert!(c.growth.is_none());

    // Unknown fields, at the top level and inside the placement and growth, are errors.
    assert!(RbfLayerConfig::from_json(
        &minimal.replace("\"sigma\": 0", "\"sigma\": 0, \"sigmaa\": 1")
    )
    .is_err());
    assert!(RbfLayerConfig::from_json(
        &minimal.replace("\"seed\": 9", "\"seed\": 9, \"points\": [2]")
    )
    .is_err());
    let bad_growth = text.replace("\"min_spacing\": 0.2", "\"min_spacing\": 0.2, \"xi\": 1");
    assert!(RbfLayerConfig::from_json(&bad_growth).is_err());
    // Round trip.
    let back: RbfLayerConfig = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
    assert_eq!(back, c);
}

#[test]
fn invalid_configs_are_rejected() {
    let good = RbfLayerConfig {
        lower: vec![0.0, 0.0],
        upper: vec![1.0, 1.0],
        placement: Placement::Lattice { points: vec![2, 3] },
        width: 0.5,
        capacity: 6,
        outputs: 1,
        ..RbfLayerConfig::default()
    };
    assert!(GaussianRbfLayer::from_config(&good).is_ok());
    let check = |f: &dyn Fn(&mut RbfLayerConfig)| {
        let mut c = good.clone();
        f(&mut c);
        GaussianRbfLayer::from_config(&c).unwrap_err()
    };
    assert!(matches!(
        check(&|c| c.capacity = 5),
        RbfConfigError::TooManyNodes {
            nodes: 6,
            capacity: 5
        }
    ));
    assert!(matches!(
        check(&|c| c.upper = vec![1.0]),
        RbfConfigError::BoxDimension { .. }
    ));
    assert!(matches!(
        check(&|c| c.upper[1] = -1.0),
        RbfConfigError::InvalidBox { dim: 1, .. }
    ));
    assert!(matches!(
        check(&|c| c.lower[0] = f64::NAN),
        RbfConfigError::InvalidBox { dim: 0, .. }
    ));
    assert!(matches!(
        check(&|c| c.placement = Placement::Lattice { points: vec![2, 0] }),
        RbfConfigError::LatticeShape { .. }
    ));
    assert!(matches!(
        check(&|c| c.placement = Placement::Lattice { points: vec![2] }),
        RbfConfigError::LatticeShape { .. }
    ));
    assert!(matches!(
        check(&|c| c.width = 0.0),
        RbfConfigError::InvalidWidth(_)
    ));
    assert!(matches!(
        check(&|c| c.width = 1e-200),
        RbfConfigError::InvalidWidth(_)
    ));
    assert!(matches!(
        check(&|c| c.gamma = -1.0),
        RbfConfigError::InvalidGain { name: "gamma", .. }
    ));
    assert!(matches!(
        check(&|c| c.sigma = f64::INFINITY),
        RbfConfigError::InvalidGain { name: "sigma", .. }
    ));
    assert!(matches!(
        check(&|c| c.relevance_window = 0),
        RbfConfigError::InvalidOption { .. }
    ));
    assert!(matches!(
        check(&|c| c.min_activation = 1.0),
        RbfConfigError::InvalidOption { .. }
    ));
    assert!(matches!(
        check(&|c| c.max_neighbours = 0),
        RbfConfigError::InvalidOption { .. }
    ));
    assert!(matches!(
        check(&|c| c.outputs = 0),
        RbfConfigError::EmptyShape { .. }
    ));
    assert!(matches!(
        check(&|c| c.growth = Some(GrowthParams {
            step_fraction: 0.0,
            ..GrowthParams::new(2, 1.0, 0.0)
        })),
        RbfConfigError::InvalidGrowth(_)
    ));
    assert!(matches!(
        check(&|c| c.placement = Placement::Explicit {
            centres: vec![vec![0.0, 1.0], vec![0.0]]
        }),
        RbfConfigError::InvalidCentre { index: 1, .. }
    ));
    assert!(matches!(
        check(&|c| c.placement = Placement::Random { count: 7, seed: 0 }),
        RbfConfigError::TooManyNodes {
            nodes: 7,
            capacity: 6
        }
    ));
    assert!(matches!(
        check(&|c| c.capacity = usize::MAX),
        RbfConfigError::TooManyNodes { .. }
    ));
}

#[test]
fn lattice_order_is_last_dimension_fastest() {
    let c = lattice_centres(&[0.0, 10.0], &[1.0, 12.0], &[2, 3]).unwrap();
    assert_eq!(
        c,
        vec![0.0, 10.0, 0.0, 11.0, 0.0, 12.0, 1.0, 10.0, 1.0, 11.0, 1.0, 12.0]
    );
    // One point per dimension: the midpoint.
    assert_eq!(lattice_centres(&[0.0], &[4.0], &[1]).unwrap(), vec![2.0]);
}

#[test]
fn relevance_is_a_two_bucket_trailing_max() {
    // Nodes at 0..=4 (width 0.5); the window is 4 steps.
    let mut layer = line_layer(5, 0.5, 4);
    let s_at = |z: f64, u: f64| (-(z - u) * (z - u) / 0.25f64).exp();
    // Steps 1..=4 at z = 0 (node 0 fully active), then steps at z = 4.
    for _ in 0..4 {
        layer.activate(&[0.0]).unwrap();
        layer.track_relevance().unwrap();
    }
    // Bucket rotated: the previous bucket holds the max over the 4 steps.
    assert_eq!(layer.relevance(0), Some(1.0));
    assert!((layer.relevance(1).unwrap() - s_at(0.0, 1.0)).abs() < 1e-15);
    assert_eq!(layer.observed_steps(0), Some(4));
    for step in 0..3 {
        layer.activate(&[4.0]).unwrap();
        layer.track_relevance().unwrap();
        // Node 0 is still remembered through the previous bucket.
        assert_eq!(layer.relevance(0), Some(1.0), "step {step}");
        assert_eq!(layer.relevance(4), Some(1.0));
    }
    // The fourth step at z = 4 rotates: the z = 0 bucket is forgotten.
    layer.activate(&[4.0]).unwrap();
    layer.track_relevance().unwrap();
    assert!(layer.relevance(0).unwrap() < 1e-16);
    assert_eq!(layer.relevance(4), Some(1.0));
    // discard(0.05) now removes nodes 0, 1 and 2 (node 3 has exp(-4) = 0.018 < 0.05 too).
    assert!(s_at(4.0, 3.0) < 0.05);
    assert_eq!(layer.discard(0.05), 4);
    assert_eq!(layer.centres(), &[4.0]);
    // A tracking step with invalid activations is refused and records nothing.
    assert_eq!(layer.activate(&[f64::NAN]), Err(RbfError::NonFiniteInput));
    assert_eq!(layer.track_relevance(), Err(RbfError::NoActivations));
    assert_eq!(layer.observed_steps(0), Some(8));
}

#[test]
fn young_nodes_are_never_discarded() {
    let mut layer = line_layer(3, 0.5, 10);
    for _ in 0..9 {
        layer.activate(&[100.0]).unwrap();
        layer.track_relevance().unwrap();
    }
    // Nine steps < window of ten: nothing is judged yet.
    assert_eq!(layer.discard(0.05), 0);
    layer.activate(&[100.0]).unwrap();
    layer.track_relevance().unwrap();
    // A node added now is young even though it is inactive.
    layer.add_node(&[-50.0], 0.5).unwrap();
    assert_eq!(layer.discard(0.05), 3);
    assert_eq!(layer.len(), 1);
    assert_eq!(layer.centres(), &[-50.0]);
    layer.reset_relevance();
    assert_eq!(layer.observed_steps(0), Some(0));
}

#[test]
fn generic_and_avx2_builds_agree() {
    let config = RbfLayerConfig {
        lower: vec![-1.0; 13],
        upper: vec![1.0; 13],
        placement: Placement::Random { count: 77, seed: 3 },
        width: 1.3,
        capacity: 90,
        outputs: 7,
        ..RbfLayerConfig::default()
    };
    let mut fast = GaussianRbfLayer::from_config(&config).unwrap();
    let mut slow = fast.clone();
    slow.force_isa(Isa::Generic);
    let e = [0.3, -0.2, 0.1, 0.0, 0.5, -0.4, 0.2];
    for k in 0..50 {
        let z: Vec<f64> = (0..13)
            .map(|j| ((k * 13 + j) as f64 * 0.37).sin())
            .collect();
        let (mut a, mut b) = ([0.0; 7], [0.0; 7]);
        fast.evaluate_adapt(&z, &e, 1e-2, &mut a).unwrap();
        slow.evaluate_adapt(&z, &e, 1e-2, &mut b).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()), "{x} vs {y}");
        }
        for (x, y) in fast.activations().iter().zip(slow.activations()) {
            assert!((x - y).abs() <= 1e-14);
        }
        let (mut p, mut q) = ([0.0; 7], [0.0; 7]);
        fast.predict(&z, &mut p).unwrap();
        slow.predict(&z, &mut q).unwrap();
        for (x, y) in p.iter().zip(&q) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()));
        }
    }
}

#[test]
fn step_coefficients_match_the_ode() {
    let mut layer = line_layer(2, 1.0, 1);
    layer.set_gains(20.0, 0.5).unwrap();
    let dt = 1e-3;
    let (a, b) = layer.step_coefficients_for_test(dt);
    assert!((a - (-20.0f64 * 0.5 * dt).exp()).abs() < 1e-16);
    // b = (1 - a) / sigma (the reference loses digits to cancellation: relative check).
    assert!((b - (1.0 - (-10.0 * dt).exp()) / 0.5).abs() < 1e-12 * b);
    assert!((b - 20.0 * dt).abs() < 20.0 * dt * 10.0 * dt);
    layer.set_integrator(Integrator::Euler);
    assert_eq!(
        layer.step_coefficients_for_test(dt),
        (1.0 - 10.0 * dt, 20.0 * dt)
    );
    layer.set_gains(20.0, 0.0).unwrap();
    layer.set_integrator(Integrator::ExactDecay);
    assert_eq!(layer.step_coefficients_for_test(dt), (1.0, 20.0 * dt));
    assert_eq!(layer.set_gains(-1.0, 0.0), Err(RbfError::InvalidGain(-1.0)));
}
