//! The implicit velocity update shared by both integrators.
//!
//! Friction (and environment damping) is a diagonal, monotone, velocity-dependent torque
//! `phi(v)`, stiff when the Coulomb term's slope `Fc / v_s` is large against a light
//! joint's inertia (docs/method.md section 7). The update evaluates it at the *new* velocity
//! (backward Euler in the dissipative term):
//!
//! ```text
//! A dv + h phi(v + dv) = h r        A = M(q) + M_E (SPD), r = everything else
//! ```
//!
//! which is the stationarity condition of the strictly convex function
//! `1/2 dv^T A dv + h sum_i P_i(v_i + dv_i) - h r^T dv` (`P_i' = phi_i`), so it has exactly
//! one solution. It is found by Newton's method on the residual
//! `g(dv) = A dv + h (phi(v + dv) - r)` with Jacobian `A + h diag(phi'(v + dv))` (SPD,
//! factored by an in-place Cholesky), started at `dv = 0`: the first Newton step is the
//! classic linearisation `(A + h dphi/dv) dv = h (r - phi(v))`. A backtracking line search
//! on `|g|^2` keeps it convergent where the linearisation alone overshoots (far from
//! `v = 0` the tanh is flat, the linearised step is explicit and can jump across zero
//! into a limit cycle; the line search stops that). Without Coulomb terms the system is
//! linear and one solve is exact.

// Parallel per-joint arrays read clearest indexed.
#![allow(clippy::needless_range_loop)]

use crate::plant::friction::Friction;
use crate::plant::linalg::SpdSystem;

/// Newton iteration cap; the line search makes every iteration decrease `|g|`.
pub(crate) const MAX_ITERATIONS: u32 = 60;
/// Halvings tried by the line search before giving up (the current iterate is then
/// accurate to rounding).
const MAX_HALVINGS: u32 = 60;
/// The default [`ImplicitSolver::set_step_tolerance`]: Newton stops once a step is at most
/// this fraction of the velocity scale `max(1, |v + dv|)` (rad/s).
pub(crate) const DEFAULT_STEP_TOLERANCE: f64 = 1e-12;

/// Outcome of one implicit solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct SolveReport {
    /// Newton iterations taken (1 for a linear system).
    pub iterations: u32,
    /// Whether the matrix factored (false: non-finite or non-SPD state; `dv` is zero).
    pub ok: bool,
}

/// Preallocated workspace of the implicit velocity update.
#[derive(Clone, Debug)]
pub(crate) struct ImplicitSolver {
    n: usize,
    sys: SpdSystem,
    g: Vec<f64>,
    g_trial: Vec<f64>,
    /// `phi'` at the current iterate and at the trial point.
    slope: Vec<f64>,
    slope_trial: Vec<f64>,
    /// `phi(v + dv)` at the current iterate and at the trial point.
    torque: Vec<f64>,
    torque_trial: Vec<f64>,
    /// Whether `torque` holds `phi(v + dv)` at the last solve's result.
    torque_valid: bool,
    delta: Vec<f64>,
    trial: Vec<f64>,
    /// Newton stops once a step is at most this times the velocity scale.
    step_tolerance: f64,
    /// Newton stops after this many iterations (1: the linearised update).
    max_iterations: u32,
}

impl ImplicitSolver {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            sys: SpdSystem::new(n),
            g: vec![0.0; n],
            g_trial: vec![0.0; n],
            slope: vec![0.0; n],
            slope_trial: vec![0.0; n],
            torque: vec![0.0; n],
            torque_trial: vec![0.0; n],
            torque_valid: false,
            delta: vec![0.0; n],
            trial: vec![0.0; n],
            step_tolerance: DEFAULT_STEP_TOLERANCE,
            max_iterations: MAX_ITERATIONS,
        }
    }

    /// At most `count` (>= 1) Newton iterations per solve (the plant's `friction_solve`).
    pub(crate) fn set_max_iterations(&mut self, count: u32) {
        self.max_iterations = count.clamp(1, MAX_ITERATIONS);
    }

    /// Newton stops once a step is at most `tol` times the velocity scale (the plant's
    /// `newton_tolerance`). Near the solution the error after a step is about the square of
    /// the step's, so a step of `tol` leaves an error of order `tol^2`.
    pub(crate) fn set_step_tolerance(&mut self, tol: f64) {
        self.step_tolerance = tol;
    }

    /// `phi(v + dv)` at the last solve's `dv`, when that solve was nonlinear and succeeded
    /// (the same values as evaluating the law again, without the tanh).
    pub(crate) fn last_torque(&self) -> Option<&[f64]> {
        self.torque_valid.then_some(&self.torque[..])
    }

    /// Solves `A dv + h phi(v + dv) = h r` for `dv` (`a` row-major `n x n`, SPD).
    pub(crate) fn solve(
        &mut self,
        a: &[f64],
        v: &[f64],
        h: f64,
        r: &[f64],
        phi: &[Friction],
        dv: &mut [f64],
    ) -> SolveReport {
        match self.n {
            7 => self.solve_n::<7>(a, v, h, r, phi, dv),
            6 => self.solve_n::<6>(a, v, h, r, phi, dv),
            _ => self.solve_n::<0>(a, v, h, r, phi, dv),
        }
    }

    /// [`Self::solve`] with the size a constant (`N > 0`: the loops unroll, the bounds
    /// checks fold away) or `self.n` (`N = 0`); the same operations either way.
    #[inline(always)]
    fn solve_n<const N: usize>(
        &mut self,
        a: &[f64],
        v: &[f64],
        h: f64,
        r: &[f64],
        phi: &[Friction],
        dv: &mut [f64],
    ) -> SolveReport {
        let n = if N > 0 { N } else { self.n };
        self.torque_valid = false;
        let (a, v, r, phi) = (&a[..n * n], &v[..n], &r[..n], &phi[..n]);
        let dv = &mut dv[..n];
        let nonlinear = phi.iter().any(|f| f.coulomb != 0.0);
        if !nonlinear {
            // Linear: (A + h Fv) dv = h (r - Fv v).
            let m = self.sys.matrix_mut();
            m.copy_from_slice(&a[..n * n]);
            for i in 0..n {
                m[i * n + i] += h * phi[i].viscous;
                dv[i] = h * (r[i] - phi[i].viscous * v[i]);
            }
            if !self.sys.factor() {
                dv[..n].fill(0.0);
                return SolveReport {
                    iterations: 1,
                    ok: false,
                };
            }
            self.sys.solve_in_place(dv);
            return SolveReport {
                iterations: 1,
                ok: true,
            };
        }

        dv[..n].fill(0.0);
        let mut gnorm2 = residual_at_zero(
            n,
            v,
            h,
            r,
            phi,
            &mut self.g,
            &mut self.slope,
            &mut self.torque,
        );
        let g0 = gnorm2.sqrt();
        let mut iterations = 0;
        while iterations < self.max_iterations {
            iterations += 1;
            // Newton direction: (A + h diag phi') delta = -g.
            let m = self.sys.matrix_mut();
            m.copy_from_slice(&a[..n * n]);
            for i in 0..n {
                m[i * n + i] += h * self.slope[i];
                self.delta[i] = -self.g[i];
            }
            if !self.sys.factor() {
                dv[..n].fill(0.0);
                return SolveReport {
                    iterations,
                    ok: false,
                };
            }
            self.sys.solve_in_place(&mut self.delta);
            // Backtracking on |g|^2 (Newton's direction is a descent direction for it
            // because the Jacobian is SPD).
            let mut alpha = 1.0;
            let mut accepted = false;
            for _ in 0..MAX_HALVINGS {
                for i in 0..n {
                    self.trial[i] = dv[i] + alpha * self.delta[i];
                }
                let trial_norm2 = residual(
                    n,
                    a,
                    v,
                    h,
                    r,
                    phi,
                    &self.trial,
                    &mut self.g_trial,
                    &mut self.slope_trial,
                    &mut self.torque_trial,
                );
                if trial_norm2 <= (1.0 - 1e-4 * alpha) * gnorm2 {
                    dv[..n].copy_from_slice(&self.trial);
                    std::mem::swap(&mut self.g, &mut self.g_trial);
                    std::mem::swap(&mut self.slope, &mut self.slope_trial);
                    std::mem::swap(&mut self.torque, &mut self.torque_trial);
                    gnorm2 = trial_norm2;
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !accepted {
                // No decrease possible: the iterate is a solution to rounding.
                break;
            }
            let step = self.delta.iter().fold(0.0_f64, |m, d| m.max(d.abs())) * alpha;
            let scale = dv
                .iter()
                .zip(v)
                .fold(1.0_f64, |m, (d, v)| m.max((v + d).abs()));
            if step <= self.step_tolerance * scale || gnorm2.sqrt() <= 1e-14 * g0 {
                break;
            }
        }
        self.torque_valid = true;
        SolveReport {
            iterations,
            ok: true,
        }
    }
}

/// `g = A dv + h (phi(v + dv) - r)`, `slope = phi'(v + dv)` and `torque = phi(v + dv)`;
/// returns `|g|^2`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn residual(
    n: usize,
    a: &[f64],
    v: &[f64],
    h: f64,
    r: &[f64],
    phi: &[Friction],
    dv: &[f64],
    g: &mut [f64],
    slope: &mut [f64],
    torque: &mut [f64],
) -> f64 {
    let (a, v, r, phi, dv) = (&a[..n * n], &v[..n], &r[..n], &phi[..n], &dv[..n]);
    let (g, slope, torque) = (&mut g[..n], &mut slope[..n], &mut torque[..n]);
    let mut norm2 = 0.0;
    for i in 0..n {
        let row = &a[i * n..i * n + n];
        let mut s = 0.0;
        for (aij, dj) in row.iter().zip(dv) {
            s += aij * dj;
        }
        let (f, df) = phi[i].torque_and_slope(v[i] + dv[i]);
        let gi = s + h * (f - r[i]);
        g[i] = gi;
        slope[i] = df;
        torque[i] = f;
        norm2 += gi * gi;
    }
    norm2
}

/// [`residual`] at `dv = 0` without the product `A dv`. For a finite `A` that sum is `+0`
/// (the terms are signed zeros added to `+0`), so `0.0 + h (phi(v + 0.0) - r)` is the same
/// value bit for bit (`v + 0.0` too: it turns `-0` into `+0` as `v + dv` does); a non-finite
/// `A` fails the factorisation that follows either way.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn residual_at_zero(
    n: usize,
    v: &[f64],
    h: f64,
    r: &[f64],
    phi: &[Friction],
    g: &mut [f64],
    slope: &mut [f64],
    torque: &mut [f64],
) -> f64 {
    let (v, r, phi) = (&v[..n], &r[..n], &phi[..n]);
    let (g, slope, torque) = (&mut g[..n], &mut slope[..n], &mut torque[..n]);
    let mut norm2 = 0.0;
    for i in 0..n {
        let (f, df) = phi[i].torque_and_slope(v[i] + 0.0);
        let gi = 0.0 + h * (f - r[i]);
        g[i] = gi;
        slope[i] = df;
        torque[i] = f;
        norm2 += gi * gi;
    }
    norm2
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar case that defeats a single linearised step: a light joint moving fast
    /// with a sharp Coulomb term. The solution must satisfy the implicit equation and
    /// not overshoot through zero.
    #[test]
    fn scalar_coulomb_converges_without_overshoot() {
        let mut s = ImplicitSolver::new(1);
        let phi = [Friction {
            viscous: 0.0,
            coulomb: 0.5,
            v_s: 0.01,
        }];
        let (m, h) = (6e-4, 2e-4);
        let mut v = 0.1;
        for _ in 0..200 {
            let mut dv = [0.0];
            let rep = s.solve(&[m], &[v], h, &[0.0], &phi, &mut dv);
            assert!(rep.ok && rep.iterations < MAX_ITERATIONS);
            let g = m * dv[0] + h * phi[0].torque(v + dv[0]);
            assert!(g.abs() < 1e-12, "residual {g}");
            // Backward Euler on a monotone friction law never reverses the velocity.
            assert!((v + dv[0]) * v >= 0.0, "{v} -> {}", v + dv[0]);
            v += dv[0];
        }
        assert!(v.abs() < 1e-6, "{v}");
    }

    /// The residual at zero without `A dv` equals the full one bit for bit, signed zeros
    /// included.
    #[test]
    fn residual_at_zero_equals_the_full_residual() {
        let n = 3;
        let a = [2.0, -0.5, 0.1, -0.5, 1.0, -0.2, 0.1, -0.2, 0.7];
        let phi = [
            Friction {
                viscous: 0.3,
                coulomb: 0.1,
                v_s: 0.01,
            },
            Friction::NONE,
            Friction {
                viscous: 0.0,
                coulomb: 2.0,
                v_s: 0.05,
            },
        ];
        for (v, r) in [
            ([0.3, -0.2, 0.004], [1.0, -2.0, 0.5]),
            ([0.0, -0.0, 0.0], [0.0, -0.0, -0.0]),
            ([-0.0, 0.0, -0.0], [-0.0, 0.0, 0.0]),
        ] {
            let mut full = ([0.0; 3], [0.0; 3], [0.0; 3]);
            let mut zero = ([0.0; 3], [0.0; 3], [0.0; 3]);
            let n_full = residual(
                n,
                &a,
                &v,
                2e-4,
                &r,
                &phi,
                &[0.0; 3],
                &mut full.0,
                &mut full.1,
                &mut full.2,
            );
            let n_zero =
                residual_at_zero(n, &v, 2e-4, &r, &phi, &mut zero.0, &mut zero.1, &mut zero.2);
            assert_eq!(n_full.to_bits(), n_zero.to_bits());
            for i in 0..n {
                assert_eq!(
                    full.0[i].to_bits(),
                    zero.0[i].to_bits(),
                    "g[{i}] at v {v:?}"
                );
                assert_eq!(full.1[i].to_bits(), zero.1[i].to_bits());
                assert_eq!(full.2[i].to_bits(), zero.2[i].to_bits());
            }
        }
    }

    #[test]
    fn linear_case_is_exact() {
        let mut s = ImplicitSolver::new(2);
        let a = [2.0, 0.5, 0.5, 1.0];
        let phi = [
            Friction {
                viscous: 3.0,
                coulomb: 0.0,
                v_s: 0.01,
            },
            Friction::NONE,
        ];
        let (v, r, h) = ([1.0, -1.0], [0.3, 0.7], 0.01);
        let mut dv = [0.0; 2];
        s.solve(&a, &v, h, &r, &phi, &mut dv);
        for i in 0..2 {
            let g =
                a[2 * i] * dv[0] + a[2 * i + 1] * dv[1] + h * (phi[i].torque(v[i] + dv[i]) - r[i]);
            assert!(g.abs() < 1e-15);
        }
    }
}
