//! Fitting the flat RBF network on free-motion data: standardisation, centres, one
//! blocked Gram pass, a Cholesky solve per candidate lambda, the choice on validation data
//! (docs/method.md section 5).

use super::budget::{check_budget, FitSize};
use super::centres::{compute_widths, kmeanspp, rng_from_seed, subsample_standardised};
use super::config::BroadConfig;
use super::coverage::coverage_threshold;
use super::cv::{acc_std, accumulate_folds, check_folds, cross_validate};
use super::data::{Dataset, Standardiser};
use super::error::BroadError;
use super::features::{FeatureMap, NodeSet};
use super::gram::{accumulate_gram, prediction_sse, GramAcc};
use super::model::{
    check_finite_result, nrmse, par_for, target_std, train_nrmse, BroadModel, GrowthState,
};
use super::provenance::{CentreSettings, FitSettings, Provenance};
use super::solve::{factor, solve};
use faer::Mat;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Seconds spent in each phase of a fit.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhaseTimes {
    /// Standardisation statistics (and data checks).
    pub standardise_s: f64,
    /// Subsample, k-means++ seeding and widths.
    pub centres_s: f64,
    /// Features and Gram accumulation (one pass over the training data).
    pub gram_s: f64,
    /// Cholesky factorisations and solves for all lambdas.
    pub solve_s: f64,
    /// Validation predictions for all lambdas (one pass over the validation data).
    pub validation_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// Validation score of one candidate lambda.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LambdaScore {
    /// Relative lambda (from the grid).
    pub lambda_rel: f64,
    /// Absolute lambda `lambda_rel * N`.
    pub lambda: f64,
    /// False when `G + lambda D` was not numerically positive definite (candidate skipped).
    pub factorised: bool,
    /// Per-output validation NRMSE (empty without validation set or when not factorised).
    pub validation_nrmse: Vec<f64>,
    /// Mean of `validation_nrmse` over the outputs (the selection criterion).
    pub mean_nrmse: Option<f64>,
}

/// What [`fit`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// Training rows N.
    pub samples: usize,
    /// Stretches of the blocked cross-validation that chose lambda (0: none, a
    /// validation set or a single lambda).
    #[serde(default)]
    pub cv_folds: usize,
    /// Validation rows (0 without validation set).
    pub validation_samples: usize,
    /// Enhancement nodes L.
    pub nodes: usize,
    /// Pattern width P = d_in + F + 1 + L.
    pub pattern_width: usize,
    /// Chosen absolute lambda.
    pub lambda: f64,
    /// Chosen relative lambda.
    pub lambda_rel: f64,
    /// All candidates.
    pub lambda_scan: Vec<LambdaScore>,
    /// Per-output validation NRMSE at the chosen lambda (RMSE / std of the validation
    /// target; RMSE itself where that std is 0). With cross-validation, the pooled error
    /// of every stretch predicted by the fit on the others, over the std of all training
    /// targets. Empty with a single lambda and no validation set.
    pub validation_nrmse: Vec<f64>,
    /// Per-output validation RMSE at the chosen lambda, in the targets' unit (N m for
    /// torques): the expected error on motion the fit did not see. Empty when
    /// `validation_nrmse` is.
    #[serde(default)]
    pub validation_rmse: Vec<f64>,
    /// Per-output training NRMSE at the chosen lambda (from the Gram terms).
    pub train_nrmse: Vec<f64>,
    /// Outputs set to zero by `BroadConfig::zero_unhelpful_outputs` (on unseen rows they
    /// did not remove [`REQUIRED_GAIN`] of the error of predicting zero); their validation
    /// NRMSE and RMSE above are then those of zero.
    #[serde(default)]
    pub zeroed_outputs: Vec<usize>,
    /// Time per phase.
    pub times: PhaseTimes,
}

/// A grid of several lambdas needs a validation set or cross-validation folds (enough
/// rows for them).
fn check_choice(
    train: &Dataset<'_>,
    validation: Option<&Dataset<'_>>,
    config: &BroadConfig,
) -> Result<(), BroadError> {
    if validation.is_some() || config.lambda_grid.len() == 1 {
        return Ok(());
    }
    if config.cv_folds == 0 {
        return Err(BroadError::NeedValidation(config.lambda_grid.len()));
    }
    check_folds(train.n_samples(), config.cv_folds)
}

fn check_same_widths(train: &Dataset<'_>, other: &Dataset<'_>) -> Result<(), BroadError> {
    if other.d_in() != train.d_in() {
        return Err(BroadError::Dimension {
            what: "validation input width",
            expected: train.d_in(),
            got: other.d_in(),
        });
    }
    if other.d_out() != train.d_out() {
        return Err(BroadError::Dimension {
            what: "validation output width",
            expected: train.d_out(),
            got: other.d_out(),
        });
    }
    Ok(())
}

/// Fits the flat RBF network of docs/method.md section 5 on `train`:
/// standardisation with the training statistics, centres by k-means++ seeding on a random
/// subsample, widths by `config.widths`, one blocked pass accumulating `G = A^T A` and
/// `A^T Y`, then for every lambda of `config.lambda_grid` a Cholesky solve of
/// `(G + lambda D) W = A^T Y` (bias not regularised). With a validation set, every
/// candidate is scored by the mean over outputs of the validation NRMSE (one more blocked
/// pass, all candidates at once) and the best is kept; the Gram does not depend on lambda,
/// so the scan costs a few factorisations, not refits. Without a validation set the grid
/// must hold exactly one value.
pub fn fit(
    train: &Dataset<'_>,
    validation: Option<&Dataset<'_>>,
    config: &BroadConfig,
) -> Result<(BroadModel, FitReport), BroadError> {
    let t0 = Instant::now();
    config.validate(train.d_in())?;
    train.check_motion("training data")?;
    if let Some(v) = validation {
        check_same_widths(train, v)?;
    }
    check_choice(train, validation, config)?;
    let size = FitSize::fit(
        train.n_samples(),
        validation.map_or(0, |v| v.n_samples()),
        train.d_in(),
        train.d_out(),
        config,
    );
    check_budget(&size, &config.budget)?;
    let standardiser = Standardiser::from_data(train);
    let t_std = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let mut rng = rng_from_seed(config.seed);
    let (pts_t, m) =
        subsample_standardised(train, &standardiser, config.centre_subsample, &mut rng);
    let d = train.d_in();
    let centres = kmeanspp(&pts_t, m, d, &[], config.nodes, &mut rng);
    drop(pts_t);
    let widths = compute_widths(&centres, d, 0, &[], &config.widths);
    let nodes = NodeSet {
        dim: d,
        centres,
        widths,
    };
    let t_centres = t1.elapsed().as_secs_f64();
    let mut times = PhaseTimes {
        standardise_s: t_std,
        centres_s: t_centres,
        ..Default::default()
    };
    let centres = CentreSettings {
        centre_subsample: config.centre_subsample,
        seed: config.seed,
        widths: config.widths.clone(),
    };
    let out = fit_inner(
        train,
        validation,
        config,
        standardiser,
        nodes,
        Some(centres),
        &mut times,
    );
    times.total_s = t0.elapsed().as_secs_f64();
    out.map(|(m, mut r)| {
        r.times = times;
        (m, r)
    })
}

/// Like [`fit`] but with given enhancement nodes (centres in standardised units of the
/// training statistics, widths), e.g. to reproduce a fit exactly or to retrain on a grown
/// node set. `config.nodes`, `centre_subsample`, `seed` and `widths` are ignored.
pub fn fit_with_nodes(
    train: &Dataset<'_>,
    validation: Option<&Dataset<'_>>,
    config: &BroadConfig,
    nodes: &NodeSet,
) -> Result<(BroadModel, FitReport), BroadError> {
    let t0 = Instant::now();
    config.validate(train.d_in())?;
    nodes.validate(train.d_in())?;
    if let Some(v) = validation {
        check_same_widths(train, v)?;
    }
    check_choice(train, validation, config)?;
    let mut size = FitSize::fit(
        train.n_samples(),
        validation.map_or(0, |v| v.n_samples()),
        train.d_in(),
        train.d_out(),
        config,
    );
    size.nodes = nodes.len();
    check_budget(&size, &config.budget)?;
    let standardiser = Standardiser::from_data(train);
    let mut times = PhaseTimes {
        standardise_s: t0.elapsed().as_secs_f64(),
        ..Default::default()
    };
    let out = fit_inner(
        train,
        validation,
        config,
        standardiser,
        nodes.clone(),
        None,
        &mut times,
    );
    times.total_s = t0.elapsed().as_secs_f64();
    out.map(|(m, mut r)| {
        r.times = times;
        (m, r)
    })
}

/// The chosen candidate: its index in the grid, its weights on all training rows and
/// its validation NRMSE.
struct Choice {
    c: usize,
    w: Mat<f64>,
    validation_nrmse: Vec<f64>,
    validation_rmse: Vec<f64>,
}

/// RMSE from NRMSE and the targets' std (`nrmse` is the RMSE itself where the std is 0).
fn to_rmse(nrmse: &[f64], std: &[f64]) -> Vec<f64> {
    nrmse
        .iter()
        .zip(std)
        .map(|(&e, &sd)| if sd > 0.0 { e * sd } else { e })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn fit_inner(
    train: &Dataset<'_>,
    validation: Option<&Dataset<'_>>,
    config: &BroadConfig,
    standardiser: Standardiser,
    nodes: NodeSet,
    centres: Option<CentreSettings>,
    times: &mut PhaseTimes,
) -> Result<(BroadModel, FitReport), BroadError> {
    let threads = config.thread_count();
    let par = par_for(threads);
    let fm = FeatureMap::new(standardiser, config.friction.clone(), nodes);
    let p = fm.width();
    let d_out = train.d_out();
    let n = train.n_samples();
    let bias = fm.bias_index();
    let cv_folds = if validation.is_none() && config.lambda_grid.len() > 1 {
        config.cv_folds
    } else {
        0
    };
    let mut scan: Vec<LambdaScore> = config
        .lambda_grid
        .iter()
        .map(|&rel| LambdaScore {
            lambda_rel: rel,
            lambda: rel * n as f64,
            factorised: false,
            validation_nrmse: Vec::new(),
            mean_nrmse: None,
        })
        .collect();
    let (acc, choice) = if cv_folds > 0 {
        choose_by_cv(&fm, train, config, cv_folds, &mut scan, times)?
    } else {
        choose_on_holdout(&fm, train, validation, config, &mut scan, times)?
    };

    let t = Instant::now();
    let Choice {
        c,
        mut w,
        mut validation_nrmse,
        mut validation_rmse,
    } = choice;
    let zeroed_outputs = if config.zero_unhelpful_outputs || config.zero_all_outputs {
        let zero_rms = match validation {
            Some(v) if cv_folds == 0 => target_rms(v),
            _ if cv_folds > 0 => acc_rms(&acc, n),
            _ => Vec::new(),
        };
        let zeroed = if config.zero_all_outputs {
            (0..d_out).collect()
        } else {
            unhelpful_outputs(&validation_rmse, &zero_rms)
        };
        // The expected error of a zeroed output is that of predicting zero.
        let known = zero_rms.len().min(validation_rmse.len());
        for &o in zeroed.iter().filter(|&&o| o < known) {
            if validation_rmse[o] > 0.0 {
                validation_nrmse[o] *= zero_rms[o] / validation_rmse[o];
            }
            validation_rmse[o] = zero_rms[o];
        }
        zeroed
    } else {
        Vec::new()
    };
    for &o in &zeroed_outputs {
        w.as_mut().col_mut(o).fill(0.0);
    }
    let lambda = scan[c].lambda;
    let chol = factor(acc.g.as_ref(), lambda, bias, par).ok_or_else(|| {
        BroadError::NotPositiveDefinite {
            tried: vec![lambda],
        }
    })?;
    let state = GrowthState {
        gram: acc.g,
        aty: acc.aty,
        chol,
        n_samples: n,
        y_sum: acc.y_sum,
        y_sq: acc.y_sq,
    };
    let train_e = train_nrmse(&state, w.as_ref());
    times.solve_s += t.elapsed().as_secs_f64();
    check_finite_result(w.as_ref(), &validation_nrmse, &train_e)?;

    let fit_settings = FitSettings {
        nodes: fm.n_nodes(),
        centres,
        lambda_grid: config.lambda_grid.clone(),
        training_rows: n,
        validation_rows: validation.map_or(0, |v| v.n_samples()),
        zeroed_outputs: zeroed_outputs.clone(),
    };
    let coverage_threshold = coverage_threshold(&fm, train, threads);
    let mut model = BroadModel {
        fm,
        d_out,
        lambda,
        lambda_rel: scan[c].lambda_rel,
        w: Vec::new(),
        wt: Vec::new(),
        state: Some(state),
        coverage_threshold,
        provenance: Provenance {
            fit: Some(fit_settings),
            ..Provenance::default()
        },
    };
    model.set_weights(w.as_ref());
    let report = FitReport {
        samples: n,
        cv_folds,
        validation_samples: validation.map(|v| v.n_samples()).unwrap_or(0),
        nodes: model.n_nodes(),
        pattern_width: p,
        lambda,
        lambda_rel: scan[c].lambda_rel,
        lambda_scan: scan,
        validation_nrmse,
        validation_rmse,
        train_nrmse: train_e,
        zeroed_outputs,
        times: PhaseTimes::default(),
    };
    Ok((model, report))
}

/// The share of the error of predicting zero that an output must remove on unseen rows to
/// be kept: a smaller gain is within what another validation recording would change.
pub const REQUIRED_GAIN: f64 = 0.02;

/// Outputs whose error on unseen motion (`validation_rmse`) is not at least
/// [`REQUIRED_GAIN`] below `zero_rms`, the error of predicting zero on the same rows (empty
/// when either is unknown).
fn unhelpful_outputs(validation_rmse: &[f64], zero_rms: &[f64]) -> Vec<usize> {
    if validation_rmse.len() != zero_rms.len() {
        return Vec::new();
    }
    (0..zero_rms.len())
        .filter(|&o| validation_rmse[o] > (1.0 - REQUIRED_GAIN) * zero_rms[o])
        .collect()
}

/// RMS of each output of `data`: the error of predicting zero.
fn target_rms(data: &Dataset<'_>) -> Vec<f64> {
    let d = data.d_out();
    let mut sq = vec![0.0; d];
    for r in data.targets().chunks_exact(d) {
        for (s, v) in sq.iter_mut().zip(r) {
            *s += v * v;
        }
    }
    let rows = data.n_samples().max(1) as f64;
    sq.iter().map(|s| (s / rows).sqrt()).collect()
}

/// RMS of each training target from the Gram accumulator (the pooled error of predicting
/// zero on every stretch of the cross-validation).
fn acc_rms(acc: &GramAcc, n: usize) -> Vec<f64> {
    acc.y_sq
        .iter()
        .map(|q| (q / n.max(1) as f64).sqrt())
        .collect()
}

/// Records the per-output NRMSE `e` of candidate `c` in the scan; true when its mean
/// beats `best`.
fn record(scan: &mut [LambdaScore], c: usize, e: Vec<f64>, best: &mut f64) -> bool {
    let mean = e.iter().sum::<f64>() / e.len().max(1) as f64;
    scan[c].validation_nrmse = e;
    scan[c].mean_nrmse = Some(mean);
    let better = mean < *best;
    if better {
        *best = mean;
    }
    better
}

/// One Gram pass, a solve per candidate, the choice on the validation set (one pass
/// predicting with every candidate), or the single candidate without one.
fn choose_on_holdout(
    fm: &FeatureMap,
    train: &Dataset<'_>,
    validation: Option<&Dataset<'_>>,
    config: &BroadConfig,
    scan: &mut [LambdaScore],
    times: &mut PhaseTimes,
) -> Result<(GramAcc, Choice), BroadError> {
    let threads = config.thread_count();
    let par = par_for(threads);
    let (p, d_out) = (fm.width(), train.d_out());
    let t = Instant::now();
    let acc = accumulate_gram(fm, train, config.block_rows, threads, config.gram_strategy);
    times.gram_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut solutions: Vec<(usize, Mat<f64>)> = Vec::new();
    for (c, score) in scan.iter_mut().enumerate() {
        if let Some(l) = factor(acc.g.as_ref(), score.lambda, fm.bias_index(), par) {
            solutions.push((c, solve(l.as_ref(), acc.aty.as_ref(), par)));
            score.factorised = true;
        }
    }
    if solutions.is_empty() {
        return Err(BroadError::NotPositiveDefinite {
            tried: scan.iter().map(|s| s.lambda).collect(),
        });
    }
    times.solve_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut chosen = 0usize; // index into `solutions`
    let mut std = Vec::new();
    if let Some(val) = validation {
        let mut w_all = Mat::<f64>::zeros(p, solutions.len() * d_out);
        for (i, (_, w)) in solutions.iter().enumerate() {
            w_all.as_mut().subcols_mut(i * d_out, d_out).copy_from(w);
        }
        let sse = prediction_sse(
            fm,
            val,
            w_all.as_ref(),
            config.block_rows,
            threads,
            config.gram_strategy,
        );
        std = target_std(val);
        let mut best = f64::INFINITY;
        for (i, (c, _)) in solutions.iter().enumerate() {
            let e = nrmse(&sse[i * d_out..(i + 1) * d_out], val.n_samples(), &std);
            if record(scan, *c, e, &mut best) {
                chosen = i;
            }
        }
    }
    times.validation_s = t.elapsed().as_secs_f64();
    let (c, w) = solutions.swap_remove(chosen);
    let validation_nrmse = scan[c].validation_nrmse.clone();
    Ok((
        acc,
        Choice {
            c,
            w,
            validation_rmse: to_rmse(&validation_nrmse, &std),
            validation_nrmse,
        },
    ))
}

/// Blocked cross-validation (`cv.rs`): per-stretch Gram passes, every candidate scored
/// on every stretch by the fit on the others, then one solve on all rows at the best.
fn choose_by_cv(
    fm: &FeatureMap,
    train: &Dataset<'_>,
    config: &BroadConfig,
    folds: usize,
    scan: &mut [LambdaScore],
    times: &mut PhaseTimes,
) -> Result<(GramAcc, Choice), BroadError> {
    let threads = config.thread_count();
    let par = par_for(threads);
    let t = Instant::now();
    let fg = accumulate_folds(
        fm,
        train,
        folds,
        config.block_rows,
        threads,
        config.gram_strategy,
    );
    times.gram_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let scores = cross_validate(&fg, &config.lambda_grid, fm.bias_index(), par);
    let mut best = f64::INFINITY;
    let mut chosen = None;
    for (c, score) in scores.into_iter().enumerate() {
        let Some(e) = score else { continue };
        scan[c].factorised = true;
        if record(scan, c, e, &mut best) || chosen.is_none() {
            chosen = Some(c);
        }
    }
    times.validation_s = t.elapsed().as_secs_f64();
    let Some(c) = chosen else {
        return Err(BroadError::NotPositiveDefinite {
            tried: scan.iter().map(|s| s.lambda).collect(),
        });
    };

    let t = Instant::now();
    let acc = fg.total;
    let lambda = scan[c].lambda;
    let l = factor(acc.g.as_ref(), lambda, fm.bias_index(), par).ok_or_else(|| {
        BroadError::NotPositiveDefinite {
            tried: vec![lambda],
        }
    })?;
    let w = solve(l.as_ref(), acc.aty.as_ref(), par);
    times.solve_s = t.elapsed().as_secs_f64();
    let validation_nrmse = scan[c].validation_nrmse.clone();
    let std = acc_std(&acc, train.n_samples());
    Ok((
        acc,
        Choice {
            c,
            w,
            validation_rmse: to_rmse(&validation_nrmse, &std),
            validation_nrmse,
        },
    ))
}
