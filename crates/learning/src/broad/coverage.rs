//! Where the training data were (issue #22, "the network knows where its training data
//! were"): the coverage of an input and the prediction faded to zero outside the data.
//!
//! * **Activation** `m(x) = max_j xi_j(x)`, the largest Gaussian enhancement node of the
//!   pattern row (`features.rs`): close to 1 on a node's centre, falling like
//!   `exp(-d^2 / eta^2)` with the standardised distance d to the nearest node.
//! * **Threshold** `m_0`: at training time, the [`COVERAGE_QUANTILE`] quantile of `m` over
//!   the training rows (99 % of the training rows have `m >= m_0`), stored in the model
//!   (and its file). Models without one (older files) have no coverage: 1 everywhere.
//! * **Coverage** `c(x) = min(1, m(x) / m_0)` in [0, 1]: 1 wherever the input is as well
//!   covered as 99 % of the training rows, falling to 0 far from every node.
//! * **Fade** `s(c) = c^2 (3 - 2 c)` (smoothstep): [`BroadModel::predict_faded_into`]
//!   multiplies the output by it, so the estimate goes smoothly to zero outside the
//!   training data instead of extrapolating.

use super::data::Dataset;
use super::error::BroadError;
use super::features::FeatureMap;
use super::model::{BroadModel, Workspace};

/// Quantile of the training rows' largest activation taken as the coverage threshold.
pub const COVERAGE_QUANTILE: f64 = 0.01;

/// Smallest threshold kept: below it the nodes do not cover the training data at all
/// (the activations underflow) and the model gets no threshold.
const MIN_THRESHOLD: f64 = 1e-200;

/// Largest Gaussian activation of a filled pattern row.
fn max_activation(fm: &FeatureMap, pattern: &[f64]) -> f64 {
    pattern[fm.gauss_offset()..]
        .iter()
        .fold(0.0f64, |m, &v| m.max(v))
}

/// The [`COVERAGE_QUANTILE`] quantile of the largest activation over the rows of `data`
/// (`threads` workers); `None` without nodes or when it underflows.
pub(crate) fn coverage_threshold(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    threads: usize,
) -> Option<f64> {
    let n = data.n_samples();
    if fm.n_nodes() == 0 || n == 0 {
        return None;
    }
    let per = n.div_ceil(threads.max(1));
    let mut m = vec![0.0; n];
    std::thread::scope(|scope| {
        for (t, out) in m.chunks_mut(per).enumerate() {
            scope.spawn(move || {
                let mut a = vec![0.0; fm.width()];
                for (i, v) in out.iter_mut().enumerate() {
                    fm.fill_row(data.input_row(t * per + i), &mut a);
                    *v = max_activation(fm, &a);
                }
            });
        }
    });
    threshold_of_maxima(&mut m)
}

/// The coverage threshold from the largest activation of every training row (any order;
/// reordered in place): the [`COVERAGE_QUANTILE`] quantile, `None` when it underflows.
pub(crate) fn threshold_of_maxima(m: &mut [f64]) -> Option<f64> {
    let n = m.len();
    if n == 0 {
        return None;
    }
    let k = ((n - 1) as f64 * COVERAGE_QUANTILE).floor() as usize;
    let (_, q, _) = m.select_nth_unstable_by(k, f64::total_cmp);
    (*q >= MIN_THRESHOLD && q.is_finite()).then_some(*q)
}

/// `c^2 (3 - 2 c)` for c in [0, 1].
pub(crate) fn smoothstep(c: f64) -> f64 {
    c * c * (3.0 - 2.0 * c)
}

impl BroadModel {
    /// The coverage threshold `m_0` (module `coverage.rs`): `None` for models trained
    /// before it existed, which then have coverage 1 everywhere.
    pub fn coverage_threshold(&self) -> Option<f64> {
        self.coverage_threshold
    }

    /// Coverage of the raw input `x`: `min(1, max_j xi_j(x) / m_0)`, in [0, 1]; 1 for a
    /// model without threshold. Allocation-free with a workspace from
    /// [`workspace`](Self::workspace).
    pub fn coverage(&self, x: &[f64], ws: &mut Workspace) -> Result<f64, BroadError> {
        self.check_input(x)?;
        Ok(self.coverage_of(self.fill_pattern(x, ws)))
    }

    fn coverage_of(&self, pattern: &[f64]) -> f64 {
        match self.coverage_threshold {
            Some(m0) => (max_activation(&self.fm, pattern) / m0).min(1.0),
            None => 1.0,
        }
    }

    /// `out = s(c(x)) W^T a(x)`: [`predict_into`](Self::predict_into) faded to zero
    /// outside the training data by the smoothstep `s` of the coverage `c(x)`, which it
    /// returns. Inside the data (c = 1) the output equals `predict_into`'s exactly.
    /// Allocation-free like `predict_into`.
    pub fn predict_faded_into(
        &self,
        x: &[f64],
        out: &mut [f64],
        ws: &mut Workspace,
    ) -> Result<f64, BroadError> {
        self.predict_into(x, out, ws)?;
        let c = self.coverage_of(ws.pattern());
        if c < 1.0 {
            let s = smoothstep(c);
            out.iter_mut().for_each(|v| *v *= s);
        }
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothstep_is_flat_at_both_ends() {
        assert_eq!(smoothstep(0.0), 0.0);
        assert_eq!(smoothstep(1.0), 1.0);
        assert_eq!(smoothstep(0.5), 0.5);
        assert!(smoothstep(0.01) < 1e-3);
    }
}
