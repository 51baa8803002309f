//! The damped pseudo-inverse of a `6 x n` Jacobian on `k` task axes (the other rows zero),
//! bounded near singularities (see [`SingularityDampingConfig`] for how the damping is
//! chosen).
//!
//! With `J J^T = U diag(s_i^2) U^T` (symmetric `6 x 6`), the selectively damped inverse is
//!
//! ```text
//!     J^# = J^T P,      J^#T = P J,      P = U diag(w_i) U^T,      w_i = 1 / (s_i^2 + lambda_i^2)
//! ```
//!
//! which equals `V diag(s_i / (s_i^2 + lambda_i^2)) U^T` (the SVD form) for `s_i > 0`. The
//! `6 - min(n, k)` smallest eigenvalues are structurally zero (the rows outside the task,
//! and more when the arm has fewer joints than task axes): their directions are outside the
//! range of `J`, and `w_i = 0` there.
//!
//! Two routes to `P`, both fixed-size (no allocation):
//! * when no singular value can be below the threshold, `P = (J J^T)^-1` on the task block
//!   by Cholesky (about 0.3 us). The test: `s_min^2 >= 1 / trace((J J^T)^-1)` (the trace
//!   of the inverse is `sum 1 / s_i^2`), so `1 / trace >= threshold^2` proves that no
//!   damping is due;
//! * otherwise the eigen-decomposition (about 5 us on a loaded 2-core machine) and the
//!   damping of each small singular value.
//!
//! Both give the same `P` when no damping is due (up to rounding).

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
    task: [bool; 6],
    /// `min(n, k)`.
    rank: usize,
    /// The number of task axes `k`.
    axes: usize,
    /// `P`.
    operator: Matrix6<f64>,
    damping: f64,
    eigen_used: bool,
}

impl DampedPseudoInverse {
    /// For Jacobians of an arm with `n` joints on the task axes `task` (the other rows
    /// zero).
    pub(crate) fn new(
        n: usize,
        task: [bool; 6],
        cfg: &SingularityDampingConfig,
    ) -> Result<Self, ConfigError> {
        let axes = task.iter().filter(|t| **t).count();
        Ok(DampedPseudoInverse {
            threshold: Bound::Positive.check("threshold", cfg.threshold)?,
            max_damping: Bound::Positive.check("max_damping", cfg.max_damping)?,
            task,
            rank: n.min(axes),
            axes,
            operator: Matrix6::zeros(),
            damping: 0.0,
            eigen_used: false,
        })
    }

    /// Factorises `j` (finite, rows outside the task zero). Fails only if the
    /// eigen-decomposition does not converge.
    pub(crate) fn factor(&mut self, j: &Matrix6xX<f64>) -> Result<(), Fault> {
        let gram = gram(j);
        if self.rank == self.axes && self.factor_undamped(&gram) {
            return Ok(());
        }
        self.factor_eigen(&gram)
    }

    /// `P = (J J^T)^-1` on the task block if no singular value can be below the threshold
    /// (then true); false leaves `self` for the eigen route.
    fn factor_undamped(&mut self, gram: &Matrix6<f64>) -> bool {
        let mut a = *gram;
        for i in 0..6 {
            if !self.task[i] {
                a[(i, i)] = 1.0;
            }
        }
        let Some(cholesky) = a.cholesky() else {
            return false;
        };
        let inverse = cholesky.inverse();
        let trace: f64 = (0..6)
            .filter(|&i| self.task[i])
            .map(|i| inverse[(i, i)])
            .sum();
        let threshold2 = self.threshold * self.threshold;
        if !(trace.is_finite() && trace > 0.0 && trace * threshold2 <= 1.0) {
            return false;
        }
        self.operator = inverse;
        self.keep_task_block();
        self.damping = 0.0;
        self.eigen_used = false;
        true
    }

    /// `P` from the eigen-decomposition, damping the small singular values.
    fn factor_eigen(&mut self, gram: &Matrix6<f64>) -> Result<(), Fault> {
        let eigen = SymmetricEigen::try_new(*gram, f64::EPSILON, MAX_EIGEN_ITERATIONS).ok_or(
            Fault::Internal("eigen-decomposition of J J^T did not converge"),
        )?;
        let mut order = [0usize, 1, 2, 3, 4, 5];
        order.sort_unstable_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
        let structural = 6 - self.rank;
        self.operator = Matrix6::zeros();
        self.damping = 0.0;
        for (rank, &i) in order.iter().enumerate().skip(structural) {
            let s2 = eigen.eigenvalues[i].max(0.0);
            let s = s2.sqrt();
            let lambda2 = if s < self.threshold {
                let ratio = s / self.threshold;
                self.max_damping * self.max_damping * (1.0 - ratio * ratio)
            } else {
                0.0
            };
            if rank == structural {
                self.damping = lambda2.sqrt();
            }
            let u = eigen.eigenvectors.column(i);
            self.operator += (u * u.transpose()) * (1.0 / (s2 + lambda2));
        }
        self.keep_task_block();
        self.eigen_used = true;
        Ok(())
    }

    /// Zeroes the rows and columns of `P` outside the task.
    fn keep_task_block(&mut self) {
        for i in 0..6 {
            if !self.task[i] {
                self.operator.row_mut(i).fill(0.0);
                self.operator.column_mut(i).fill(0.0);
            }
        }
    }

    /// `J^#T tau` (a wrench from joint torques), `j` the factorised Jacobian.
    pub(crate) fn transpose_apply(&self, j: &Matrix6xX<f64>, tau: &[f64]) -> Vector6<f64> {
        let mut y = Vector6::zeros();
        for (c, t) in tau.iter().enumerate() {
            y += j.column(c) * *t;
        }
        self.operator * y
    }

    /// `J^# y` into `out` (joint space), `j` the factorised Jacobian.
    pub(crate) fn apply(&self, j: &Matrix6xX<f64>, y: &Vector6<f64>, out: &mut [f64]) {
        let v = self.operator * y;
        for (c, o) in out.iter_mut().enumerate() {
            *o = j.column(c).dot(&v);
        }
    }

    /// The damping `lambda` of the smallest of the `min(n, k)` singular values at the last
    /// factorisation (0 when none was below the threshold).
    pub(crate) fn damping(&self) -> f64 {
        self.damping
    }

    /// Forget the last factorisation.
    pub(crate) fn reset(&mut self) {
        self.operator = Matrix6::zeros();
        self.damping = 0.0;
        self.eigen_used = false;
    }
}

/// `J J^T`, exactly symmetric.
fn gram(j: &Matrix6xX<f64>) -> Matrix6<f64> {
    let mut out = Matrix6::zeros();
    for r in 0..6 {
        for c in r..6 {
            let v = j.row(r).dot(&j.row(c));
            out[(r, c)] = v;
            out[(c, r)] = v;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// A pseudo-random 6 x n Jacobian with prescribed singular values (columns beyond 6
    /// get none), `seed` choosing the bases.
    fn jacobian(n: usize, singular: [f64; 6], seed: u64) -> Matrix6xX<f64> {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let u = DMatrix::from_fn(6, 6, |_, _| next()).qr().q();
        let v = DMatrix::from_fn(n, n, |_, _| next()).qr().q();
        let mut s = DMatrix::zeros(6, n);
        for i in 0..6.min(n) {
            s[(i, i)] = singular[i];
        }
        let j = u * s * v.transpose();
        Matrix6xX::from_fn(n, |r, c| j[(r, c)])
    }

    fn operator_of(inverse: &DampedPseudoInverse) -> Matrix6<f64> {
        inverse.operator
    }

    #[test]
    fn the_cholesky_route_is_taken_only_without_damping_and_agrees_with_the_eigen_route() {
        let cfg = SingularityDampingConfig::default();
        let mut fast_taken = 0;
        for seed in 0..200 {
            let smallest = 0.02 + 0.003 * seed as f64;
            let j = jacobian(7, [smallest, 0.3, 0.5, 0.9, 1.4, 2.0], seed);
            let mut p = DampedPseudoInverse::new(7, [true; 6], &cfg).unwrap();
            p.factor(&j).unwrap();
            let mut e = DampedPseudoInverse::new(7, [true; 6], &cfg).unwrap();
            e.factor_eigen(&gram(&j)).unwrap();
            if !p.eigen_used {
                fast_taken += 1;
                // Only when no singular value is below the threshold.
                assert!(smallest >= cfg.threshold, "seed {seed}: s_min {smallest}");
                let (a, b) = (operator_of(&p), operator_of(&e));
                assert!(
                    (a - b).norm() <= 1e-10 * b.norm(),
                    "seed {seed}: {}",
                    (a - b).norm()
                );
            }
            assert_eq!(p.damping(), e.damping());
            assert_eq!(p.damping() > 0.0, smallest < cfg.threshold);
        }
        assert!(fast_taken > 100, "{fast_taken}");
    }

    #[test]
    fn the_gain_is_bounded_in_every_direction() {
        for (threshold, max_damping) in [(0.1, 0.1), (0.1, 0.02), (0.05, 0.2)] {
            let cfg = SingularityDampingConfig {
                threshold,
                max_damping,
            };
            let bound = threshold / f64::min(threshold, max_damping).powi(2);
            for smallest in [0.0, 1e-12, 1e-6, 0.01, 0.05, 0.099, 0.1, 0.3] {
                let j = jacobian(7, [smallest, 0.07, 0.5, 0.9, 1.4, 2.0], 3);
                let mut p = DampedPseudoInverse::new(7, [true; 6], &cfg).unwrap();
                p.factor(&j).unwrap();
                // The gain of J^#T is the largest singular value of P J.
                let pj = operator_of(&p) * &j;
                let gain = DMatrix::from_fn(6, 7, |r, c| pj[(r, c)])
                    .singular_values()
                    .max();
                assert!(
                    gain <= bound * (1.0 + 1e-9),
                    "{cfg:?}, s_min {smallest}: gain {gain} > {bound}"
                );
            }
        }
    }

    #[test]
    fn structural_zeros_and_axes_outside_the_task_get_no_weight() {
        // Three task axes (x, z, ry) on a 2-joint arm: rank 2.
        let mut j = jacobian(2, [0.5, 0.3, 0.0, 0.0, 0.0, 0.0], 9);
        for r in [1, 3, 5] {
            j.row_mut(r).fill(0.0);
        }
        let task = [true, false, true, false, true, false];
        let mut p =
            DampedPseudoInverse::new(2, task, &SingularityDampingConfig::default()).unwrap();
        p.factor(&j).unwrap();
        assert!(p.eigen_used);
        let op = operator_of(&p);
        for i in [1, 3, 5] {
            assert!(op
                .row(i)
                .iter()
                .chain(op.column(i).iter())
                .all(|v| *v == 0.0));
        }
        // J^# J is the identity on the joints (the arm's two joints are both reachable).
        let mut out = [0.0; 2];
        for c in 0..2 {
            let col: Vector6<f64> = j.column(c).into_owned();
            p.apply(&j, &col, &mut out);
            for (r, o) in out.iter().enumerate() {
                let expected = if r == c { 1.0 } else { 0.0 };
                assert!((o - expected).abs() < 1e-12, "{out:?}");
            }
        }
    }
}
