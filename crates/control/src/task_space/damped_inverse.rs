//! The damped pseudo-inverse of a `6 x n` Jacobian, bounded near singularities (see
//! [`SingularityDampingConfig`] for how the damping is chosen).
//!
//! With `J J^T = U diag(s_i^2) U^T` (a symmetric `6 x 6` eigen-decomposition: fixed size, so
//! no allocation), the selectively damped inverse is
//!
//! ```text
//!     J^# = J^T U diag(w_i) U^T,      J^#T = U diag(w_i) U^T J,      w_i = 1 / (s_i^2 + lambda_i^2)
//! ```
//!
//! which equals `V diag(s_i / (s_i^2 + lambda_i^2)) U^T` (the SVD form) for `s_i > 0`. Rows
//! of axes outside the task are zero; the `6 - min(n, k)` smallest eigenvalues (`k` task
//! axes) are then structurally zero: their directions are outside the range of `J`, and
//! `w_i = 0` there.

use nalgebra::{Matrix6, Matrix6xX, SymmetricEigen, Vector6};

use super::config::SingularityDampingConfig;
use crate::config::Bound;
use crate::error::{ConfigError, Fault};

/// Iteration bound of the eigen-decomposition (it converges in a few sweeps for a 6 x 6
/// matrix; the bound only guarantees termination).
const MAX_EIGEN_ITERATIONS: usize = 200;

/// The factorisation of one Jacobian and the damping it needed.
#[derive(Clone, Debug)]
pub(crate) struct DampedPseudoInverse {
    threshold: f64,
    max_damping: f64,
    rank: usize,
    basis: Matrix6<f64>,
    weights: Vector6<f64>,
    smallest_singular_value: f64,
    damping: f64,
}

impl DampedPseudoInverse {
    /// For Jacobians of an arm with `n` joints on `k` task axes (the other rows zero).
    pub(crate) fn new(
        n: usize,
        k: usize,
        cfg: &SingularityDampingConfig,
    ) -> Result<Self, ConfigError> {
        Ok(DampedPseudoInverse {
            threshold: Bound::Positive.check("threshold", cfg.threshold)?,
            max_damping: Bound::Positive.check("max_damping", cfg.max_damping)?,
            rank: n.min(k),
            basis: Matrix6::identity(),
            weights: Vector6::zeros(),
            smallest_singular_value: 0.0,
            damping: 0.0,
        })
    }

    /// Factorises `j` (finite). Fails only if the eigen-decomposition does not converge.
    pub(crate) fn factor(&mut self, j: &Matrix6xX<f64>) -> Result<(), Fault> {
        let mut jjt = Matrix6::zeros();
        for r in 0..6 {
            for c in r..6 {
                let v = j.row(r).dot(&j.row(c));
                jjt[(r, c)] = v;
                jjt[(c, r)] = v;
            }
        }
        let eigen = SymmetricEigen::try_new(jjt, f64::EPSILON, MAX_EIGEN_ITERATIONS).ok_or(
            Fault::Internal("eigen-decomposition of J J^T did not converge"),
        )?;
        let mut order = [0usize, 1, 2, 3, 4, 5];
        order.sort_unstable_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
        let structural = 6 - self.rank;
        self.basis = eigen.eigenvectors;
        self.smallest_singular_value = f64::INFINITY;
        self.damping = 0.0;
        for (k, &i) in order.iter().enumerate() {
            if k < structural {
                self.weights[i] = 0.0;
                continue;
            }
            let s2 = eigen.eigenvalues[i].max(0.0);
            let s = s2.sqrt();
            let lambda2 = if s < self.threshold {
                let ratio = s / self.threshold;
                self.max_damping * self.max_damping * (1.0 - ratio * ratio)
            } else {
                0.0
            };
            self.weights[i] = 1.0 / (s2 + lambda2);
            if k == structural {
                self.smallest_singular_value = s;
                self.damping = lambda2.sqrt();
            }
        }
        Ok(())
    }

    /// `J^#T tau` (a wrench from joint torques), `j` the factorised Jacobian.
    pub(crate) fn transpose_apply(&self, j: &Matrix6xX<f64>, tau: &[f64]) -> Vector6<f64> {
        let mut y = Vector6::zeros();
        for (c, t) in tau.iter().enumerate() {
            y += j.column(c) * *t;
        }
        self.weighted(&y)
    }

    /// `J^# y` into `out` (joint space), `j` the factorised Jacobian.
    pub(crate) fn apply(&self, j: &Matrix6xX<f64>, y: &Vector6<f64>, out: &mut [f64]) {
        let v = self.weighted(y);
        for (c, o) in out.iter_mut().enumerate() {
            *o = j.column(c).dot(&v);
        }
    }

    /// `U diag(w) U^T y`.
    fn weighted(&self, y: &Vector6<f64>) -> Vector6<f64> {
        let mut coefficients = self.basis.tr_mul(y);
        coefficients.component_mul_assign(&self.weights);
        self.basis * coefficients
    }

    /// The smallest of the `min(n, k)` singular values at the last factorisation (infinite
    /// with no task axis).
    pub(crate) fn smallest_singular_value(&self) -> f64 {
        self.smallest_singular_value
    }

    /// The damping `lambda` applied to that singular value.
    pub(crate) fn damping(&self) -> f64 {
        self.damping
    }

    /// Forget the last factorisation.
    pub(crate) fn reset(&mut self) {
        self.basis = Matrix6::identity();
        self.weights = Vector6::zeros();
        self.smallest_singular_value = 0.0;
        self.damping = 0.0;
    }
}
