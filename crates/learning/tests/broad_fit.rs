//! Fitting, prediction and input checks of the flat RBF network (docs/method.md section 5).

mod broad_common;

use admittance_learning::broad::{
    fit, fit_with_nodes, BroadConfig, BroadError, Dataset, FrictionFeatures, GramStrategy, NodeSet,
    WidthRule,
};
use admittance_testkit::count_allocations;
use broad_common::{data, rel_diff, small_config, target};
use proptest::prelude::*;

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

#[test]
fn fit_learns_a_smooth_map() {
    let (x, y) = data(4000, 1, 0.01);
    let (xv, yv) = data(1000, 2, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let val = Dataset::new(&xv, &yv, 3, 2).unwrap();
    let (model, report) = fit(&train, Some(&val), &small_config(80)).unwrap();
    assert_eq!(report.samples, 4000);
    assert_eq!(report.validation_samples, 1000);
    assert_eq!(report.nodes, 80);
    assert_eq!(report.pattern_width, 3 + 1 + 80);
    assert_eq!(model.pattern_width(), 84);
    assert_eq!(report.validation_nrmse.len(), 2);
    for e in &report.validation_nrmse {
        assert!(*e < 0.1, "validation NRMSE {e}");
    }
    for e in &report.train_nrmse {
        assert!(*e < 0.1, "train NRMSE {e}");
    }
    // The reported validation error is the model's error on the validation set.
    let e = model.evaluate(&val, 1).unwrap();
    assert!(rel_diff(&e, &report.validation_nrmse) < 1e-9);
    // Timings are filled.
    assert!(report.times.total_s > 0.0 && report.times.gram_s > 0.0);
}

#[test]
fn lambda_choice_is_the_validation_minimum() {
    let (x, y) = data(1500, 3, 0.3);
    let (xv, yv) = data(500, 4, 0.3);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let val = Dataset::new(&xv, &yv, 3, 2).unwrap();
    let mut cfg = small_config(120);
    cfg.lambda_grid = vec![1e-9, 1e-7, 1e-5, 1e-3, 1e-1, 10.0];
    let (model, report) = fit(&train, Some(&val), &cfg).unwrap();
    let best = report
        .lambda_scan
        .iter()
        .filter_map(|s| s.mean_nrmse.map(|m| (m, s.lambda_rel)))
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a });
    assert_eq!(report.lambda_rel, best.1);
    assert_eq!(model.lambda_rel(), best.1);
    assert_eq!(model.lambda(), best.1 * 1500.0);
    // Noisy targets and many nodes: the smallest lambda overfits, the largest underfits.
    let first = report.lambda_scan.first().unwrap().mean_nrmse.unwrap();
    let last = report.lambda_scan.last().unwrap().mean_nrmse.unwrap();
    assert!(best.0 < first && best.0 < last, "{:?}", report.lambda_scan);
}

/// Explicit pattern matrix: the ridge normal equations hold, with the bias unregularised
/// (so the training residuals have zero mean).
#[test]
fn weights_solve_the_ridge_normal_equations() {
    let (x, y) = data(700, 5, 0.05);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(30);
    cfg.lambda_grid = vec![1e-4];
    cfg.friction = FrictionFeatures {
        columns: vec![1],
        scales: vec![0.1, 0.5],
    };
    let (model, _) = fit(&train, None, &cfg).unwrap();
    let p = model.pattern_width();
    assert_eq!(p, 3 + 2 + 1 + 30);
    let n = 700;
    let mut a = vec![0.0; n * p];
    for i in 0..n {
        model
            .pattern_into(train.input_row(i), &mut a[i * p..(i + 1) * p])
            .unwrap();
    }
    let w = model.weights();
    let bias = model.bias_index();
    assert_eq!(bias, 5);
    for o in 0..2 {
        // r = y - A w
        let r: Vec<f64> = (0..n)
            .map(|i| y[i * 2 + o] - (0..p).map(|j| a[i * p + j] * w[j * 2 + o]).sum::<f64>())
            .collect();
        // A^T r = lambda D w
        let mut worst = 0.0f64;
        let mut scale = 0.0f64;
        for j in 0..p {
            let atr: f64 = (0..n).map(|i| a[i * p + j] * r[i]).sum();
            let reg = if j == bias {
                0.0
            } else {
                model.lambda() * w[j * 2 + o]
            };
            worst = worst.max((atr - reg).abs());
            let aty: f64 = (0..n).map(|i| a[i * p + j] * y[i * 2 + o]).sum();
            scale = scale.max(aty.abs());
        }
        assert!(
            worst < 1e-9 * scale,
            "normal equations residual {worst} (scale {scale})"
        );
        let mean_r = r.iter().sum::<f64>() / n as f64;
        assert!(mean_r.abs() < 1e-10, "mean residual {mean_r}");
    }
}

#[test]
fn predict_into_matches_pattern_times_weights_and_batch() {
    let (x, y) = data(1200, 6, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(50);
    cfg.lambda_grid = vec![1e-6];
    cfg.friction = FrictionFeatures {
        columns: vec![0, 2],
        scales: vec![0.05],
    };
    let (model, _) = fit(&train, None, &cfg).unwrap();
    let mut ws = model.workspace();
    let mut out = [0.0; 2];
    let mut a = vec![0.0; model.pattern_width()];
    let mut batch = vec![0.0; 200 * 2];
    model.predict_batch(&x[..600], &mut batch).unwrap();
    let mut abs_err = 0.0;
    for i in 0..200 {
        let xi = train.input_row(i);
        model.predict_into(xi, &mut out, &mut ws).unwrap();
        model.pattern_into(xi, &mut a).unwrap();
        for o in 0..2 {
            let e: f64 = a
                .iter()
                .enumerate()
                .map(|(j, v)| v * model.weights()[j * 2 + o])
                .sum();
            assert!((out[o] - e).abs() < 1e-10 * (1.0 + e.abs()));
            assert_eq!(out[o], batch[i * 2 + o]);
            abs_err += (out[o] - target(xi)[o]).abs();
        }
    }
    // And it approximates the function.
    assert!(
        abs_err / 400.0 < 0.05,
        "mean absolute error {}",
        abs_err / 400.0
    );
}

#[test]
fn predict_into_does_not_allocate() {
    let (x, y) = data(800, 7, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(40);
    cfg.lambda_grid = vec![1e-6];
    cfg.friction = FrictionFeatures {
        columns: vec![1],
        scales: vec![0.01, 0.1],
    };
    let (model, _) = fit(&train, None, &cfg).unwrap();
    let mut ws = model.workspace();
    let mut out = [0.0; 2];
    model.predict_into(&x[..3], &mut out, &mut ws).unwrap();
    let allocations = count_allocations(|| {
        for i in 0..500 {
            model
                .predict_into(&x[i * 3..i * 3 + 3], &mut out, &mut ws)
                .unwrap();
        }
    });
    assert_eq!(allocations, 0, "predict_into allocated");
}

/// Block size, thread count and Gram strategy change only the rounding.
#[test]
fn blocking_and_threads_do_not_change_the_fit() {
    let (x, y) = data(3000, 8, 0.02);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(60);
    cfg.lambda_grid = vec![1e-6];
    let (reference, _) = fit(&train, None, &cfg).unwrap();
    for (block, threads, strategy) in [
        (7, 1, GramStrategy::PerThread),
        (1000, 2, GramStrategy::PerThread),
        (333, 3, GramStrategy::PerThread),
        (512, 2, GramStrategy::SharedGemm),
        (5000, 2, GramStrategy::SharedGemm),
    ] {
        let mut c = cfg.clone();
        c.block_rows = block;
        c.threads = threads;
        c.gram_strategy = strategy;
        let (m, _) = fit(&train, None, &c).unwrap();
        assert_eq!(
            m.nodes(),
            reference.nodes(),
            "centres depend only on the seed"
        );
        let d = rel_diff(m.weights(), reference.weights());
        assert!(
            d < 1e-9,
            "block {block} threads {threads} {strategy:?}: rel diff {d}"
        );
    }
}

#[test]
fn centres_are_deterministic_and_seeded() {
    let (x, y) = data(2000, 9, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(25);
    cfg.lambda_grid = vec![1e-6];
    let (a, _) = fit(&train, None, &cfg).unwrap();
    let (b, _) = fit(&train, None, &cfg).unwrap();
    assert_eq!(a.nodes(), b.nodes());
    assert_eq!(a.weights(), b.weights());
    cfg.seed += 1;
    let (c, _) = fit(&train, None, &cfg).unwrap();
    assert_ne!(a.nodes().centres, c.nodes().centres);
    // Centres are data points (standardised): each lies on a training row.
    let s = a.standardiser();
    for cj in a.nodes().centres.chunks(3) {
        let found = x
            .chunks(3)
            .any(|r| (0..3).all(|k| ((r[k] - s.mean[k]) / s.std[k] - cj[k]).abs() < 1e-12));
        assert!(found);
    }
    // Widths are positive and finite.
    assert!(a.nodes().widths.iter().all(|w| w.is_finite() && *w > 0.0));
}

#[test]
fn width_rules_and_duplicate_points() {
    // Only 4 distinct input points but 12 nodes: duplicate centres, zero k-NN distances.
    let pts = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.5],
        [1.0, 1.0, -1.0],
    ];
    let mut x = Vec::new();
    let mut y = Vec::new();
    for i in 0..400 {
        let p = pts[i % 4];
        x.extend_from_slice(&p);
        let t = target(&p);
        y.extend_from_slice(&t);
    }
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    for rule in [
        WidthRule::Knn { k: 3, scale: 1.0 },
        WidthRule::GlobalMedian { scale: 2.0 },
        WidthRule::Fixed(0.7),
    ] {
        let mut cfg = small_config(12);
        cfg.widths = rule.clone();
        cfg.lambda_grid = vec![1e-6];
        let (m, _) = fit(&train, None, &cfg).unwrap();
        assert!(
            m.nodes().widths.iter().all(|w| w.is_finite() && *w > 0.0),
            "{rule:?}: {:?}",
            m.nodes().widths
        );
        if let WidthRule::Fixed(w) = rule {
            assert!(m.nodes().widths.iter().all(|&v| v == w));
        }
        let e = m.evaluate(&train, 1).unwrap();
        assert!(e.iter().all(|v| *v < 0.05), "{rule:?}: {e:?}");
    }
}

#[test]
fn constant_input_column_is_guarded() {
    let (mut x, y) = data(600, 10, 0.01);
    for r in x.chunks_mut(3) {
        r[2] = 4.25;
    }
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(20);
    cfg.lambda_grid = vec![1e-6];
    let (m, _) = fit(&train, None, &cfg).unwrap();
    assert_eq!(m.standardiser().std[2], 1.0);
    assert_eq!(m.standardiser().mean[2], 4.25);
    let mut out = [0.0; 2];
    m.predict_into(&[0.1, 0.2, 4.25], &mut out, &mut m.workspace())
        .unwrap();
    assert!(out.iter().all(|v| v.is_finite()));
}

/// docs/method.md section 7: a Coulomb step at zero velocity is smoothed by Gaussian nodes;
/// tanh(q'/v) features represent it.
#[test]
fn friction_features_capture_the_coulomb_step() {
    let rows = 4000;
    let mut x = Vec::with_capacity(rows * 2);
    let mut y = Vec::with_capacity(rows);
    for i in 0..rows {
        let t = i as f64 * 0.005;
        let q = (0.3 * t).sin();
        let qd = 0.9 * (1.1 * t).cos();
        x.extend_from_slice(&[q, qd]);
        y.push(0.5 * (qd / 0.01).tanh() + 0.2 * qd + 1.5 * q.sin());
    }
    let train = Dataset::new(&x, &y, 2, 1).unwrap();
    let mut cfg = small_config(40);
    cfg.lambda_grid = vec![1e-8];
    let (plain, _) = fit(&train, None, &cfg).unwrap();
    cfg.friction = FrictionFeatures {
        columns: vec![1],
        scales: vec![0.01, 0.05, 0.2],
    };
    let (with, _) = fit(&train, None, &cfg).unwrap();
    let e_plain = plain.evaluate(&train, 1).unwrap()[0];
    let e_with = with.evaluate(&train, 1).unwrap()[0];
    assert!(
        e_with < 0.3 * e_plain,
        "with friction features {e_with}, without {e_plain}"
    );
    assert!(e_with < 0.01, "{e_with}");
    assert_eq!(with.pattern_width(), 2 + 3 + 1 + 40);
}

#[test]
fn fit_with_nodes_reproduces_fit() {
    let (x, y) = data(1000, 12, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(30);
    cfg.lambda_grid = vec![1e-5];
    let (a, _) = fit(&train, None, &cfg).unwrap();
    let (b, _) = fit_with_nodes(&train, None, &cfg, a.nodes()).unwrap();
    assert_eq!(a.weights(), b.weights());
    // Zero nodes: a linear model with bias.
    let empty = NodeSet {
        dim: 3,
        centres: vec![],
        widths: vec![],
    };
    let (lin, _) = fit_with_nodes(&train, None, &cfg, &empty).unwrap();
    assert_eq!(lin.pattern_width(), 4);
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let (x, y) = data(100, 13, 0.01);
    // Shapes.
    assert!(matches!(
        Dataset::new(&x, &y, 0, 2),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        Dataset::new(&x, &y, 3, 0),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        Dataset::new(&x[..298], &y, 3, 2),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        Dataset::new(&x, &y[..198], 3, 2),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        Dataset::new(&[], &[], 3, 2),
        Err(BroadError::Empty { .. })
    ));
    // NaN names the row and column.
    let mut bad = x.clone();
    bad[3 * 57 + 2] = f64::NAN;
    match Dataset::new(&bad, &y, 3, 2) {
        Err(BroadError::NonFinite {
            row, column, what, ..
        }) => {
            assert_eq!((row, column, what), (57, 2, "inputs"));
        }
        other => panic!("{other:?}"),
    }
    let mut bady = y.clone();
    bady[2 * 9 + 1] = f64::INFINITY;
    let err = Dataset::new(&x, &bady, 3, 2).unwrap_err();
    assert!(err.to_string().contains("row 9"), "{err}");
    // Configuration.
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(10);
    cfg.cv_folds = 0;
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::NeedValidation(4))
    ));
    cfg.lambda_grid = vec![-1.0];
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.lambda_grid = vec![];
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.lambda_grid = vec![1e-6];
    cfg.friction = FrictionFeatures {
        columns: vec![3],
        scales: vec![0.1],
    };
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.friction = FrictionFeatures {
        columns: vec![1],
        scales: vec![0.0],
    };
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.friction = FrictionFeatures::none();
    cfg.block_rows = 0;
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.block_rows = 64;
    cfg.widths = WidthRule::Knn { k: 0, scale: 1.0 };
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.widths = WidthRule::Fixed(f64::NAN);
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::Config(_))
    ));
    cfg.widths = WidthRule::Fixed(1.0);
    // Validation set of other widths.
    let (xv, yv) = data(10, 14, 0.01);
    let val = Dataset::new(&xv[..20], &yv[..10], 2, 1).unwrap();
    assert!(matches!(
        fit(&train, Some(&val), &cfg),
        Err(BroadError::Dimension { .. })
    ));
    // Nodes of the wrong width.
    let nodes = NodeSet {
        dim: 2,
        centres: vec![0.0; 4],
        widths: vec![1.0, 1.0],
    };
    assert!(matches!(
        fit_with_nodes(&train, None, &cfg, &nodes),
        Err(BroadError::Dimension { .. })
    ));
    let nodes = NodeSet {
        dim: 3,
        centres: vec![0.0; 6],
        widths: vec![1.0, -1.0],
    };
    assert!(matches!(
        fit_with_nodes(&train, None, &cfg, &nodes),
        Err(BroadError::Config(_))
    ));
    // Prediction.
    let (m, _) = fit(&train, None, &cfg).unwrap();
    let mut ws = m.workspace();
    let mut out = [0.0; 2];
    assert!(matches!(
        m.predict_into(&[0.0; 2], &mut out, &mut ws),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        m.predict_into(&[0.0; 3], &mut [0.0; 3], &mut ws),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        m.predict_into(&[0.0, f64::NAN, 0.0], &mut out, &mut ws),
        Err(BroadError::NonFinite { column: 1, .. })
    ));
    // A fresh default workspace works (grown once).
    m.predict_into(&[0.0; 3], &mut out, &mut Default::default())
        .unwrap();
    assert!(matches!(
        m.predict_batch(&[0.0; 4], &mut [0.0; 2]),
        Err(BroadError::Dimension { .. })
    ));
    assert!(matches!(
        m.evaluate(&val, 1),
        Err(BroadError::Dimension { .. })
    ));
}

#[test]
fn singular_systems_report_not_positive_definite_or_survive() {
    // All rows identical: nothing moves, so there is nothing to learn (issue 34 item 10:
    // refused by name rather than fitted to a rank-one Gram with a validation error of 0).
    let x = vec![0.5; 300];
    let y = vec![1.0; 200];
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(5);
    cfg.lambda_grid = vec![1e-3];
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::NoMotion { .. })
    ));
}

#[test]
fn default_config_for_arm() {
    let c = BroadConfig::for_arm(7);
    assert_eq!(c.nodes, 1000);
    assert_eq!(c.friction.columns, (7..14).collect::<Vec<_>>());
    assert_eq!(c.friction.scales, vec![0.01, 0.05, 0.2]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Dataset construction never panics, whatever the lengths.
    #[test]
    fn dataset_new_never_panics(nx in 0usize..40, ny in 0usize..40, d in 0usize..5, n in 0usize..5) {
        let x = vec![0.25; nx];
        let y = vec![0.5; ny];
        let _ = Dataset::new(&x, &y, d, n);
    }

    /// Standardised training columns have mean 0 and standard deviation 1.
    #[test]
    fn standardisation_statistics(rows in 2usize..60, seed in 0u64..1000, scale in 0.001f64..1000.0, shift in -1e3f64..1e3) {
        let (mut x, y) = data(rows, seed, 0.0);
        for v in &mut x { *v = *v * scale + shift; }
        let train = Dataset::new(&x, &y[..rows * 2], 3, 2).unwrap();
        let s = admittance_learning::broad::Standardiser::from_data(&train);
        let mut z = vec![0.0; 3];
        let mut sum = [0.0; 3];
        let mut sq = [0.0; 3];
        for r in x.chunks(3) {
            s.apply(r, &mut z);
            for k in 0..3 { sum[k] += z[k]; sq[k] += z[k] * z[k]; }
        }
        for k in 0..3 {
            prop_assert!((sum[k] / rows as f64).abs() < 1e-9);
            prop_assert!((sq[k] / rows as f64 - 1.0).abs() < 1e-9);
        }
    }

    /// Prediction is finite and bounded for any finite input, far from the data too.
    #[test]
    fn prediction_is_finite(a in -1e6f64..1e6, b in -1e6f64..1e6, c in -1e3f64..1e3) {
        use std::sync::OnceLock;
        static MODEL: OnceLock<admittance_learning::broad::BroadModel> = OnceLock::new();
        let m = MODEL.get_or_init(|| {
            let (x, y) = data(500, 21, 0.01);
            let train = Dataset::new(&x, &y, 3, 2).unwrap();
            let mut cfg = small_config(20);
            cfg.lambda_grid = vec![1e-6];
            fit(&train, None, &cfg).unwrap().0
        });
        let mut out = [0.0; 2];
        m.predict_into(&[a, b, c], &mut out, &mut m.workspace()).unwrap();
        prop_assert!(out.iter().all(|v| v.is_finite()));
    }
}
