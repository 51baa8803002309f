//! Behaviour of the Gaussian RBF layer (docs/method.md sections 3 and 4): activations and output
//! against hand computations, centre placement, online learning, sigma-modification, discard
//! and growth.

use admittance_learning::rbf::{
    lattice_centres, random_centres, GaussianRbfLayer, GrowOutcome, GrowthParams, Integrator,
    LayerOptions, Placement, RbfError, RbfLayerConfig,
};

fn options(gamma: f64, sigma: f64) -> LayerOptions {
    LayerOptions {
        gamma,
        sigma,
        ..LayerOptions::default()
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * (1.0 + a.abs().max(b.abs()))
}

/// Two nodes, hand-computed eq. 9 and eq. 10.
#[test]
fn activation_and_output_match_hand_computation() {
    let mut layer =
        GaussianRbfLayer::with_centres(2, 2, 4, &[0.0, 0.0], 1.0, options(1.0, 0.0)).unwrap();
    assert_eq!(layer.add_node(&[1.0, 2.0], 2.0), Ok(1));
    layer.weights_mut().copy_from_slice(&[1.0, 2.0, 3.0, -1.0]);
    let mut out = [0.0; 2];
    layer.evaluate(&[1.0, 1.0], &mut out).unwrap();
    // ||Z - u1||^2 = 2, eta1 = 1; ||Z - u2||^2 = 1, eta2 = 2.
    let s1 = (-2.0f64).exp();
    let s2 = (-0.25f64).exp();
    assert!(close(layer.activations()[0], s1, 1e-15));
    assert!(close(layer.activations()[1], s2, 1e-15));
    assert!(close(out[0], s1 * 1.0 + s2 * 3.0, 1e-15));
    assert!(close(out[1], s1 * 2.0 - s2 * 1.0, 1e-15));
    // At a centre the activation is exactly one.
    layer.activate(&[1.0, 2.0]).unwrap();
    assert_eq!(layer.activations()[1], 1.0);
    // predict agrees and does not touch the stored activations.
    let mut p = [0.0; 2];
    layer.predict(&[1.0, 1.0], &mut p).unwrap();
    assert!(close(p[0], out[0], 1e-15) && close(p[1], out[1], 1e-15));
    assert_eq!(layer.activations()[1], 1.0);
    assert_eq!(layer.last_input(), Some(&[1.0, 2.0][..]));
    // Frobenius norm of W.
    assert!(close(
        layer.weight_norm(),
        (1.0f64 + 4.0 + 9.0 + 1.0).sqrt(),
        1e-15
    ));
    // activations_at writes s_i(z) for every node without touching state.
    let mut s = [0.0; 4];
    layer.activations_at(&[1.0, 1.0], &mut s).unwrap();
    assert!(close(s[0], s1, 1e-15) && close(s[1], s2, 1e-15));
}

#[test]
fn activations_below_the_cutoff_are_zero() {
    let config = RbfLayerConfig {
        lower: vec![0.0],
        upper: vec![0.0],
        placement: Placement::Lattice { points: vec![1] },
        width: 1.0,
        capacity: 1,
        outputs: 1,
        min_activation: 1e-6,
        ..RbfLayerConfig::default()
    };
    let mut layer = GaussianRbfLayer::from_config(&config).unwrap();
    // exp(-13) = 2.3e-6 is kept, exp(-14) = 8.3e-7 is cut.
    layer.activate(&[13f64.sqrt()]).unwrap();
    assert!(close(layer.activations()[0], (-13.0f64).exp(), 1e-14));
    layer.activate(&[14f64.sqrt()]).unwrap();
    assert_eq!(layer.activations()[0], 0.0);
    // Far beyond the exponent range: zero, no NaN.
    layer.activate(&[1e200]).unwrap();
    assert_eq!(layer.activations()[0], 0.0);
}

#[test]
fn lattice_placement_counts_and_covers_the_box() {
    let lower = [-1.5, -1.3, 0.0];
    let upper = [1.5, 1.3, 2.0];
    let points = [4, 3, 5];
    let c = lattice_centres(&lower, &upper, &points).unwrap();
    assert_eq!(c.len(), 4 * 3 * 5 * 3);
    for k in 0..3 {
        let coords: Vec<f64> = c.iter().skip(k).step_by(3).copied().collect();
        // Corners included, everything inside, the expected number of distinct values.
        let min = coords.iter().copied().fold(f64::INFINITY, f64::min);
        let max = coords.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(min, lower[k]);
        assert!(close(max, upper[k], 1e-15));
        let mut distinct = coords.clone();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        assert_eq!(distinct.len(), points[k]);
        // Even spacing.
        let h = (upper[k] - lower[k]) / (points[k] - 1) as f64;
        for w in distinct.windows(2) {
            assert!(close(w[1] - w[0], h, 1e-12));
        }
    }
    // Every lattice node is distinct.
    let mut nodes: Vec<Vec<u64>> = c
        .chunks(3)
        .map(|u| u.iter().map(|x| x.to_bits()).collect())
        .collect();
    nodes.sort();
    nodes.dedup();
    assert_eq!(nodes.len(), 60);
    // Through the config, the layer holds the same centres.
    let config = RbfLayerConfig {
        lower: lower.to_vec(),
        upper: upper.to_vec(),
        placement: Placement::Lattice {
            points: points.to_vec(),
        },
        width: 0.5,
        capacity: 100,
        outputs: 7,
        ..RbfLayerConfig::default()
    };
    let layer = GaussianRbfLayer::from_config(&config).unwrap();
    assert_eq!(layer.len(), 60);
    assert_eq!(layer.centres(), &c[..]);
    assert!(layer.widths().iter().all(|&w| w == 0.5));
    assert!(layer.weights().iter().all(|&w| w == 0.0));
}

#[test]
fn random_placement_is_seeded_and_inside_the_box() {
    let lower = vec![-1.0, 5.0, -10.0];
    let upper = vec![1.0, 6.0, 10.0];
    let a = random_centres(&lower, &upper, 500, 42).unwrap();
    let b = random_centres(&lower, &upper, 500, 42).unwrap();
    let c = random_centres(&lower, &upper, 500, 43).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    for u in a.chunks(3) {
        for k in 0..3 {
            assert!(u[k] >= lower[k] && u[k] < upper[k]);
        }
    }
    // Roughly uniform: each coordinate's mean is near the box centre (500 samples:
    // standard error of the mean is width / sqrt(12 * 500) = 0.013 width).
    for k in 0..3 {
        let mean = a.iter().skip(k).step_by(3).sum::<f64>() / 500.0;
        let mid = 0.5 * (lower[k] + upper[k]);
        assert!(
            (mean - mid).abs() < 0.06 * (upper[k] - lower[k]),
            "dim {k}: {mean}"
        );
    }
    let config = RbfLayerConfig {
        lower,
        upper,
        placement: Placement::Random {
            count: 500,
            seed: 42,
        },
        width: 1.0,
        capacity: 512,
        outputs: 1,
        ..RbfLayerConfig::default()
    };
    assert_eq!(
        GaussianRbfLayer::from_config(&config).unwrap().centres(),
        &a[..]
    );
}

fn target(z: &[f64]) -> [f64; 2] {
    [
        (1.3 * z[0]).sin() * z[1].cos(),
        0.5 * z[0] * z[1] + 0.2 * z[1],
    ]
}

/// A lattice network learns a smooth 2-input, 2-output function online along a periodic
/// trajectory (deterministic learning), driven by e = f(Z) - f_hat(Z) (the update law of
/// docs/method.md section 3 with e2 replaced by the approximation error). The learned map is
/// then checked with frozen weights along the whole orbit.
#[test]
fn learns_a_smooth_function_online() {
    let config = RbfLayerConfig {
        lower: vec![-2.0, -2.0],
        upper: vec![2.0, 2.0],
        placement: Placement::Lattice { points: vec![9, 9] },
        width: 0.5,
        capacity: 81,
        outputs: 2,
        gamma: 10.0,
        sigma: 1e-4,
        ..RbfLayerConfig::default()
    };
    let mut layer = GaussianRbfLayer::from_config(&config).unwrap();
    let dt = 1e-3;
    let period = 2.0 * std::f64::consts::PI;
    let steps_per_period = (period / dt) as usize;
    let z_at = |t: f64| [1.5 * t.sin(), 1.5 * (2.0 * t + 0.5).sin()];
    // RMS and worst error of the frozen network over 1000 points of the orbit.
    let orbit_error = |layer: &GaussianRbfLayer| {
        let (mut sum, mut worst) = (0.0, 0.0f64);
        let mut out = [0.0; 2];
        for k in 0..1000 {
            let z = z_at(k as f64 * period / 1000.0 + 1e-3);
            layer.predict(&z, &mut out).unwrap();
            let f = target(&z);
            let e2 = (f[0] - out[0]).powi(2) + (f[1] - out[1]).powi(2);
            sum += e2;
            worst = worst.max(e2.sqrt());
        }
        ((sum / 1000.0).sqrt(), worst)
    };
    let (untrained, _) = orbit_error(&layer);
    assert!(untrained > 0.4, "RMS of f along the orbit {untrained}");
    let mut out = [0.0; 2];
    let mut after = Vec::new();
    for p in 0..30 {
        for k in 0..steps_per_period {
            let z = z_at((p * steps_per_period + k) as f64 * dt);
            let f = target(&z);
            layer.evaluate(&z, &mut out).unwrap();
            layer.adapt(&[f[0] - out[0], f[1] - out[1]], dt).unwrap();
        }
        after.push(orbit_error(&layer));
    }
    let (rms5, _) = after[4];
    let (rms30, worst30) = after[29];
    // 30 periods: the RMS error falls by more than 30x, the worst error is below 0.05, and
    // learning is still progressing between periods 5 and 30.
    assert!(
        rms30 < untrained / 30.0,
        "untrained {untrained}, by period {after:?}"
    );
    assert!(worst30 < 0.05, "worst {worst30}");
    assert!(rms30 < rms5 / 2.0, "period 5 {rms5}, period 30 {rms30}");
}

/// With a persistent error, sigma-modification bounds the weights: at a fixed input the
/// law W' = Gamma (S e^T - sigma W) converges to S e^T / sigma, so
/// ||W||_F <= ||S|| ||e|| / sigma; without it the weights grow without bound.
#[test]
fn sigma_modification_bounds_the_weights() {
    for integrator in [Integrator::ExactDecay, Integrator::Euler] {
        let centres = lattice_centres(&[-1.0, -1.0], &[1.0, 1.0], &[3, 3]).unwrap();
        let mut layer =
            GaussianRbfLayer::with_centres(2, 3, 9, &centres, 0.8, options(10.0, 0.5)).unwrap();
        layer.set_integrator(integrator);
        let mut unbounded = layer.clone();
        unbounded.set_gains(10.0, 0.0).unwrap();
        let z = [0.3, -0.2];
        let e = [1.0, -2.0, 0.5];
        let e_norm = (1.0f64 + 4.0 + 0.25).sqrt();
        layer.activate(&z).unwrap();
        unbounded.activate(&z).unwrap();
        let s_norm = layer
            .activations()
            .iter()
            .map(|s| s * s)
            .sum::<f64>()
            .sqrt();
        let bound = s_norm * e_norm / 0.5;
        let dt = 1e-3;
        for _ in 0..20_000 {
            layer.adapt(&e, dt).unwrap();
            unbounded.adapt(&e, dt).unwrap();
            assert!(layer.weight_norm() <= bound * (1.0 + 1e-12));
        }
        // 20 s = 100 time constants (1 / (Gamma sigma) = 0.2 s): at the bound.
        assert!(layer.weight_norm() > bound * (1.0 - 1e-9), "{integrator:?}");
        // W = S e^T / sigma exactly.
        let w = layer.weights();
        for (i, &s) in layer.activations().iter().enumerate() {
            for j in 0..3 {
                assert!(close(w[i * 3 + j], s * e[j] / 0.5, 1e-9));
            }
        }
        // Without sigma-modification the norm grows linearly: Gamma t ||S|| ||e||.
        assert!(close(
            unbounded.weight_norm(),
            10.0 * 20.0 * s_norm * e_norm,
            1e-9
        ));
        assert!(unbounded.weight_norm() > 50.0 * bound);
    }
}

/// With e = 0 the exact-decay integrator reproduces W(t) = W0 exp(-Gamma sigma t) for any
/// step; Euler agrees to first order.
#[test]
fn exact_decay_is_exact_and_euler_is_first_order() {
    let mut exact =
        GaussianRbfLayer::with_centres(1, 2, 2, &[0.0, 1.0], 1.0, options(4.0, 0.25)).unwrap();
    exact.weights_mut().copy_from_slice(&[1.0, -2.0, 3.0, 0.5]);
    let mut euler = exact.clone();
    euler.set_integrator(Integrator::Euler);
    exact.activate(&[0.2]).unwrap();
    euler.activate(&[0.2]).unwrap();
    for _ in 0..10 {
        exact.adapt(&[0.0, 0.0], 0.1).unwrap();
        euler.adapt(&[0.0, 0.0], 0.1).unwrap();
    }
    let decay = (-4.0f64 * 0.25 * 1.0).exp();
    for (w, w0) in exact.weights().iter().zip([1.0, -2.0, 3.0, 0.5]) {
        assert!(close(*w, w0 * decay, 1e-14));
    }
    // Euler: (1 - 0.1)^10 = 0.3487 vs exp(-1) = 0.3679.
    for (w, w0) in euler.weights().iter().zip([1.0, -2.0, 3.0, 0.5]) {
        assert!(close(*w, w0 * 0.9f64.powi(10), 1e-14));
    }
}

#[test]
fn evaluate_adapt_equals_evaluate_then_adapt() {
    let config = RbfLayerConfig {
        lower: vec![-1.0; 28],
        upper: vec![1.0; 28],
        placement: Placement::Random { count: 70, seed: 1 },
        width: 2.5,
        capacity: 80,
        outputs: 7,
        ..RbfLayerConfig::default()
    };
    let mut a = GaussianRbfLayer::from_config(&config).unwrap();
    let mut b = a.clone();
    let (mut oa, mut ob) = ([0.0; 7], [0.0; 7]);
    for k in 0..100 {
        let z: Vec<f64> = (0..28)
            .map(|j| (0.01 * k as f64 + j as f64).sin())
            .collect();
        let e: Vec<f64> = (0..7).map(|j| (0.02 * k as f64 - j as f64).cos()).collect();
        a.evaluate_adapt(&z, &e, 1e-3, &mut oa).unwrap();
        b.evaluate(&z, &mut ob).unwrap();
        b.adapt(&e, 1e-3).unwrap();
        assert_eq!(oa, ob);
        assert_eq!(a.weights(), b.weights());
    }
}

#[test]
fn non_finite_data_is_reported_and_never_reaches_the_weights() {
    let centres = lattice_centres(&[-1.0], &[1.0], &[5]).unwrap();
    let mut layer =
        GaussianRbfLayer::with_centres(1, 2, 8, &centres, 0.5, options(5.0, 0.1)).unwrap();
    let mut out = [7.0; 2];
    // No activations yet.
    assert_eq!(layer.adapt(&[1.0, 1.0], 1e-3), Err(RbfError::NoActivations));
    assert_eq!(layer.output(&mut out), Err(RbfError::NoActivations));
    layer.evaluate(&[0.1], &mut out).unwrap();
    layer.adapt(&[1.0, -1.0], 1e-3).unwrap();
    let before = layer.weights().to_vec();
    assert_eq!(
        layer.adapt(&[f64::NAN, 1.0], 1e-3),
        Err(RbfError::NonFiniteError)
    );
    assert_eq!(
        layer.adapt(&[f64::INFINITY, 1.0], 1e-3),
        Err(RbfError::NonFiniteError)
    );
    assert!(
        matches!(layer.adapt(&[1.0, 1.0], f64::NAN), Err(RbfError::InvalidStep(x)) if x.is_nan())
    );
    assert_eq!(
        layer.adapt(&[1.0, 1.0], -1.0),
        Err(RbfError::InvalidStep(-1.0))
    );
    assert_eq!(
        layer.adapt(&[1.0], 1e-3),
        Err(RbfError::DimensionMismatch {
            what: "error e",
            expected: 2,
            got: 1
        })
    );
    assert_eq!(layer.weights(), &before[..]);
    // A non-finite input invalidates the activations: the next adapt is refused.
    out = [7.0; 2];
    assert_eq!(
        layer.evaluate(&[f64::NAN], &mut out),
        Err(RbfError::NonFiniteInput)
    );
    assert_eq!(out, [7.0; 2]);
    assert_eq!(layer.adapt(&[1.0, 1.0], 1e-3), Err(RbfError::NoActivations));
    assert_eq!(layer.last_input(), None);
    assert_eq!(
        layer.evaluate(&[0.0, 0.0], &mut out),
        Err(RbfError::DimensionMismatch {
            what: "input Z",
            expected: 1,
            got: 2
        })
    );
    assert_eq!(layer.weights(), &before[..]);
    // evaluate_adapt with a bad error: the output is computed, the weights are untouched.
    assert_eq!(
        layer.evaluate_adapt(&[0.1], &[f64::NAN, 0.0], 1e-3, &mut out),
        Err(RbfError::NonFiniteError)
    );
    let mut reference = [0.0; 2];
    layer.predict(&[0.1], &mut reference).unwrap();
    assert_eq!(out, reference);
    assert_eq!(layer.weights(), &before[..]);
    // Growth and explicit addition refuse non-finite centres.
    let g = GrowthParams::new(2, 0.0, 0.0);
    assert_eq!(
        layer.maybe_grow(&[f64::INFINITY], &g),
        Err(RbfError::NonFiniteInput)
    );
    assert_eq!(
        layer.add_node(&[f64::NAN], 1.0),
        Err(RbfError::NonFiniteInput)
    );
    assert_eq!(
        layer.add_node(&[0.0], 0.0),
        Err(RbfError::InvalidWidth(0.0))
    );
    assert_eq!(layer.len(), 5);
}

/// 1-D line of nodes at 0, 1, ..., 10 (width 0.5); the trajectory sweeps [0, 3].
fn swept_line() -> GaussianRbfLayer {
    let config = RbfLayerConfig {
        lower: vec![0.0],
        upper: vec![10.0],
        placement: Placement::Lattice { points: vec![11] },
        width: 0.5,
        capacity: 16,
        outputs: 2,
        relevance_window: 300,
        ..RbfLayerConfig::default()
    };
    let mut layer = GaussianRbfLayer::from_config(&config).unwrap();
    for (i, w) in layer.weights_mut().iter_mut().enumerate() {
        *w = 1.0 + i as f64;
    }
    for k in 0..300 {
        layer.activate(&[3.0 * k as f64 / 299.0]).unwrap();
        layer.track_relevance().unwrap();
    }
    layer
}

#[test]
fn discard_removes_exactly_the_nodes_below_threshold() {
    let mut layer = swept_line();
    let before = layer.clone();
    // Relevance = max activation over the sweep: 1 for nodes 0..=3, exp(-(u - 3)^2 / 0.25)
    // beyond: node 4 -> exp(-4) = 0.018.
    for i in 0..=3 {
        assert!(layer.relevance(i).unwrap() > 0.999);
    }
    assert!(close(layer.relevance(4).unwrap(), (-4.0f64).exp(), 1e-12));
    assert_eq!(layer.discard(0.05), 7);
    assert_eq!(layer.len(), 4);
    assert_eq!(layer.centres(), &[0.0, 1.0, 2.0, 3.0]);
    // Survivors keep their weights, widths and relevance; the outputs of the remaining nodes
    // are unchanged: f_hat_after(z) = f_hat_before(z) - sum over removed nodes.
    assert_eq!(layer.weights(), &before.weights()[..8]);
    assert_eq!(layer.widths(), &before.widths()[..4]);
    for i in 0..4 {
        assert_eq!(layer.relevance(i), before.relevance(i));
    }
    for z in [0.0, 1.7, 3.0, 4.5, 8.0] {
        let (mut after, mut full) = ([0.0; 2], [0.0; 2]);
        layer.predict(&[z], &mut after).unwrap();
        before.predict(&[z], &mut full).unwrap();
        let mut removed = [0.0; 2];
        for i in 4..11 {
            let s = (-(z - i as f64) * (z - i as f64) / 0.25).exp();
            removed[0] += s * before.weights()[2 * i];
            removed[1] += s * before.weights()[2 * i + 1];
        }
        assert!(close(after[0], full[0] - removed[0], 1e-12), "z = {z}");
        assert!(close(after[1], full[1] - removed[1], 1e-12), "z = {z}");
    }
    // Stored activations follow the compaction: output() equals predict at the last input.
    let (mut o, mut p) = ([0.0; 2], [0.0; 2]);
    layer.output(&mut o).unwrap();
    layer.predict(&[3.0], &mut p).unwrap();
    assert_eq!(o, p);
    // A lower threshold removes nothing more; a NaN threshold removes nothing.
    assert_eq!(layer.discard(0.05), 0);
    assert_eq!(layer.discard(f64::NAN), 0);
    // Discarding with a threshold above 1 empties the layer; the layer still works.
    assert_eq!(layer.discard(1.5), 4);
    assert!(layer.is_empty());
    let mut out = [1.0; 2];
    layer.evaluate(&[0.0], &mut out).unwrap();
    assert_eq!(out, [0.0; 2]);
    layer.adapt(&[1.0, 1.0], 1e-3).unwrap();
}

#[test]
fn discard_with_threshold_between_activations() {
    let mut layer = swept_line();
    // exp(-4) = 0.0183 < 0.02: node 4 goes; exp(-16) for node 5 too.
    assert_eq!(layer.discard(0.02), 7);
    let mut layer = swept_line();
    // 0.01 < exp(-4): node 4 stays.
    assert_eq!(layer.discard(0.01), 6);
    assert_eq!(layer.centres(), &[0.0, 1.0, 2.0, 3.0, 4.0]);
    // remove_node compacts in order.
    assert!(layer.remove_node(1));
    assert!(!layer.remove_node(9));
    assert_eq!(layer.centres(), &[0.0, 2.0, 3.0, 4.0]);
    assert_eq!(layer.weight_row(1), Some(&[5.0, 6.0][..]));
}

#[test]
fn growth_adds_at_z_with_zero_weight() {
    let centres = lattice_centres(&[0.0, 0.0], &[1.0, 1.0], &[2, 2]).unwrap();
    let mut layer =
        GaussianRbfLayer::with_centres(2, 3, 6, &centres, 0.4, options(1.0, 0.0)).unwrap();
    layer.add_node(&[0.5, 0.5], 0.8).unwrap();
    layer.weights_mut().iter_mut().for_each(|w| *w = 1.0);
    let params = GrowthParams::new(3, 1.0, 0.1);
    // Near the square: the 3 nearest centres are within 1 on average -> covered.
    let near = layer.maybe_grow(&[0.6, 0.4], &params).unwrap();
    assert!(matches!(near, GrowOutcome::Covered { mean_distance } if mean_distance < 1.0));
    assert!(!near.added());
    assert_eq!(layer.len(), 5);
    // Far away: the mean distance to the 3 nearest exceeds Xi = 1.
    let z = [3.0, 2.0];
    let far = layer.maybe_grow(&z, &params).unwrap();
    let nearest: Vec<f64> = {
        let mut d: Vec<f64> = centres
            .chunks(2)
            .chain(std::iter::once(&[0.5, 0.5][..]))
            .map(|u| ((z[0] - u[0]).powi(2) + (z[1] - u[1]).powi(2)).sqrt())
            .collect();
        d.sort_by(f64::total_cmp);
        d
    };
    let mean = (nearest[0] + nearest[1] + nearest[2]) / 3.0;
    match far {
        GrowOutcome::Added {
            index,
            mean_distance,
        } => {
            assert_eq!(index, 5);
            assert!(close(mean_distance, mean, 1e-14));
        }
        other => panic!("expected growth, got {other:?}"),
    }
    assert_eq!(layer.centre(5), Some(&z[..]));
    assert_eq!(layer.weight_row(5), Some(&[0.0, 0.0, 0.0][..]));
    // Width: mean of the 3 nearest centres' widths: (1, 1) at 0.4, (0.5, 0.5) at 0.8 and
    // (1, 0) or (0, 1)... the three nearest to (3, 2) are (1, 1), (1, 0), (0.5, 0.5).
    assert!(close(layer.widths()[5], (0.4 + 0.4 + 0.8) / 3.0, 1e-15));
    assert_eq!(layer.observed_steps(5), Some(0));
    // Capacity 6 reached: further growth is refused, and so is add_node.
    let full = layer.maybe_grow(&[-5.0, -5.0], &params).unwrap();
    assert!(matches!(full, GrowOutcome::AtCapacity { .. }));
    assert_eq!(
        layer.add_node(&[9.0, 9.0], 1.0),
        Err(RbfError::AtCapacity(6))
    );
    assert_eq!(layer.len(), 6);
}

#[test]
fn growth_respects_spacing_and_step_fraction() {
    // Four centres on a line at 0, 10, 20, 30 (1-D).
    let mut layer =
        GaussianRbfLayer::with_centres(1, 1, 10, &[0.0, 10.0, 20.0, 30.0], 2.0, options(1.0, 0.0))
            .unwrap();
    // z = 0.05: the mean distance to the 3 nearest is ~10 > Xi = 5, but the nearest centre
    // is 0.05 away, closer than the spacing 0.5.
    let params = GrowthParams::new(3, 5.0, 0.5);
    let out = layer.maybe_grow(&[0.05], &params).unwrap();
    assert!(matches!(out, GrowOutcome::TooClose { nearest, .. } if close(nearest, 0.05, 1e-12)));
    assert_eq!(layer.len(), 4);
    // Half-way placement: from the nearest centre (30) towards z = 50 -> 40.
    let half = GrowthParams {
        step_fraction: 0.5,
        ..GrowthParams::new(2, 5.0, 0.5)
    };
    assert!(layer.maybe_grow(&[50.0], &half).unwrap().added());
    assert_eq!(layer.centre(4), Some(&[40.0][..]));
    // Half-way from 40 towards 41 would be 40.5: 0.5 from 40 -> allowed at exactly the
    // spacing; towards 40.8 -> 40.4, too close.
    let wide = GrowthParams {
        step_fraction: 0.5,
        ..GrowthParams::new(1, 0.1, 0.5)
    };
    assert!(matches!(
        layer.maybe_grow(&[40.8], &wide).unwrap(),
        GrowOutcome::TooClose { .. }
    ));
    assert!(layer.maybe_grow(&[41.0], &wide).unwrap().added());
    assert_eq!(layer.centre(5), Some(&[40.5][..]));
    // An empty layer grows at z with the default width.
    let mut empty = GaussianRbfLayer::empty(
        2,
        1,
        3,
        LayerOptions {
            default_width: 0.7,
            ..LayerOptions::default()
        },
    )
    .unwrap();
    let grown = empty
        .maybe_grow(&[1.0, 2.0], &GrowthParams::new(4, 1.0, 0.0))
        .unwrap();
    assert!(
        matches!(grown, GrowOutcome::Added { index: 0, mean_distance } if mean_distance.is_infinite())
    );
    assert_eq!(empty.widths(), &[0.7]);
    assert_eq!(empty.centres(), &[1.0, 2.0]);
}

/// Growth at the last input reuses the distances of `activate`, and the new node is active
/// at once: the next `adapt` trains it.
#[test]
fn growth_at_last_input_trains_the_new_node() {
    let mut layer =
        GaussianRbfLayer::with_centres(1, 1, 4, &[0.0, 1.0], 0.5, options(10.0, 0.0)).unwrap();
    let mut out = [0.0];
    layer.evaluate(&[5.0], &mut out).unwrap();
    let params = GrowthParams::new(2, 1.0, 0.2);
    let grown = layer.maybe_grow_at_last_input(&params).unwrap();
    assert!(
        matches!(grown, GrowOutcome::Added { index: 2, mean_distance } if close(mean_distance, 4.5, 1e-15))
    );
    assert_eq!(layer.centre(2), Some(&[5.0][..]));
    assert_eq!(layer.activations()[2], 1.0);
    layer.adapt(&[1.0], 0.1).unwrap();
    // W_new = Gamma dt s e = 10 * 0.1 * 1 * 1.
    assert!(close(layer.weights()[2], 1.0, 1e-15));
    // Same input again: now covered by the new node (mean of 5 - 5 = 0 and 5 - 1 = 4 is 2
    // > 1, so use m = 1).
    let again = layer
        .maybe_grow_at_last_input(&GrowthParams::new(1, 1.0, 0.2))
        .unwrap();
    assert!(matches!(again, GrowOutcome::Covered { mean_distance } if mean_distance == 0.0));
    // Without a valid input there is nothing to grow at.
    assert_eq!(layer.activate(&[f64::NAN]), Err(RbfError::NonFiniteInput));
    assert_eq!(
        layer.maybe_grow_at_last_input(&params),
        Err(RbfError::NoActivations)
    );
}

/// Discard and growth across several blocks of the kernels' centre layout (blocks of 32
/// nodes): after removing nodes from every block and adding new ones, every activation and
/// the output equal eq. 9 and eq. 10 computed by hand from the public centres.
#[test]
fn activations_follow_the_centres_through_discard_and_growth_over_many_blocks() {
    let d = 5;
    let centre = |i: usize| -> Vec<f64> {
        (0..d)
            .map(|k| ((i * 7 + k * 3) as f64 * 0.61).sin() * 2.0)
            .collect()
    };
    let mut layer = GaussianRbfLayer::empty(
        d,
        3,
        160,
        LayerOptions {
            relevance_window: 1,
            min_activation: 0.0,
            ..options(1.0, 0.0)
        },
    )
    .unwrap();
    // Every third node is narrow: irrelevant at the tracked input, it goes; the others are
    // wide and stay, so the survivors move within and across blocks.
    for i in 0..100 {
        let width = if i % 3 == 1 {
            0.05
        } else {
            3.0 + (i % 4) as f64 * 0.25
        };
        layer.add_node(&centre(i), width).unwrap();
    }
    for (i, w) in layer.weights_mut().iter_mut().enumerate() {
        *w = (i as f64 * 0.37).cos();
    }
    layer.activate(&centre(0)).unwrap();
    layer.track_relevance().unwrap();
    assert_eq!(layer.discard(1e-3), 33);
    for i in 100..150 {
        layer.add_node(&centre(i), 0.8).unwrap();
    }
    assert!(layer.len() > 64, "{} nodes", layer.len());
    let z: Vec<f64> = (0..d).map(|k| 0.3 * k as f64 - 0.5).collect();
    let mut out = [0.0; 3];
    layer.evaluate(&z, &mut out).unwrap();
    let mut expected = [0.0; 3];
    for i in 0..layer.len() {
        let c = layer.centre(i).unwrap();
        let eta = layer.widths()[i];
        let r2: f64 = z.iter().zip(c).map(|(a, b)| (a - b) * (a - b)).sum();
        let s = (-r2 / (eta * eta)).exp();
        assert!(close(layer.activations()[i], s, 1e-13), "node {i}");
        for (e, w) in expected.iter_mut().zip(layer.weight_row(i).unwrap()) {
            *e += s * w;
        }
    }
    for (o, e) in out.iter().zip(&expected) {
        assert!(close(*o, *e, 1e-12), "{o} vs {e}");
    }
}
