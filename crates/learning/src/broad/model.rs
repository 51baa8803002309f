//! The trained flat RBF network: its parts, allocation-free prediction, evaluation and
//! re-solving for another lambda (docs/method.md section 5). Fitting is in `fit.rs`, growth in
//! `growth.rs`.

use super::config::{BroadConfig, FrictionFeatures, GramStrategy};
use super::data::{check_finite, Dataset, Standardiser};
use super::error::BroadError;
use super::features::{FeatureMap, NodeSet};
use super::gram::prediction_sse;
use super::kernels;
use super::provenance::Provenance;
use super::solve::{factor, solve, sse_from_gram};
use faer::{Mat, MatRef, Par};

/// What the model keeps to grow without retraining (docs/method.md section 5, "incremental
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

    /// The pattern row of the last prediction.
    pub(crate) fn pattern(&self) -> &[f64] {
        &self.pattern
    }
}

/// A trained flat ("broad") RBF network, `f_hat(x) = W^T a(x)` with the pattern row
/// `a(x) = [X_std | friction features | 1 | xi(X)]` (docs/method.md section 5 and section 7).
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
    /// Coverage threshold `m_0` (`coverage.rs`); `None`: no coverage (older files).
    pub(crate) coverage_threshold: Option<f64>,
    /// What the model knows about how it was made (`provenance.rs`).
    pub(crate) provenance: Provenance,
}

pub(crate) fn par_for(threads: usize) -> Par {
    if threads > 1 {
        Par::rayon(threads)
    } else {
        Par::Seq
    }
}

pub(crate) fn target_std(data: &Dataset<'_>) -> Vec<f64> {
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

pub(crate) fn nrmse(sse: &[f64], rows: usize, std: &[f64]) -> Vec<f64> {
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

pub(crate) fn train_nrmse(state: &GrowthState, w: MatRef<'_, f64>) -> Vec<f64> {
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
pub(crate) fn check_finite_result(
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

    pub(crate) fn check_input(&self, x: &[f64]) -> Result<(), BroadError> {
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

    /// Pattern row `a(x)` of one raw input (length P), docs/method.md section 5.
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

    /// The pattern row of the checked input `x` in the workspace (grown once if it is
    /// too small).
    pub(crate) fn fill_pattern<'w>(&self, x: &[f64], ws: &'w mut Workspace) -> &'w [f64] {
        let p = self.pattern_width();
        if ws.pattern.len() != p {
            ws.pattern.resize(p, 0.0);
        }
        self.fm.fill_row(x, &mut ws.pattern);
        &ws.pattern
    }

    /// `out = W^T a(x)`: the estimate `f_hat(q, q', q'')` of docs/method.md section 5 for one
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
        self.fill_pattern(x, ws);
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_results_are_errors_naming_what() {
        let mut w = Mat::<f64>::zeros(4, 2);
        assert!(check_finite_result(w.as_ref(), &[0.1, 0.2], &[0.1, 0.3]).is_ok());
        w[(3, 1)] = f64::NAN;
        let e = check_finite_result(w.as_ref(), &[], &[]).unwrap_err();
        assert!(
            matches!(&e, BroadError::NonFiniteResult(m) if m.contains("pattern column 3, output 1 is NaN")),
            "{e}"
        );
        w[(3, 1)] = 0.0;
        let e = check_finite_result(w.as_ref(), &[0.1, f64::INFINITY], &[]).unwrap_err();
        assert!(
            e.to_string()
                .contains("validation NRMSE of output 1 is inf"),
            "{e}"
        );
        let e = check_finite_result(w.as_ref(), &[], &[f64::NAN]).unwrap_err();
        assert!(e.to_string().contains("training NRMSE of output 0"), "{e}");
    }
}
