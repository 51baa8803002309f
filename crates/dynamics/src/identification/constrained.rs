//! The identification least squares over physically possible arms only (issue 30): each
//! body in log-Cholesky coordinates (`consistency.rs`), and each joint's rotor inertia,
//! viscous friction and friction curve kept dissipative by bounds (`JointTerms::is_physical`:
//! `I_a >= 0`, `F_v >= 0`, a friction curve that opposes the velocity at every speed),
//! minimised together by a
//! projected Levenberg-Marquardt on the normal equations (the cost is quadratic in the
//! parameters, so each step needs only the Gram matrix, never the samples). The two Coulomb
//! levels live in the coordinates `t = 10 F_c1 + F_c2` and `u = F_c1 + F_c2`, both `>= 0`:
//! exactly the curves that oppose the velocity at every speed. The bounds are
//! part of the fit, not a clipping afterwards: a bound that binds hands its share of the
//! torque to the other terms.

use nalgebra::{DMatrix, DVector};

use crate::algorithms::regressor::PARAMETERS_PER_BODY;
use crate::identification::consistency::{from_log_cholesky, margin, to_log_cholesky};
use crate::identification::joint_terms::JOINT_FEATURES;
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
    fn cost(&self, x: &DVector<f64>) -> f64 {
        self.yy + x.dot(&(&self.a * x)) - 2.0 * self.c.dot(x)
    }
}

/// How one body's ten parameters are free.
#[derive(Clone, Copy)]
enum Body {
    /// Held at the prior (a massless prior body cannot be placed in log-Cholesky).
    Fixed,
    /// Physically possible by construction: log-Cholesky coordinates from `start` in `z`,
    /// with the body's margin.
    Consistent { start: usize, margin: f64 },
    /// The parameters themselves from `start` (the user turned consistency off).
    Linear { start: usize },
}

/// The free coordinates `z` of the reduced solution `x`: the bodies (see [`Body`]), then
/// the active joint columns. Joint coordinates are `x` itself except the two Coulomb
/// levels, whose coordinates are `t = 10 F_c1 + F_c2` (at the first) and `u = F_c1 + F_c2`
/// (at the second), so that every joint bound is `z >= 0`.
struct Coordinates {
    bodies: Vec<Body>,
    /// Per joint coordinate (from `first_joint_z`): for the second Coulomb level's (`u`),
    /// the coordinate of the first's (`t`).
    pair: Vec<Option<usize>>,
    /// Per coordinate of `z`: bounded below by zero.
    bounded: Vec<bool>,
    first_joint_x: usize,
    first_joint_z: usize,
    len: usize,
}

impl Coordinates {
    /// For the active columns `idx` (full column indices) of an arm of `bodies` bodies.
    fn new(idx: &[usize], bodies: usize, physical: bool, prior: &[f64]) -> (Self, usize) {
        let inertial = bodies * PARAMETERS_PER_BODY;
        let mut slots = Vec::with_capacity(bodies);
        let mut z_len = 0;
        for b in 0..bodies {
            let mut p = [0.0; PARAMETERS_PER_BODY];
            p.copy_from_slice(&prior[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY]);
            let slot = if !physical {
                Body::Linear { start: z_len }
            } else {
                let eps = margin(&p);
                match to_log_cholesky(&p, eps) {
                    Some(_) => Body::Consistent {
                        start: z_len,
                        margin: eps,
                    },
                    None => Body::Fixed,
                }
            };
            if !matches!(slot, Body::Fixed) {
                z_len += PARAMETERS_PER_BODY;
            }
            slots.push(slot);
        }
        let joint_cols: Vec<usize> = idx.iter().copied().filter(|&c| c >= inertial).collect();
        let first_joint_z = z_len;
        let mut pair = Vec::with_capacity(joint_cols.len());
        let mut bounded = vec![false; first_joint_z];
        for &c in &joint_cols {
            let feature = (c - inertial) % JOINT_FEATURES;
            // Rotor inertia, viscous and both Coulomb coordinates are bounded below by zero.
            bounded.push(feature < 4);
            pair.push(if feature == 3 {
                joint_cols
                    .iter()
                    .position(|&o| o == c - 1)
                    .map(|p| first_joint_z + p)
            } else {
                None
            });
        }
        let coords = Coordinates {
            bodies: slots,
            pair,
            bounded,
            first_joint_x: idx.len() - joint_cols.len(),
            first_joint_z,
            len: idx.len(),
        };
        (coords, first_joint_z + joint_cols.len())
    }

    /// The coordinates of the reduced solution `x`, projected onto the bounds; `None` when
    /// a body cannot be expressed (not physically possible).
    fn from_x(&self, x: &DVector<f64>, z_len: usize) -> Option<DVector<f64>> {
        let mut z = DVector::zeros(z_len);
        for (b, slot) in self.bodies.iter().enumerate() {
            let mut p = [0.0; PARAMETERS_PER_BODY];
            p.copy_from_slice(
                &x.as_slice()[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY],
            );
            match *slot {
                Body::Fixed => {}
                Body::Consistent { start, margin } => {
                    let t = to_log_cholesky(&p, margin)?;
                    z.rows_mut(start, PARAMETERS_PER_BODY).copy_from_slice(&t);
                }
                Body::Linear { start } => {
                    z.rows_mut(start, PARAMETERS_PER_BODY).copy_from_slice(&p);
                }
            }
        }
        for j in 0..self.pair.len() {
            z[self.first_joint_z + j] = x[self.first_joint_x + j];
        }
        for j in 0..self.pair.len() {
            if let Some(p) = self.pair[j] {
                let (c1, c2) = (x[self.x_of(p)], x[self.first_joint_x + j]);
                z[p] = 10.0 * c1 + c2;
                z[self.first_joint_z + j] = c1 + c2;
            }
        }
        self.project(&mut z);
        Some(z)
    }

    fn project(&self, z: &mut DVector<f64>) {
        for (v, &b) in z.iter_mut().zip(&self.bounded) {
            if b && *v < 0.0 {
                *v = 0.0;
            }
        }
    }

    fn to_x(&self, z: &DVector<f64>, fixed: &DVector<f64>) -> DVector<f64> {
        let mut x = fixed.clone();
        for (b, slot) in self.bodies.iter().enumerate() {
            let rows = b * PARAMETERS_PER_BODY;
            match *slot {
                Body::Fixed => {}
                Body::Consistent { start, margin } => {
                    let mut t = [0.0; PARAMETERS_PER_BODY];
                    t.copy_from_slice(&z.as_slice()[start..start + PARAMETERS_PER_BODY]);
                    x.rows_mut(rows, PARAMETERS_PER_BODY)
                        .copy_from_slice(&from_log_cholesky(&t, margin));
                }
                Body::Linear { start } => {
                    x.rows_mut(rows, PARAMETERS_PER_BODY)
                        .copy_from(&z.rows(start, PARAMETERS_PER_BODY));
                }
            }
        }
        for j in 0..self.pair.len() {
            x[self.first_joint_x + j] = z[self.first_joint_z + j];
        }
        for (j, pair) in self.pair.iter().enumerate() {
            if let Some(p) = *pair {
                let (t, u) = (z[p], z[self.first_joint_z + j]);
                x[self.x_of(p)] = (t - u) / 9.0;
                x[self.first_joint_x + j] = (10.0 * u - t) / 9.0;
            }
        }
        x
    }

    /// The row of `x` of joint coordinate `z` index `zi`.
    fn x_of(&self, zi: usize) -> usize {
        self.first_joint_x + (zi - self.first_joint_z)
    }

    /// `dx/dz` (the consistent bodies' 10 x 10 blocks by central differences).
    fn jacobian(&self, z: &DVector<f64>) -> DMatrix<f64> {
        let mut jac = DMatrix::zeros(self.len, z.len());
        for (b, slot) in self.bodies.iter().enumerate() {
            let rows = b * PARAMETERS_PER_BODY;
            match *slot {
                Body::Fixed => {}
                Body::Linear { start } => {
                    for k in 0..PARAMETERS_PER_BODY {
                        jac[(rows + k, start + k)] = 1.0;
                    }
                }
                Body::Consistent { start, margin } => {
                    for k in 0..PARAMETERS_PER_BODY {
                        let mut t = [0.0; PARAMETERS_PER_BODY];
                        t.copy_from_slice(&z.as_slice()[start..start + PARAMETERS_PER_BODY]);
                        t[k] += STEP;
                        let plus = from_log_cholesky(&t, margin);
                        t[k] -= 2.0 * STEP;
                        let minus = from_log_cholesky(&t, margin);
                        for r in 0..PARAMETERS_PER_BODY {
                            jac[(rows + r, start + k)] = (plus[r] - minus[r]) / (2.0 * STEP);
                        }
                    }
                }
            }
        }
        for j in 0..self.pair.len() {
            jac[(self.first_joint_x + j, self.first_joint_z + j)] = 1.0;
        }
        for (j, pair) in self.pair.iter().enumerate() {
            if let Some(p) = *pair {
                let (xt, xu, zu) = (self.x_of(p), self.first_joint_x + j, self.first_joint_z + j);
                jac[(xt, p)] = 1.0 / 9.0;
                jac[(xt, zu)] = -1.0 / 9.0;
                jac[(xu, p)] = -1.0 / 9.0;
                jac[(xu, zu)] = 10.0 / 9.0;
            }
        }
        jac
    }
}

/// The minimiser over physically possible arms (bodies possible when `physical`, joint
/// terms always), started from the prior and from the unconstrained solution projected
/// onto the possible set. Returns the full solution vector (inactive columns at the prior).
pub(crate) fn solve_physical(
    normal: &Normal,
    active: &[bool],
    prior: &DVector<f64>,
    ridge: f64,
    bodies: usize,
    physical: bool,
) -> Option<DVector<f64>> {
    let (a, c, idx) = reduced_system(normal, active, prior, ridge);
    let quad = Quadratic {
        a,
        c,
        yy: normal.yy,
    };
    let from_prior: DVector<f64> = DVector::from_fn(idx.len(), |r, _| prior[idx[r]]);
    let (coords, z_len) = Coordinates::new(&idx, bodies, physical, from_prior.as_slice());
    let free = crate::identification::normal::solve(normal, active, prior, ridge)
        .map(|x| DVector::from_fn(idx.len(), |r, _| x[idx[r]]));
    let mut best: Option<(f64, DVector<f64>)> = None;
    for start in [Some(from_prior.clone()), free].into_iter().flatten() {
        // A start's impossible bodies are projected onto the possible set.
        let Some(z) = coords.from_x(&start, z_len) else {
            continue;
        };
        let cost = quad.cost(&coords.to_x(&z, &from_prior));
        if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, z));
        }
    }
    let (mut cost, mut z) = best?;
    let mut x = coords.to_x(&z, &from_prior);
    let mut mu = 1e-3;
    for _ in 0..MAX_ITERATIONS {
        let jac = coords.jacobian(&z);
        let mut grad = jac.transpose() * (&quad.a * &x - &quad.c);
        let hess = jac.transpose() * &quad.a * &jac;
        // Coordinates at their bound whose gradient pushes them out are held this step.
        let held: Vec<bool> = (0..z.len())
            .map(|i| coords.bounded[i] && z[i] <= 0.0 && grad[i] > 0.0)
            .collect();
        for (i, &h) in held.iter().enumerate() {
            if h {
                grad[i] = 0.0;
            }
        }
        let mut improved = false;
        for _ in 0..12 {
            let mut h = hess.clone();
            for i in 0..h.nrows() {
                if held[i] {
                    h.row_mut(i).fill(0.0);
                    h.column_mut(i).fill(0.0);
                    h[(i, i)] = 1.0;
                } else {
                    h[(i, i)] += mu * hess[(i, i)].max(1e-12);
                }
            }
            let Some(step) = h.cholesky().map(|c| c.solve(&grad)) else {
                mu *= 10.0;
                continue;
            };
            let mut trial = &z - step;
            coords.project(&mut trial);
            let x_trial = coords.to_x(&trial, &from_prior);
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
    for (r, &col) in idx.iter().enumerate() {
        full[col] = x[r];
    }
    full.iter().all(|v| v.is_finite()).then_some(full)
}
