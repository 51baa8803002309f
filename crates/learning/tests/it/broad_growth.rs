//! Incremental growth (docs/method.md section 5, eq. 14-16): the exact ridge route (Cholesky
//! extension) and the paper's Greville pseudo-inverse form both equal a full retrain.

use crate::broad_common;
use admittance_learning::broad::{
    fit, fit_with_nodes, greville_add_columns, pseudo_inverse, BroadError, Dataset, GrowthSpec,
    NodeSet,
};
use broad_common::{data, rel_diff, small_config};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn ridge_growth_equals_full_retrain_explicit_nodes() {
    let (x, y) = data(2500, 31, 0.02);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(40);
    cfg.lambda_grid = vec![1e-6];
    cfg.threads = 2;
    let (mut model, _) = fit(&train, None, &cfg).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let extra = NodeSet {
        dim: 3,
        centres: (0..15 * 3).map(|_| rng.random_range(-1.7..1.7)).collect(),
        widths: (0..15).map(|_| rng.random_range(0.5..1.5)).collect(),
    };
    let report = model
        .grow(&train, &GrowthSpec::Nodes(extra.clone()), &cfg)
        .unwrap();
    assert_eq!(report.nodes_added, 15);
    assert_eq!(report.nodes, 55);
    assert_eq!(model.n_nodes(), 55);
    let mut all = fit(&train, None, &cfg).unwrap().0.nodes().clone();
    all.extend(&extra);
    assert_eq!(model.nodes(), &all);
    let (retrained, _) = fit_with_nodes(&train, None, &cfg, &all).unwrap();
    let d = rel_diff(model.weights(), retrained.weights());
    assert!(d < 1e-8, "growth vs retrain rel diff {d}");
    // Predictions agree too, and the growth helped (or at least did not hurt) the fit.
    let e_grown = model.evaluate(&train, 1).unwrap();
    let e_retrained = retrained.evaluate(&train, 1).unwrap();
    assert!(rel_diff(&e_grown, &e_retrained) < 1e-8);
    for (a, b) in report.train_nrmse.iter().zip(&e_grown) {
        assert!((a - b).abs() < 1e-6 * b.max(1e-3), "{a} vs {b}");
    }
    // The coverage threshold, taken from the growth's own pass over the data, is the
    // retrain's (which makes a pass of its own).
    let (grown_m0, retrained_m0) = (
        model.coverage_threshold().expect("grown threshold"),
        retrained.coverage_threshold().expect("retrained threshold"),
    );
    assert!(
        (grown_m0 - retrained_m0).abs() <= 1e-12 * retrained_m0,
        "coverage threshold {grown_m0} after growth, {retrained_m0} retrained"
    );
}

#[test]
fn repeated_kmeanspp_growth_equals_full_retrain() {
    let (x, y) = data(3000, 32, 0.02);
    let (xv, yv) = data(800, 33, 0.02);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let val = Dataset::new(&xv, &yv, 3, 2).unwrap();
    let mut cfg = small_config(20);
    cfg.lambda_grid = vec![1e-8, 1e-6, 1e-4];
    let (mut model, report) = fit(&train, Some(&val), &cfg).unwrap();
    let before = model.evaluate(&val, 1).unwrap();
    model
        .grow(
            &train,
            &GrowthSpec::KMeansPlusPlus { count: 10, seed: 1 },
            &cfg,
        )
        .unwrap();
    model
        .grow(
            &train,
            &GrowthSpec::KMeansPlusPlus { count: 7, seed: 2 },
            &cfg,
        )
        .unwrap();
    assert_eq!(model.n_nodes(), 37);
    // Old nodes unchanged, new widths positive.
    assert!(model
        .nodes()
        .widths
        .iter()
        .all(|w| w.is_finite() && *w > 0.0));
    let mut fixed = cfg.clone();
    fixed.lambda_grid = vec![report.lambda_rel];
    let (retrained, _) = fit_with_nodes(&train, None, &fixed, model.nodes()).unwrap();
    let d = rel_diff(model.weights(), retrained.weights());
    assert!(d < 1e-8, "growth vs retrain rel diff {d}");
    let after = model.evaluate(&val, 1).unwrap();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(
        mean(&after) < mean(&before),
        "growth should help an under-sized network: {before:?} -> {after:?}"
    );
    // Zero nodes: nothing changes.
    let w = model.weights().to_vec();
    let r = model
        .grow(
            &train,
            &GrowthSpec::KMeansPlusPlus { count: 0, seed: 3 },
            &cfg,
        )
        .unwrap();
    assert_eq!(r.nodes_added, 0);
    assert_eq!(model.weights(), &w[..]);
}

#[test]
fn set_lambda_matches_a_refit() {
    let (x, y) = data(1500, 34, 0.05);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(30);
    cfg.lambda_grid = vec![1e-6];
    let (mut model, _) = fit(&train, None, &cfg).unwrap();
    model.set_lambda(1e-3).unwrap();
    cfg.lambda_grid = vec![1e-3];
    let (refit, _) = fit(&train, None, &cfg).unwrap();
    assert!(rel_diff(model.weights(), refit.weights()) < 1e-10);
    assert_eq!(model.lambda(), refit.lambda());
    assert!(matches!(model.set_lambda(0.0), Err(BroadError::Config(_))));
}

#[test]
fn growth_refuses_other_data_and_missing_state() {
    let (x, y) = data(1000, 35, 0.02);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(10);
    cfg.lambda_grid = vec![1e-6];
    let (mut model, _) = fit(&train, None, &cfg).unwrap();
    let spec = GrowthSpec::KMeansPlusPlus { count: 3, seed: 0 };
    // Other rows, same count.
    let (x2, y2) = data(1000, 36, 0.02);
    let other = Dataset::new(&x2, &y2, 3, 2).unwrap();
    assert!(matches!(
        model.grow(&other, &spec, &cfg),
        Err(BroadError::GrowthDataMismatch(_))
    ));
    // Same inputs, other targets.
    let y3: Vec<f64> = y.iter().map(|v| v + 0.1).collect();
    let other = Dataset::new(&x, &y3, 3, 2).unwrap();
    assert!(matches!(
        model.grow(&other, &spec, &cfg),
        Err(BroadError::GrowthDataMismatch(_))
    ));
    // Fewer rows.
    let fewer = Dataset::new(&x[..1500], &y[..1000], 3, 2).unwrap();
    assert!(matches!(
        model.grow(&fewer, &spec, &cfg),
        Err(BroadError::GrowthDataMismatch(_))
    ));
    // Wrong widths.
    let narrow = Dataset::new(&x[..2000], &y[..1000], 2, 1).unwrap();
    assert!(matches!(
        model.grow(&narrow, &spec, &cfg),
        Err(BroadError::Dimension { .. })
    ));
    // Explicit nodes of another dimension.
    let bad = NodeSet {
        dim: 2,
        centres: vec![0.0; 2],
        widths: vec![1.0],
    };
    assert!(matches!(
        model.grow(&train, &GrowthSpec::Nodes(bad), &cfg),
        Err(BroadError::Dimension { .. })
    ));
    // Nothing changed by the failed attempts.
    assert_eq!(model.n_nodes(), 10);
    model.strip_growth_state();
    assert!(!model.has_growth_state());
    assert!(matches!(
        model.grow(&train, &spec, &cfg),
        Err(BroadError::NoGrowthState)
    ));
    assert!(matches!(
        model.set_lambda(1e-3),
        Err(BroadError::NoGrowthState)
    ));
}

fn random_mat(rows: usize, cols: usize, rng: &mut ChaCha8Rng) -> Mat<f64> {
    Mat::from_fn(rows, cols, |_, _| rng.random_range(-1.0..1.0))
}

fn mat_rel_diff(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
    let mut num = 0.0;
    let mut den = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            num += (a[(i, j)] - b[(i, j)]).powi(2);
            den += b[(i, j)].powi(2);
        }
    }
    (num / den).sqrt()
}

fn pinv_times(a_pinv: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Mat<f64> {
    let mut w = Mat::zeros(a_pinv.nrows(), y.ncols());
    matmul(w.as_mut(), Accum::Replace, a_pinv, y, 1.0, Par::Seq);
    w
}

/// Greville form (c != 0 branch) on a small full-rank problem equals the pseudo-inverse
/// retrain (and the least-squares solution) on the grown matrix.
#[test]
fn greville_equals_pinv_retrain_full_rank() {
    let mut rng = ChaCha8Rng::seed_from_u64(40);
    let (n, p, k, dout) = (120, 8, 5, 3);
    let a = random_mat(n, p, &mut rng);
    let new_cols = random_mat(n, k, &mut rng);
    let y = random_mat(n, dout, &mut rng);
    let a_pinv = pseudo_inverse(a.as_ref(), 1e-12).unwrap();
    let w = pinv_times(a_pinv.as_ref(), y.as_ref());
    let grown = greville_add_columns(
        a.as_ref(),
        a_pinv.as_ref(),
        w.as_ref(),
        y.as_ref(),
        new_cols.as_ref(),
        1e-10,
    )
    .unwrap();
    assert_eq!((grown.a.nrows(), grown.a.ncols()), (n, p + k));
    let mut ap = Mat::<f64>::zeros(n, p + k);
    ap.as_mut().submatrix_mut(0, 0, n, p).copy_from(&a);
    ap.as_mut().submatrix_mut(0, p, n, k).copy_from(&new_cols);
    assert_eq!(mat_rel_diff(grown.a.as_ref(), ap.as_ref()), 0.0);
    let ap_pinv = pseudo_inverse(ap.as_ref(), 1e-12).unwrap();
    let d_pinv = mat_rel_diff(grown.a_pinv.as_ref(), ap_pinv.as_ref());
    assert!(d_pinv < 1e-10, "A^+ rel diff {d_pinv}");
    let w_ref = pinv_times(ap_pinv.as_ref(), y.as_ref());
    let d_w = mat_rel_diff(grown.w.as_ref(), w_ref.as_ref());
    assert!(d_w < 1e-10, "W rel diff {d_w}");
    // Least squares by the normal equations (full column rank): A^T A W = A^T Y.
    let mut ata = Mat::<f64>::zeros(p + k, p + k);
    matmul(
        ata.as_mut(),
        Accum::Replace,
        ap.transpose(),
        ap.as_ref(),
        1.0,
        Par::Seq,
    );
    let mut aty = Mat::<f64>::zeros(p + k, dout);
    matmul(
        aty.as_mut(),
        Accum::Replace,
        ap.transpose(),
        y.as_ref(),
        1.0,
        Par::Seq,
    );
    let mut lhs = Mat::<f64>::zeros(p + k, dout);
    matmul(
        lhs.as_mut(),
        Accum::Replace,
        ata.as_ref(),
        grown.w.as_ref(),
        1.0,
        Par::Seq,
    );
    assert!(mat_rel_diff(lhs.as_ref(), aty.as_ref()) < 1e-10);
}

/// The c == 0 branch: a new column in the span of A (docs/method.md section 5's corrected
/// `b^T = (1 + d^T d)^-1 d^T A^+`) still gives the pseudo-inverse of the grown matrix.
#[test]
fn greville_dependent_column_branch() {
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let (n, p, dout) = (60, 6, 2);
    let a = random_mat(n, p, &mut rng);
    let y = random_mat(n, dout, &mut rng);
    let coef = random_mat(p, 1, &mut rng);
    let mut dep = Mat::<f64>::zeros(n, 1);
    matmul(
        dep.as_mut(),
        Accum::Replace,
        a.as_ref(),
        coef.as_ref(),
        1.0,
        Par::Seq,
    );
    let indep = random_mat(n, 1, &mut rng);
    let mut new_cols = Mat::<f64>::zeros(n, 2);
    new_cols.as_mut().submatrix_mut(0, 0, n, 1).copy_from(&dep);
    new_cols
        .as_mut()
        .submatrix_mut(0, 1, n, 1)
        .copy_from(&indep);
    let a_pinv = pseudo_inverse(a.as_ref(), 1e-12).unwrap();
    let w = pinv_times(a_pinv.as_ref(), y.as_ref());
    let grown = greville_add_columns(
        a.as_ref(),
        a_pinv.as_ref(),
        w.as_ref(),
        y.as_ref(),
        new_cols.as_ref(),
        1e-9,
    )
    .unwrap();
    let ap_pinv = pseudo_inverse(grown.a.as_ref(), 1e-10).unwrap();
    let d_pinv = mat_rel_diff(grown.a_pinv.as_ref(), ap_pinv.as_ref());
    assert!(d_pinv < 1e-8, "A^+ rel diff {d_pinv}");
    let w_ref = pinv_times(ap_pinv.as_ref(), y.as_ref());
    assert!(mat_rel_diff(grown.w.as_ref(), w_ref.as_ref()) < 1e-8);
}

/// Greville on the network's own pattern matrix (small, unregularised): adding Gaussian
/// node columns equals the pseudo-inverse fit of the grown pattern matrix.
#[test]
fn greville_on_network_pattern_columns() {
    let (x, y) = data(300, 42, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(12);
    cfg.lambda_grid = vec![1e-6];
    let (model, _) = fit(&train, None, &cfg).unwrap();
    let mut grown = model.clone();
    grown
        .grow(
            &train,
            &GrowthSpec::KMeansPlusPlus { count: 4, seed: 9 },
            &cfg,
        )
        .unwrap();
    let (n, p, pg) = (300, model.pattern_width(), grown.pattern_width());
    let mut full = Mat::<f64>::zeros(n, pg);
    let mut row = vec![0.0; pg];
    for i in 0..n {
        grown.pattern_into(train.input_row(i), &mut row).unwrap();
        for j in 0..pg {
            full[(i, j)] = row[j];
        }
    }
    let ym = MatRef::from_row_major_slice(&y, n, 2);
    let a = full.as_ref().subcols(0, p);
    let a_pinv = pseudo_inverse(a, 1e-12).unwrap();
    let w = pinv_times(a_pinv.as_ref(), ym);
    let g = greville_add_columns(
        a,
        a_pinv.as_ref(),
        w.as_ref(),
        ym,
        full.as_ref().subcols(p, pg - p),
        1e-10,
    )
    .unwrap();
    let w_ref = pinv_times(pseudo_inverse(full.as_ref(), 1e-12).unwrap().as_ref(), ym);
    let d = mat_rel_diff(g.w.as_ref(), w_ref.as_ref());
    assert!(d < 1e-6, "W rel diff {d}");
}

#[test]
fn greville_rejects_bad_shapes() {
    let a = Mat::<f64>::zeros(5, 2);
    let pinv = Mat::<f64>::zeros(2, 5);
    let w = Mat::<f64>::zeros(2, 1);
    let y = Mat::<f64>::zeros(5, 1);
    let cols = Mat::<f64>::zeros(4, 1);
    assert!(matches!(
        greville_add_columns(
            a.as_ref(),
            pinv.as_ref(),
            w.as_ref(),
            y.as_ref(),
            cols.as_ref(),
            1e-10
        ),
        Err(BroadError::Greville(_))
    ));
    let bad_pinv = Mat::<f64>::zeros(5, 2);
    let cols = Mat::<f64>::zeros(5, 1);
    assert!(greville_add_columns(
        a.as_ref(),
        bad_pinv.as_ref(),
        w.as_ref(),
        y.as_ref(),
        cols.as_ref(),
        1e-10
    )
    .is_err());
    assert!(greville_add_columns(
        a.as_ref(),
        pinv.as_ref(),
        w.as_ref(),
        y.as_ref(),
        cols.as_ref(),
        f64::NAN
    )
    .is_err());
    let mut nan = Mat::<f64>::zeros(3, 3);
    nan[(1, 1)] = f64::NAN;
    assert!(pseudo_inverse(nan.as_ref(), 1e-12).is_err());
    let mut nan_cols = Mat::<f64>::zeros(5, 1);
    nan_cols[(4, 0)] = f64::INFINITY;
    let err = greville_add_columns(
        a.as_ref(),
        pinv.as_ref(),
        w.as_ref(),
        y.as_ref(),
        nan_cols.as_ref(),
        1e-10,
    )
    .unwrap_err();
    assert!(err.to_string().contains("new columns"), "{err}");
}
