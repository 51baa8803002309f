//! Honest validation of the ridge parameter (issue #22): without a validation set the
//! fit chooses lambda by blocked cross-validation over contiguous stretches, which a
//! recording whose tail repeats its training motion cannot fool; the network is then
//! fitted on all rows at the chosen lambda.

use crate::broad_common;
use admittance_learning::broad::{fit, BroadConfig, BroadError, Dataset};
use broad_common::{data, rel_diff, small_config};

fn cv_config() -> BroadConfig {
    BroadConfig {
        lambda_grid: vec![1e-9, 1e-7, 1e-5, 1e-3, 1e-1],
        ..small_config(150)
    }
}

/// 800 noisy rows, then a tail of 200 rows that repeats rows 100..300 exactly (the same
/// motion and the same noise, as a repeated excitation period would).
fn repeating_tail() -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut y) = data(800, 5, 0.6);
    let (xr, yr) = (x[300..900].to_vec(), y[200..600].to_vec());
    x.extend_from_slice(&xr);
    y.extend_from_slice(&yr);
    (x, y)
}

#[test]
fn cross_validation_is_not_fooled_by_a_repeated_tail() {
    let (x, y) = repeating_tail();
    let config = cv_config();
    // The tail split: train on the first 800 rows, choose on the repeated tail.
    let head = Dataset::new(&x[..2400], &y[..1600], 3, 2).unwrap();
    let tail = Dataset::new(&x[2400..], &y[1600..], 3, 2).unwrap();
    let (_, by_tail) = fit(&head, Some(&tail), &config).unwrap();
    // Blocked cross-validation over all rows.
    let all = Dataset::new(&x, &y, 3, 2).unwrap();
    let (_, by_cv) = fit(&all, None, &config).unwrap();
    assert_eq!(by_cv.cv_folds, 5);
    assert!(
        by_cv.lambda_rel > by_tail.lambda_rel,
        "cross-validation chose {:e}, the tail {:e}",
        by_cv.lambda_rel,
        by_tail.lambda_rel
    );
    // The tail's error flatters the fit; the cross-validated one does not.
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(
        mean(&by_cv.validation_nrmse) > mean(&by_tail.validation_nrmse),
        "{:?} vs {:?}",
        by_cv.validation_nrmse,
        by_tail.validation_nrmse
    );
    // On fresh rows of the same function the cross-validated choice does better.
    let (xf, yf) = data(2000, 99, 0.0);
    let fresh = Dataset::new(&xf, &yf, 3, 2).unwrap();
    let (tail_net, _) = fit(&head, Some(&tail), &config).unwrap();
    let (cv_net, _) = fit(&all, None, &config).unwrap();
    let (e_tail, e_cv) = (
        mean(&tail_net.evaluate(&fresh, 1).unwrap()),
        mean(&cv_net.evaluate(&fresh, 1).unwrap()),
    );
    assert!(e_cv < e_tail, "fresh rows: cv {e_cv}, tail {e_tail}");
}

#[test]
fn the_final_network_is_the_fit_on_all_rows_at_the_chosen_lambda() {
    let (x, y) = data(900, 8, 0.2);
    let all = Dataset::new(&x, &y, 3, 2).unwrap();
    let config = cv_config();
    let (net, report) = fit(&all, None, &config).unwrap();
    assert_eq!(report.samples, 900);
    assert_eq!(report.validation_samples, 0);
    assert_eq!(report.validation_nrmse.len(), 2);
    assert_eq!(report.validation_rmse.len(), 2);
    let scored = report.lambda_scan.iter().filter(|s| s.mean_nrmse.is_some());
    assert_eq!(scored.count(), config.lambda_grid.len());
    let single = BroadConfig {
        lambda_grid: vec![report.lambda_rel],
        ..config.clone()
    };
    let (again, r2) = fit(&all, None, &single).unwrap();
    assert_eq!(r2.cv_folds, 0);
    assert!(r2.validation_nrmse.is_empty());
    assert!(rel_diff(net.weights(), again.weights()) < 1e-8);
    // The cross-validated error is above the training error.
    for (v, t) in report.validation_nrmse.iter().zip(&report.train_nrmse) {
        assert!(v > t, "{v} <= {t}");
    }
}

#[test]
fn folds_are_configurable_and_checked() {
    let (x, y) = data(400, 9, 0.2);
    let all = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut config = BroadConfig {
        cv_folds: 3,
        ..small_config(20)
    };
    assert_eq!(fit(&all, None, &config).unwrap().1.cv_folds, 3);
    config.cv_folds = 1;
    assert!(matches!(
        fit(&all, None, &config),
        Err(BroadError::Config(_))
    ));
    config.cv_folds = 0;
    assert!(matches!(
        fit(&all, None, &config),
        Err(BroadError::NeedValidation(4))
    ));
    config.cv_folds = 300;
    assert!(matches!(
        fit(&all, None, &config),
        Err(BroadError::Config(_))
    ));
}

/// Output 0 learnable, output 1 noise that no input explains (a residual where the nominal
/// model already has everything): the fit with `zero_unhelpful_outputs` keeps 0 and sets 1
/// to zero, on a validation set and by cross-validation alike; without it, both are kept.
#[test]
fn an_output_that_does_not_beat_zero_on_unseen_rows_is_set_to_zero() {
    let noise_on_output_1 = |rows: usize, seed: u64| {
        let (x, mut y) = data(rows, seed, 0.0);
        let (_, noise) = data(rows, seed + 100, 1.0);
        let (_, clean) = data(rows, seed + 100, 0.0);
        for r in 0..rows {
            y[2 * r + 1] = noise[2 * r + 1] - clean[2 * r + 1];
        }
        (x, y)
    };
    let (x, y) = noise_on_output_1(1000, 5);
    let (xv, yv) = noise_on_output_1(400, 6);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let val = Dataset::new(&xv, &yv, 3, 2).unwrap();
    let gated = BroadConfig {
        zero_unhelpful_outputs: true,
        ..cv_config()
    };
    for validation in [Some(&val), None] {
        let (net, report) = fit(&train, validation, &gated).unwrap();
        assert_eq!(report.zeroed_outputs, vec![1], "{report:?}");
        let mut out = vec![0.0; 2 * 400];
        net.predict_batch(&xv, &mut out).unwrap();
        assert!(out.iter().skip(1).step_by(2).all(|&v| v == 0.0));
        assert!(out.iter().step_by(2).any(|&v| v.abs() > 0.1));
        // The expected error of the zeroed output is that of predicting zero.
        assert!(report.validation_nrmse[0] < 0.5, "{report:?}");
        let (_, plain) = fit(&train, validation, &cv_config()).unwrap();
        assert!(plain.zeroed_outputs.is_empty());
        assert!(report.validation_rmse[1] <= plain.validation_rmse[1] * 1.5);
    }
}

/// Without a recording of other motion (`zero_all_outputs`, set by the callers when a
/// residual has only cross-validation over its own recording): every output is zero, the
/// learnable one too, and the expected error is that of predicting zero.
#[test]
fn zero_all_outputs_leaves_the_nominal_model_alone() {
    let (x, y) = data(1000, 5, 0.0);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let config = BroadConfig {
        zero_unhelpful_outputs: true,
        zero_all_outputs: true,
        ..cv_config()
    };
    let (net, report) = fit(&train, None, &config).unwrap();
    assert_eq!(report.zeroed_outputs, vec![0, 1], "{report:?}");
    let mut out = vec![0.0; 2 * 1000];
    net.predict_batch(&x, &mut out).unwrap();
    assert!(out.iter().all(|&v| v == 0.0));
    let (_, plain) = fit(&train, None, &cv_config()).unwrap();
    assert!(plain.validation_nrmse[0] < 0.5, "{plain:?}");
    assert!(report.validation_nrmse[0] > 0.9, "{report:?}");
    assert_eq!(
        net.provenance().fit.as_ref().unwrap().zeroed_outputs,
        vec![0, 1]
    );
}
