//! The trained flat RBF network: fit with lambda selection, incremental growth,
//! allocation-free prediction (METHOD.md section 5).

use super::budget::{check_budget, FitSize};
use super::centres::{compute_widths, kmeanspp, rng_from_seed, subsample_standardised};
use super::config::{BroadConfig, FrictionFeatures, GramStrategy};
use super::data::{check_finite, Dataset, Standardiser};
use super::error::BroadError;
use super::features::{FeatureMap, NodeSet};
use super::gram::{accumulate_gram, accumulate_new_rows, prediction_sse};
use super::kernels;
use super::provenance::{CentreSettings, FitSettings, GrowthRecord, Provenance};
use super::solve::{extend_factor, factor, solve, sse_from_gram};
use faer::{Mat, MatRef, Par};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What the model keeps to grow without retraining (METHOD.md section 5, "incremental
/// growth"): the Gram matrix `G = A^T A` (lower triangle), `A^T Y`, the Cholesky factor of
/// `G + lambda D` at the chosen lambda, and fingerprints of the training data.
#[derive(Clone, Debug)]
pub(crate) struct GrowthState {
    pub(crate) gram: Mat<f64>,
    pub(crate) aty: Mat<f64>,
    pub(crate) chol: Mat<f64>,
    pub(crate) n_samples: usize,
    pub(crate) y_sum: Vec<f64>,
    pub(crate) y_sq: Vec<f64>,
}

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
    /// target; RMSE itself where that std is 0). Empty without validation set.
    pub validation_nrmse: Vec<f64>,
    /// Per-output training NRMSE at the chosen lambda (from the Gram terms).
    pub train_nrmse: Vec<f64>,
    /// Time per phase.
    pub times: PhaseTimes,
}

/// What [`BroadModel::grow`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrowthReport {
    /// Nodes added k.
    pub nodes_added: usize,
    /// Nodes after growth.
    pub nodes: usize,
    /// Seconds choosing the new centres and widths.
    pub centres_s: f64,
    /// Seconds for the cross terms (one pass over the data).
    pub cross_terms_s: f64,
    /// Seconds for the Cholesky extension and the new solve.
    pub solve_s: f64,
    /// Everything.
    pub total_s: f64,
    /// Per-output training NRMSE after growth (from the Gram terms).
    pub train_nrmse: Vec<f64>,
}

/// Which nodes [`BroadModel::grow`] adds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum GrowthSpec {
    /// These nodes (centres in standardised units).
    Nodes(NodeSet),
    /// `count` nodes by continuing the k-means++ seeding with the existing centres as
    /// already chosen: new centres land where the data is far from every current centre,
    /// the region METHOD.md section 4 grows into. Drawn from a fresh subsample of
    /// `config.centre_subsample` rows with a ChaCha8 generator seeded by `seed`; widths by
    /// `config.widths` with all centres as neighbours (old widths unchanged).
    KMeansPlusPlus {
        /// Number of nodes k.
        count: usize,
        /// Seed.
        seed: u64,
    },
}

/// Scratch for [`BroadModel::predict_into`]: holds the pattern row so that prediction
/// allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    pattern: Vec<f64>,
}

impl Workspace {
    /// An empty workspace (grown on first use; prefer [`BroadModel::workspace`]).
    pub fn new() -> Self {
        Self::default()
    }
}

/// A trained flat ("broad") RBF network, `f_hat(x) = W^T a(x)` with the pattern row
/// `a(x) = [X_std | friction features | 1 | xi(X)]` (METHOD.md section 5 and section 7).
#[derive(Clone, Debug)]
pub struct BroadModel {
    pub(crate) fm: FeatureMap,
    pub(crate) d_out: usize,
    pub(crate) lambda: f64,
    pub(crate) lambda_rel: f64,
    /// W, P x d_out, row-major.
    pub(crate) w: Vec<f64>,
    /// W^T, d_out x P, row-major (prediction layout).
    pub(crate) wt: Vec<f64>,
    pub(crate) state: Option<GrowthState>,
    /// What the model knows about how it was made (`provenance.rs`).
    pub(crate) provenance: Provenance,
}

fn par_for(threads: usize) -> Par {
    if threads > 1 {
        Par::rayon(threads)
    } else {
        Par::Seq
    }
}

fn target_std(data: &Dataset<'_>) -> Vec<f64> {
    let n = data.d_out();
    let rows = data.n_samples() as f64;
    let mut mean = vec![0.0; n];
    for r in data.targets().chunks_exact(n) {
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v;
        }
    }
    mean.iter_mut().for_each(|m| *m /= rows);
    let mut var = vec![0.0; n];
    for r in data.targets().chunks_exact(n) {
        for ((s, v), m) in var.iter_mut().zip(r).zip(&mean) {
            *s += (v - m) * (v - m);
        }
    }
    var.iter().map(|v| (v / rows).sqrt()).collect()
}

fn nrmse(sse: &[f64], rows: usize, std: &[f64]) -> Vec<f64> {
    sse.iter()
        .zip(std)
        .map(|(&s, &sd)| {
            let rmse = (s / rows as f64).sqrt();
            if sd > 0.0 {
                rmse / sd
            } else {
                rmse
            }
        })
        .collect()
}

fn train_nrmse(state: &GrowthState, w: MatRef<'_, f64>) -> Vec<f64> {
    let sse = sse_from_gram(state.gram.as_ref(), state.aty.as_ref(), &state.y_sq, w);
    let n = state.n_samples as f64;
    let std: Vec<f64> = state
        .y_sum
        .iter()
        .zip(&state.y_sq)
        .map(|(&s, &q)| {
            let m = s / n;
            (q / n - m * m).max(0.0).sqrt()
        })
        .collect();
    nrmse(&sse, state.n_samples, &std)
}

/// A fit whose weights or error measures are not finite (an ill-conditioned system that
/// the Cholesky test let through, overflowing sums) is an error, never a model.
fn check_finite_result(
    w: MatRef<'_, f64>,
    validation_nrmse: &[f64],
    train_nrmse: &[f64],
) -> Result<(), BroadError> {
    for j in 0..w.ncols() {
        for i in 0..w.nrows() {
            if !w[(i, j)].is_finite() {
                return Err(BroadError::NonFiniteResult(format!(
                    "weight of pattern column {i}, output {j} is {}",
                    w[(i, j)]
                )));
            }
        }
    }
    for (what, v) in [("validation", validation_nrmse), ("training", train_nrmse)] {
        if let Some((o, e)) = v.iter().enumerate().find(|(_, e)| !e.is_finite()) {
            return Err(BroadError::NonFiniteResult(format!(
                "{what} NRMSE of output {o} is {e}"
            )));
        }
    }
    Ok(())
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

/// Fits the flat RBF network of METHOD.md section 5 on `train`:
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
    if let Some(v) = validation {
        check_same_widths(train, v)?;
    }
    if validation.is_none() && config.lambda_grid.len() > 1 {
        return Err(BroadError::NeedValidation(config.lambda_grid.len()));
    }
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
    if validation.is_none() && config.lambda_grid.len() > 1 {
        return Err(BroadError::NeedValidation(config.lambda_grid.len()));
    }
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

    let t = Instant::now();
    let acc = accumulate_gram(&fm, train, config.block_rows, threads, config.gram_strategy);
    times.gram_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut scan = Vec::with_capacity(config.lambda_grid.len());
    let mut solutions: Vec<(usize, Mat<f64>)> = Vec::new();
    for (c, &rel) in config.lambda_grid.iter().enumerate() {
        let lambda = rel * n as f64;
        let ok = match factor(acc.g.as_ref(), lambda, bias, par) {
            Some(l) => {
                solutions.push((c, solve(l.as_ref(), acc.aty.as_ref(), par)));
                true
            }
            None => false,
        };
        scan.push(LambdaScore {
            lambda_rel: rel,
            lambda,
            factorised: ok,
            validation_nrmse: Vec::new(),
            mean_nrmse: None,
        });
    }
    if solutions.is_empty() {
        return Err(BroadError::NotPositiveDefinite {
            tried: scan.iter().map(|s| s.lambda).collect(),
        });
    }
    times.solve_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut chosen = 0usize; // index into `solutions`
    let mut validation_nrmse = Vec::new();
    if let Some(val) = validation {
        let mut w_all = Mat::<f64>::zeros(p, solutions.len() * d_out);
        for (i, (_, w)) in solutions.iter().enumerate() {
            w_all.as_mut().subcols_mut(i * d_out, d_out).copy_from(w);
        }
        let sse = prediction_sse(
            &fm,
            val,
            w_all.as_ref(),
            config.block_rows,
            threads,
            config.gram_strategy,
        );
        let std = target_std(val);
        let mut best = f64::INFINITY;
        for (i, (c, _)) in solutions.iter().enumerate() {
            let e = nrmse(&sse[i * d_out..(i + 1) * d_out], val.n_samples(), &std);
            let mean = e.iter().sum::<f64>() / d_out as f64;
            if mean < best {
                best = mean;
                chosen = i;
            }
            scan[*c].validation_nrmse = e;
            scan[*c].mean_nrmse = Some(mean);
        }
        validation_nrmse = scan[solutions[chosen].0].validation_nrmse.clone();
    }
    times.validation_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let (c, w) = solutions.swap_remove(chosen);
    drop(solutions);
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
    };
    let mut model = BroadModel {
        fm,
        d_out,
        lambda,
        lambda_rel: scan[c].lambda_rel,
        w: Vec::new(),
        wt: Vec::new(),
        state: Some(state),
        provenance: Provenance {
            fit: Some(fit_settings),
            ..Provenance::default()
        },
    };
    model.set_weights(w.as_ref());
    let report = FitReport {
        samples: n,
        validation_samples: validation.map(|v| v.n_samples()).unwrap_or(0),
        nodes: model.n_nodes(),
        pattern_width: p,
        lambda,
        lambda_rel: scan[c].lambda_rel,
        lambda_scan: scan,
        validation_nrmse,
        train_nrmse: train_e,
        times: PhaseTimes::default(),
    };
    Ok((model, report))
}

impl BroadModel {
    pub(crate) fn set_weights(&mut self, w: MatRef<'_, f64>) {
        let p = w.nrows();
        let n = w.ncols();
        self.w = vec![0.0; p * n];
        self.wt = vec![0.0; p * n];
        for i in 0..p {
            for o in 0..n {
                self.w[i * n + o] = w[(i, o)];
                self.wt[o * p + i] = w[(i, o)];
            }
        }
    }

    /// Input width d_in.
    pub fn d_in(&self) -> usize {
        self.fm.d_in()
    }
    /// Output width d_out.
    pub fn d_out(&self) -> usize {
        self.d_out
    }
    /// Number of enhancement nodes L.
    pub fn n_nodes(&self) -> usize {
        self.fm.n_nodes()
    }
    /// Pattern width P = d_in + F + 1 + L.
    pub fn pattern_width(&self) -> usize {
        self.fm.width()
    }
    /// Index of the bias column in the pattern row (d_in + F).
    pub fn bias_index(&self) -> usize {
        self.fm.bias_index()
    }
    /// Absolute ridge parameter in use.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    /// Relative ridge parameter (lambda / N).
    pub fn lambda_rel(&self) -> f64 {
        self.lambda_rel
    }
    /// Weights W, P x d_out, row-major (row i: pattern column i).
    pub fn weights(&self) -> &[f64] {
        &self.w
    }
    /// Enhancement nodes (centres in standardised units).
    pub fn nodes(&self) -> &NodeSet {
        &self.fm.nodes
    }
    /// Input standardisation.
    pub fn standardiser(&self) -> &Standardiser {
        &self.fm.standardiser
    }
    /// Friction features.
    pub fn friction(&self) -> &FrictionFeatures {
        &self.fm.friction
    }
    /// True when the model keeps the Gram state needed by [`grow`](Self::grow) and
    /// [`set_lambda`](Self::set_lambda).
    pub fn has_growth_state(&self) -> bool {
        self.state.is_some()
    }
    /// Number of training rows behind the growth state.
    pub fn training_samples(&self) -> Option<usize> {
        self.state.as_ref().map(|s| s.n_samples)
    }
    /// Drops the growth state (Gram, factor; about 16 P^2 bytes) for a deployment copy.
    pub fn strip_growth_state(&mut self) {
        self.state = None;
    }

    /// A workspace sized for this model.
    pub fn workspace(&self) -> Workspace {
        Workspace {
            pattern: vec![0.0; self.pattern_width()],
        }
    }

    fn check_input(&self, x: &[f64]) -> Result<(), BroadError> {
        if x.len() != self.d_in() {
            return Err(BroadError::Dimension {
                what: "input vector",
                expected: self.d_in(),
                got: x.len(),
            });
        }
        if let Some((k, &v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(BroadError::NonFinite {
                what: "input vector",
                row: 0,
                column: k,
                value: v,
            });
        }
        Ok(())
    }

    /// Pattern row `a(x)` of one raw input (length P), METHOD.md section 5.
    pub fn pattern_into(&self, x: &[f64], a: &mut [f64]) -> Result<(), BroadError> {
        self.check_input(x)?;
        if a.len() != self.pattern_width() {
            return Err(BroadError::Dimension {
                what: "pattern row",
                expected: self.pattern_width(),
                got: a.len(),
            });
        }
        self.fm.fill_row(x, a);
        Ok(())
    }

    /// `out = W^T a(x)`: the estimate `f_hat(q, q', q'')` of METHOD.md section 5 for one
    /// raw input row. Allocation-free when `ws` comes from [`workspace`](Self::workspace)
    /// (a workspace made before a [`grow`](Self::grow) is enlarged once).
    pub fn predict_into(
        &self,
        x: &[f64],
        out: &mut [f64],
        ws: &mut Workspace,
    ) -> Result<(), BroadError> {
        self.check_input(x)?;
        if out.len() != self.d_out {
            return Err(BroadError::Dimension {
                what: "output vector",
                expected: self.d_out,
                got: out.len(),
            });
        }
        let p = self.pattern_width();
        if ws.pattern.len() != p {
            ws.pattern.resize(p, 0.0);
        }
        self.fm.fill_row(x, &mut ws.pattern);
        for (o, v) in out.iter_mut().enumerate() {
            *v = kernels::dot(&ws.pattern, &self.wt[o * p..(o + 1) * p]);
        }
        Ok(())
    }

    /// Predictions for many rows: `inputs` row-major (N x d_in), `out` row-major (N x d_out).
    pub fn predict_batch(&self, inputs: &[f64], out: &mut [f64]) -> Result<(), BroadError> {
        let d = self.d_in();
        if !inputs.len().is_multiple_of(d) {
            return Err(BroadError::Dimension {
                what: "input array length (multiple of d_in)",
                expected: (inputs.len() / d + 1) * d,
                got: inputs.len(),
            });
        }
        let rows = inputs.len() / d;
        if out.len() != rows * self.d_out {
            return Err(BroadError::Dimension {
                what: "output array length",
                expected: rows * self.d_out,
                got: out.len(),
            });
        }
        check_finite(inputs, d, "inputs")?;
        let mut ws = self.workspace();
        for i in 0..rows {
            self.predict_into(
                &inputs[i * d..(i + 1) * d],
                &mut out[i * self.d_out..(i + 1) * self.d_out],
                &mut ws,
            )?;
        }
        Ok(())
    }

    /// Per-output NRMSE (RMSE / std of the target; RMSE where the std is 0) on `data`,
    /// by blocked passes (`threads`, 0 = all cores).
    pub fn evaluate(&self, data: &Dataset<'_>, threads: usize) -> Result<Vec<f64>, BroadError> {
        if data.d_in() != self.d_in() {
            return Err(BroadError::Dimension {
                what: "data input width",
                expected: self.d_in(),
                got: data.d_in(),
            });
        }
        if data.d_out() != self.d_out {
            return Err(BroadError::Dimension {
                what: "data output width",
                expected: self.d_out,
                got: data.d_out(),
            });
        }
        let threads = if threads == 0 {
            BroadConfig::default().thread_count()
        } else {
            threads
        };
        let w = MatRef::from_row_major_slice(&self.w, self.pattern_width(), self.d_out);
        let sse = prediction_sse(&self.fm, data, w, 2048, threads, GramStrategy::PerThread);
        Ok(nrmse(&sse, data.n_samples(), &target_std(data)))
    }

    /// Re-solves with another relative lambda from the stored Gram (no pass over data).
    pub fn set_lambda(&mut self, lambda_rel: f64) -> Result<(), BroadError> {
        if !(lambda_rel.is_finite() && lambda_rel > 0.0) {
            return Err(BroadError::Config(format!(
                "lambda {lambda_rel} must be finite and > 0"
            )));
        }
        let bias = self.bias_index();
        let state = self.state.as_mut().ok_or(BroadError::NoGrowthState)?;
        let lambda = lambda_rel * state.n_samples as f64;
        let par = par_for(BroadConfig::default().thread_count());
        let chol = factor(state.gram.as_ref(), lambda, bias, par).ok_or(
            BroadError::NotPositiveDefinite {
                tried: vec![lambda],
            },
        )?;
        let w = solve(chol.as_ref(), state.aty.as_ref(), par);
        check_finite_result(w.as_ref(), &[], &[])?;
        state.chol = chol;
        self.lambda = lambda;
        self.lambda_rel = lambda_rel;
        self.set_weights(w.as_ref());
        Ok(())
    }

    /// Incremental growth by k enhancement nodes without retraining (METHOD.md section 5,
    /// eq. 14-16 in its exact ridge form): one pass over the training data computes only
    /// the k new rows of the Gram, `A_new^T [A_old | A_new]`, and `A_new^T Y`; the stored
    /// Cholesky factor is extended by the Schur-complement block
    /// (`L21 = G21 L11^-T`, `L22 = chol(G22 + lambda I - L21 L21^T)`) and W re-solved.
    /// The result equals a full retrain on the grown node set with the same lambda
    /// (to rounding). `train` must be the training data of the fit (checked by row count,
    /// input means and target sums). `config` supplies `block_rows`, `threads`,
    /// `gram_strategy`, `centre_subsample` and `widths`.
    pub fn grow(
        &mut self,
        train: &Dataset<'_>,
        spec: &GrowthSpec,
        config: &BroadConfig,
    ) -> Result<GrowthReport, BroadError> {
        let t0 = Instant::now();
        config.validate(self.d_in())?;
        let d = self.d_in();
        if train.d_in() != d {
            return Err(BroadError::Dimension {
                what: "growth data input width",
                expected: d,
                got: train.d_in(),
            });
        }
        if train.d_out() != self.d_out {
            return Err(BroadError::Dimension {
                what: "growth data output width",
                expected: self.d_out,
                got: train.d_out(),
            });
        }
        let state = self.state.as_ref().ok_or(BroadError::NoGrowthState)?;
        self.check_training_data(train, state)?;
        let added = match spec {
            GrowthSpec::Nodes(ns) => ns.len(),
            GrowthSpec::KMeansPlusPlus { count, .. } => *count,
        };
        let size = FitSize::growth(self, train.n_samples(), 0, added, config);
        check_budget(&size, &config.budget)?;
        let threads = config.thread_count();
        let par = par_for(threads);

        let new_nodes = match spec {
            GrowthSpec::Nodes(ns) => {
                ns.validate(d)?;
                ns.clone()
            }
            GrowthSpec::KMeansPlusPlus { count, seed } => {
                let mut rng = rng_from_seed(*seed);
                let (pts_t, m) = subsample_standardised(
                    train,
                    &self.fm.standardiser,
                    config.centre_subsample,
                    &mut rng,
                );
                let centres = kmeanspp(&pts_t, m, d, &self.fm.nodes.centres, *count, &mut rng);
                let mut all = self.fm.nodes.centres.clone();
                all.extend_from_slice(&centres);
                let widths = compute_widths(
                    &all,
                    d,
                    self.n_nodes(),
                    &self.fm.nodes.widths,
                    &config.widths,
                );
                NodeSet {
                    dim: d,
                    centres,
                    widths,
                }
            }
        };
        let k = new_nodes.len();
        let centres_s = t0.elapsed().as_secs_f64();
        if k == 0 {
            let train_e = train_nrmse(
                state,
                MatRef::from_row_major_slice(&self.w, self.pattern_width(), self.d_out),
            );
            return Ok(GrowthReport {
                nodes_added: 0,
                nodes: self.n_nodes(),
                centres_s,
                cross_terms_s: 0.0,
                solve_s: 0.0,
                total_s: t0.elapsed().as_secs_f64(),
                train_nrmse: train_e,
            });
        }
        let mut all_nodes = self.fm.nodes.clone();
        all_nodes.extend(&new_nodes);
        let fm = FeatureMap::new(
            self.fm.standardiser.clone(),
            self.fm.friction.clone(),
            all_nodes,
        );

        let t = Instant::now();
        let (rows, aty_new) = accumulate_new_rows(
            &fm,
            train,
            k,
            config.block_rows,
            threads,
            config.gram_strategy,
        );
        let cross_terms_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let p_old = self.pattern_width();
        let p = p_old + k;
        let chol = extend_factor(state.chol.as_ref(), rows.as_ref(), self.lambda, par).ok_or(
            BroadError::NotPositiveDefinite {
                tried: vec![self.lambda],
            },
        )?;
        let mut gram = Mat::<f64>::zeros(p, p);
        gram.as_mut()
            .submatrix_mut(0, 0, p_old, p_old)
            .copy_from(&state.gram);
        gram.as_mut().submatrix_mut(p_old, 0, k, p).copy_from(&rows);
        let mut aty = Mat::<f64>::zeros(p, self.d_out);
        aty.as_mut()
            .submatrix_mut(0, 0, p_old, self.d_out)
            .copy_from(&state.aty);
        aty.as_mut()
            .submatrix_mut(p_old, 0, k, self.d_out)
            .copy_from(&aty_new);
        let w = solve(chol.as_ref(), aty.as_ref(), par);
        let new_state = GrowthState {
            gram,
            aty,
            chol,
            n_samples: state.n_samples,
            y_sum: state.y_sum.clone(),
            y_sq: state.y_sq.clone(),
        };
        let train_e = train_nrmse(&new_state, w.as_ref());
        let solve_s = t.elapsed().as_secs_f64();
        check_finite_result(w.as_ref(), &[], &train_e)?;

        self.provenance.growth.push(GrowthRecord {
            nodes_added: k,
            centres: match spec {
                GrowthSpec::Nodes(_) => None,
                GrowthSpec::KMeansPlusPlus { seed, .. } => Some(CentreSettings {
                    centre_subsample: config.centre_subsample,
                    seed: *seed,
                    widths: config.widths.clone(),
                }),
            },
        });
        self.fm = fm;
        self.state = Some(new_state);
        self.set_weights(w.as_ref());
        Ok(GrowthReport {
            nodes_added: k,
            nodes: self.n_nodes(),
            centres_s,
            cross_terms_s,
            solve_s,
            total_s: t0.elapsed().as_secs_f64(),
            train_nrmse: train_e,
        })
    }

    fn check_training_data(
        &self,
        train: &Dataset<'_>,
        state: &GrowthState,
    ) -> Result<(), BroadError> {
        if train.n_samples() != state.n_samples {
            return Err(BroadError::GrowthDataMismatch(format!(
                "{} rows, the model was trained on {}",
                train.n_samples(),
                state.n_samples
            )));
        }
        let now = Standardiser::from_data(train);
        for (k, ((a, b), s)) in now
            .mean
            .iter()
            .zip(&self.fm.standardiser.mean)
            .zip(&self.fm.standardiser.std)
            .enumerate()
        {
            if (a - b).abs() > 1e-9 * (s + b.abs()) {
                return Err(BroadError::GrowthDataMismatch(format!(
                    "mean of input column {k} is {a}, training mean was {b}"
                )));
            }
        }
        let d_out = self.d_out;
        let mut y_sum = vec![0.0; d_out];
        for r in train.targets().chunks_exact(d_out) {
            for (s, v) in y_sum.iter_mut().zip(r) {
                *s += v;
            }
        }
        for (o, (a, b)) in y_sum.iter().zip(&state.y_sum).enumerate() {
            let scale = (state.y_sq[o] * state.n_samples as f64).sqrt();
            if (a - b).abs() > 1e-9 * scale.max(1e-300) {
                return Err(BroadError::GrowthDataMismatch(format!(
                    "sum of target column {o} is {a}, training sum was {b}"
                )));
            }
        }
        Ok(())
    }
}
