//! The identification least squares over physically possible bodies only: each body in
//! log-Cholesky coordinates (`consistency.rs`), the joint terms as they are, minimised by
//! Levenberg-Marquardt on the normal equations (the cost is quadratic in the parameters,
//! so each step needs only the Gram matrix, never the samples).

use nalgebra::{DMatrix, DVector};

use crate::algorithms::regressor::PARAMETERS_PER_BODY;
use crate::identification::consistency::{from_log_cholesky, margin, to_log_cholesky};
use crate::identification::normal::{reduced_system, Normal};

const MAX_ITERATIONS: usize = 300;
/// Finite-difference step of the log-Cholesky Jacobian.
const STEP: f64 = 1e-6;

/// The reduced quadratic `f(x) = x^T A x - 2 c^T x` on the active columns, ridge included.
struct Quadratic {
    a: DMatrix<f64>,
    c: DVector<f64>,
    yy: f64,
}

impl Quadratic {
    fn new(
        normal: &Normal,
        active: &[bool],
        prior: &DVector<f64>,
        ridge: f64,
    ) -> (Self, Vec<usize>) {
        let (a, c, idx) = reduced_system(normal, active, prior, ridge);
        (
            Quadratic {
                a,
                c,
                yy: normal.yy,
            },
            idx,
        )
    }

    fn cost(&self, x: &DVector<f64>) -> f64 {
        self.yy + x.dot(&(&self.a * x)) - 2.0 * self.c.dot(x)
    }
}

/// The free coordinates: log-Cholesky per body (bodies without one stay at the prior),
/// then the active joint-term columns.
struct Coordinates {
    /// Per body: where its coordinates start in `z` and its margin, or `None` (fixed).
    bodies: Vec<Option<(usize, f64)>>,
    z: DVector<f64>,
    first_joint: usize,
    len: usize,
}

impl Coordinates {
    fn to_x(&self, z: &DVector<f64>, fixed: &DVector<f64>) -> DVector<f64> {
        let mut x = fixed.clone();
        for (b, slot) in self.bodies.iter().enumerate() {
            if let Some((s, eps)) = *slot {
                let mut t = [0.0; PARAMETERS_PER_BODY];
                t.copy_from_slice(&z.as_slice()[s..s + PARAMETERS_PER_BODY]);
                x.rows_mut(b * PARAMETERS_PER_BODY, PARAMETERS_PER_BODY)
                    .copy_from_slice(&from_log_cholesky(&t, eps));
            }
        }
        let joints = x.len() - self.first_joint;
        let start = z.len() - joints;
        x.rows_mut(self.first_joint, joints)
            .copy_from(&z.rows(start, joints));
        x
    }

    /// `dx/dz` (the bodies' 10 x 10 blocks by central differences; identity for joints).
    fn jacobian(&self, z: &DVector<f64>) -> DMatrix<f64> {
        let joints = self.len - self.first_joint;
        let mut jac = DMatrix::zeros(self.len, z.len());
        for (b, slot) in self.bodies.iter().enumerate() {
            let Some((s, eps)) = *slot else { continue };
            for k in 0..PARAMETERS_PER_BODY {
                let mut t = [0.0; PARAMETERS_PER_BODY];
                t.copy_from_slice(&z.as_slice()[s..s + PARAMETERS_PER_BODY]);
                t[k] += STEP;
                let plus = from_log_cholesky(&t, eps);
                t[k] -= 2.0 * STEP;
                let minus = from_log_cholesky(&t, eps);
                for r in 0..PARAMETERS_PER_BODY {
                    jac[(b * PARAMETERS_PER_BODY + r, s + k)] = (plus[r] - minus[r]) / (2.0 * STEP);
                }
            }
        }
        let start = z.len() - joints;
        for j in 0..joints {
            jac[(self.first_joint + j, start + j)] = 1.0;
        }
        jac
    }
}

/// The minimiser over physically possible bodies, started from the prior (whose bodies
/// are physically possible, or projected onto that set first). Returns the full solution
/// vector (inactive columns at the prior).
pub(crate) fn solve_consistent(
    normal: &Normal,
    active: &[bool],
    prior: &DVector<f64>,
    ridge: f64,
    bodies: usize,
) -> Option<DVector<f64>> {
    let (quad, idx) = Quadratic::new(normal, active, prior, ridge);
    let inertial = bodies * PARAMETERS_PER_BODY;
    // Two starts: the prior, and the unconstrained solution with its bodies projected onto
    // the possible ones (near the optimum when the data agree with physics).
    let from_prior: DVector<f64> = DVector::from_fn(idx.len(), |r, _| prior[idx[r]]);
    let mut best: Option<(f64, Coordinates, DVector<f64>)> = None;
    let free = crate::identification::normal::solve(normal, active, prior, ridge)
        .map(|x| DVector::from_fn(idx.len(), |r, _| x[idx[r]]));
    for start in [Some(from_prior.clone()), free].into_iter().flatten() {
        let mut slots = Vec::with_capacity(bodies);
        let mut z0 = Vec::new();
        for b in 0..bodies {
            let mut p = [0.0; PARAMETERS_PER_BODY];
            p.copy_from_slice(
                &start.as_slice()[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY],
            );
            let mut prior_body = [0.0; PARAMETERS_PER_BODY];
            prior_body.copy_from_slice(
                &from_prior.as_slice()[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY],
            );
            // A body the prior cannot place (massless) stays at the prior.
            let eps = margin(&prior_body);
            match to_log_cholesky(&prior_body, eps).and(to_log_cholesky(&p, eps)) {
                Some(t) => {
                    slots.push(Some((z0.len(), eps)));
                    z0.extend_from_slice(&t);
                }
                None => slots.push(None),
            }
        }
        z0.extend_from_slice(&start.as_slice()[inertial..]);
        let coords = Coordinates {
            bodies: slots,
            z: DVector::from_vec(z0),
            first_joint: inertial,
            len: idx.len(),
        };
        let cost = quad.cost(&coords.to_x(&coords.z, &from_prior));
        if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, coords, from_prior.clone()));
        }
    }
    let (_, coords, start) = best?;
    let mut z = coords.z.clone();
    let mut x = coords.to_x(&z, &start);
    let mut cost = quad.cost(&x);
    let mut mu = 1e-3;
    for _ in 0..MAX_ITERATIONS {
        let jac = coords.jacobian(&z);
        let grad = jac.transpose() * (&quad.a * &x - &quad.c);
        let hess = jac.transpose() * &quad.a * &jac;
        let mut improved = false;
        for _ in 0..12 {
            let mut h = hess.clone();
            for i in 0..h.nrows() {
                h[(i, i)] += mu * hess[(i, i)].max(1e-12);
            }
            let Some(step) = h.cholesky().map(|c| c.solve(&grad)) else {
                mu *= 10.0;
                continue;
            };
            let trial = &z - step;
            let x_trial = coords.to_x(&trial, &start);
            let c_trial = quad.cost(&x_trial);
            if c_trial.is_finite() && c_trial < cost {
                let gain = cost - c_trial;
                z = trial;
                x = x_trial;
                improved = gain > 1e-12 * cost.abs().max(1e-300);
                cost = c_trial;
                mu = (mu / 3.0).max(1e-12);
                break;
            }
            mu *= 4.0;
        }
        if !improved {
            break;
        }
    }
    let mut full = prior.clone();
    for (r, &c) in idx.iter().enumerate() {
        full[c] = x[r];
    }
    full.iter().all(|v| v.is_finite()).then_some(full)
}
