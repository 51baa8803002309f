//! The identification least squares over physically possible arms only (issue 30).
//!
//! The set is convex: a body is possible exactly when its pseudo-inertia `J` is positive
//! definite (`consistency.rs`; kept `margin` from singular) and, when a [`BodyExtent`] is
//! given, its mass at most a bound and spread no farther than a sphere (two linear bounds
//! on the parameters, `tr(J Q) >= 0` for the sphere's `Q`: Wensing et al. 2017's density
//! realizability), and each joint's rotor inertia,
//! viscous friction and friction curve are dissipative by linear bounds
//! (`JointTerms::is_physical`: `I_a >= 0`, `F_v >= 0`, and `10 F_c1 + F_c2 >= 0`,
//! `F_c1 + F_c2 >= 0`: exactly the friction curves that oppose the velocity at every speed).
//! The cost is quadratic, so the fit is a semidefinite least squares with one global
//! minimum, found by a barrier method (Boyd and Vandenberghe 2004, ch. 11): Newton's method
//! on `t f(x) - sum log det(J_b - margin) - sum log(bound)` for a growing `t`, from a
//! strictly possible start, until the duality gap `nu / t` is below a part in 1e7 of the
//! unconstrained fit's residual (and at most 1e-13 of the torques' sum of squares). Only the
//! last `t`'s centring is carried to full precision: the others only lead there, and a
//! rough centre serves them as well. Every iterate is strictly inside the set, so the result is
//! physical with nothing clipped afterwards: a bound that binds hands its share of the torque
//! to the other terms.

use nalgebra::{DMatrix, DVector, Matrix3, Matrix4, Vector3};

use crate::algorithms::regressor::PARAMETERS_PER_BODY;
use crate::identification::cholesky::cholesky;
use crate::identification::consistency::{margin, project, pseudo_inertia_of};
use crate::identification::joint_terms::JOINT_FEATURES;
use crate::identification::normal::{reduced_system, Normal};

/// Growth of `t` between centrings.
const T_GROWTH: f64 = 10.0;
/// Duality gap at which the method stops, relative to the unconstrained fit's sum of
/// squared residuals (a lower bound of the constrained one's), and at least this share of
/// the torques' sum of squares (noise-free data leave no residual to be relative to).
const GAP: f64 = 1e-7;
const GAP_FLOOR: f64 = 1e-13;
/// Newton steps in all (a cap: 86 to 127 were taken on the Baxter recording when every
/// centring was carried to full precision, about 70 on average since).
const MAX_NEWTON_STEPS: usize = 400;
/// Newton decrement (`lambda^2` of `t f + barrier`) at which the last `t`'s centring stops.
const FINAL_DECREMENT: f64 = 1e-7;
/// The same for the earlier `t`s, which only lead to the last: centring them to the last
/// one's precision took a third more Newton steps on the simulated Panda's 60 s at 4 Hz
/// (10,607 against 7,134) for the same fit (its expected false torque within 1e-9, relative).
const PATH_DECREMENT: f64 = 1.0;
/// Halvings of a step before the line search gives up.
const MAX_HALVINGS: usize = 60;

/// A body kept possible: its ten columns and the pseudo-inertia of each unit parameter.
struct Body {
    cols: [usize; PARAMETERS_PER_BODY],
    basis: [Matrix4<f64>; PARAMETERS_PER_BODY],
    margin: f64,
}

impl Body {
    fn new(cols: [usize; PARAMETERS_PER_BODY], margin: f64) -> Self {
        Body {
            cols,
            basis: std::array::from_fn(|k| {
                let mut e = [0.0; PARAMETERS_PER_BODY];
                e[k] = 1.0;
                pseudo_inertia_of(&e)
            }),
            margin,
        }
    }

    /// `J(x) - margin 1`.
    fn slack(&self, x: &DVector<f64>) -> Matrix4<f64> {
        let mut s = Matrix4::identity() * -self.margin;
        for (m, &c) in self.basis.iter().zip(&self.cols) {
            s += m * x[c];
        }
        s
    }
}

/// Where a body's mass may be: at most `max_mass` (kg), at a root-mean-square distance of
/// at most `radius` (m) from `centre` (m, the body's frame). Pseudo-inertia alone bounds
/// neither: fitted on a narrow recording, a link of the real Baxter took 3760 kg, and one
/// of the simulated Kinova 18 kg against its URDF's 0.99 (docs/experiments.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BodyExtent {
    pub max_mass: f64,
    pub centre: [f64; 3],
    pub radius: f64,
}

impl BodyExtent {
    /// Whether the body `p` (ten inertial parameters) ended at this extent: its mass within
    /// 1 % of the bound, or its mass's rms distance from the centre within 1 % of the radius.
    /// A body emptied to next to no mass (under 1 % of the bound) is not counted: the sphere
    /// then only holds the cone's margin, it is not what the data pushed against.
    pub(crate) fn reached(&self, p: &[f64; PARAMETERS_PER_BODY]) -> bool {
        let j = pseudo_inertia_of(p);
        let m = j[(3, 3)];
        if !(m > 0.01 * self.max_mass) {
            return false;
        }
        let c = Vector3::from(self.centre);
        // The mean square distance from c: (tr Sigma - 2 h.c + m |c|^2) / m.
        let h = Vector3::new(j[(0, 3)], j[(1, 3)], j[(2, 3)]);
        let trace = j[(0, 0)] + j[(1, 1)] + j[(2, 2)];
        let spread = (trace - 2.0 * h.dot(&c) + m * c.norm_squared()) / m;
        m >= 0.99 * self.max_mass || spread >= 0.99 * 0.99 * self.radius * self.radius
    }
}

/// An affine bound on one body's parameters, `sum coef * x[col] + constant > 0`.
struct ExtentRow {
    /// The body (index into `Set::bodies`).
    body: usize,
    terms: Vec<(usize, f64)>,
    constant: f64,
}

impl ExtentRow {
    fn value(&self, x: &DVector<f64>) -> f64 {
        self.constant + self.terms.iter().map(|&(c, v)| v * x[c]).sum::<f64>()
    }

    /// The two rows of `extent` for `body` (its sphere, then its mass).
    fn of(body: &Body, index: usize, extent: &BodyExtent) -> [ExtentRow; 2] {
        // tr(J Q) with Q = [-1/r^2 1, c/r^2; c^T/r^2, 1 - |c|^2/r^2] is the integral of
        // the density times (1 - |x - c|^2 / r^2): non-negative exactly when the mass's mean
        // square distance from c is at most r^2. Linear in J, so one row over the basis.
        let c = Vector3::from(extent.centre);
        let r2 = extent.radius * extent.radius;
        let mut q = Matrix4::zeros();
        q.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * (-1.0 / r2)));
        q.fixed_view_mut::<3, 1>(0, 3).copy_from(&(c / r2));
        q.fixed_view_mut::<1, 3>(3, 0)
            .copy_from(&(c.transpose() / r2));
        q[(3, 3)] = 1.0 - c.norm_squared() / r2;
        let sphere = (0..PARAMETERS_PER_BODY)
            .map(|k| (body.cols[k], (body.basis[k] * q).trace()))
            .collect();
        [
            ExtentRow {
                body: index,
                terms: sphere,
                constant: 0.0,
            },
            // The mass is the first parameter.
            ExtentRow {
                body: index,
                terms: vec![(body.cols[0], -1.0)],
                constant: extent.max_mass,
            },
        ]
    }
}

/// The physically possible set of the reduced problem's columns.
struct Set {
    bodies: Vec<Body>,
    /// Linear bounds `sum coef * x[col] > 0`.
    bounds: Vec<Vec<(usize, f64)>>,
    /// The bodies' extents.
    extents: Vec<ExtentRow>,
}

impl Set {
    /// For the active columns `idx` of an arm of `bodies` bodies: the bodies (those the
    /// prior gives mass) when `physical`, within `extents[b]` when given, joint terms always.
    fn new(
        idx: &[usize],
        bodies: usize,
        physical: bool,
        prior: &[f64],
        extents: &[BodyExtent],
    ) -> Self {
        let inertial = bodies * PARAMETERS_PER_BODY;
        let position = |col: usize| idx.iter().position(|&c| c == col);
        let mut set = Set {
            bodies: Vec::new(),
            bounds: Vec::new(),
            extents: Vec::new(),
        };
        for b in (0..bodies).filter(|_| physical) {
            let cols: Option<Vec<usize>> = (0..PARAMETERS_PER_BODY)
                .map(|k| position(b * PARAMETERS_PER_BODY + k))
                .collect();
            let Some(cols) = cols else { continue };
            let mut p = [0.0; PARAMETERS_PER_BODY];
            p.copy_from_slice(&prior[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY]);
            let body = Body::new(std::array::from_fn(|k| cols[k]), margin(&p));
            if let Some(extent) = extents.get(b) {
                set.extents
                    .extend(ExtentRow::of(&body, set.bodies.len(), extent));
            }
            set.bodies.push(body);
        }
        for (r, &col) in idx.iter().enumerate().filter(|(_, &c)| c >= inertial) {
            let feature = (col - inertial) % JOINT_FEATURES;
            match (feature, position(col + 1), position(col.wrapping_sub(1))) {
                (0 | 1, _, _) => set.bounds.push(vec![(r, 1.0)]),
                // The two Coulomb levels: 10 F_c1 + F_c2 and F_c1 + F_c2.
                (2, Some(second), _) => {
                    set.bounds.push(vec![(r, 10.0), (second, 1.0)]);
                    set.bounds.push(vec![(r, 1.0), (second, 1.0)]);
                }
                (2, None, _) | (3, _, None) => set.bounds.push(vec![(r, 1.0)]),
                _ => {}
            }
        }
        set
    }

    /// The barrier parameter: the sum of the cones' orders.
    fn order(&self) -> f64 {
        (4 * self.bodies.len() + self.bounds.len() + self.extents.len()) as f64
    }

    fn bound(row: &[(usize, f64)], x: &DVector<f64>) -> f64 {
        row.iter().map(|&(c, v)| v * x[c]).sum()
    }

    /// `-sum log det(slack) - sum log(bound)`; `None` outside the set's interior.
    fn barrier(&self, x: &DVector<f64>) -> Option<f64> {
        let mut sum = 0.0;
        for b in &self.bodies {
            let l = b.slack(x).cholesky()?.l();
            sum -= 2.0 * (0..4).map(|i| l[(i, i)].ln()).sum::<f64>();
        }
        for row in &self.bounds {
            let v = Self::bound(row, x);
            if !(v > 0.0) {
                return None;
            }
            sum -= v.ln();
        }
        for row in &self.extents {
            let v = row.value(x);
            if !(v > 0.0) {
                return None;
            }
            sum -= v.ln();
        }
        sum.is_finite().then_some(sum)
    }

    /// Adds the barrier's gradient and Hessian at `x` (inside the set).
    fn add_derivatives(
        &self,
        x: &DVector<f64>,
        grad: &mut DVector<f64>,
        hess: &mut DMatrix<f64>,
    ) -> Option<()> {
        for b in &self.bodies {
            let inv = b.slack(x).cholesky()?.inverse();
            let p: [Matrix4<f64>; PARAMETERS_PER_BODY] = std::array::from_fn(|k| inv * b.basis[k]);
            for k in 0..PARAMETERS_PER_BODY {
                grad[b.cols[k]] -= p[k].trace();
                for l in 0..=k {
                    let h = p[k].component_mul(&p[l].transpose()).sum();
                    hess[(b.cols[k], b.cols[l])] += h;
                    if l != k {
                        hess[(b.cols[l], b.cols[k])] += h;
                    }
                }
            }
        }
        for row in &self.bounds {
            let v = Self::bound(row, x);
            for &(c, a) in row {
                grad[c] -= a / v;
                for &(d, e) in row {
                    hess[(c, d)] += a * e / (v * v);
                }
            }
        }
        for row in &self.extents {
            let v = row.value(x);
            for &(c, a) in &row.terms {
                grad[c] -= a / v;
                for &(d, e) in &row.terms {
                    hess[(c, d)] += a * e / (v * v);
                }
            }
        }
        Some(())
    }

    /// A point strictly inside the set near `x`: each body's pseudo-inertia with its
    /// eigenvalues raised to twice the margin (or the prior's, when `x` gives the body no
    /// mass at all), each bound's columns raised to `floor` where the bound is not positive.
    fn interior_near(&self, x: &DVector<f64>, prior: &[f64], floor: &[f64]) -> DVector<f64> {
        let mut z = x.clone();
        for b in &self.bodies {
            let take = |v: &dyn Fn(usize) -> f64| -> [f64; PARAMETERS_PER_BODY] {
                std::array::from_fn(|k| v(b.cols[k]))
            };
            let p = project(&take(&|c| x[c]), 2.0 * b.margin)
                .or_else(|| project(&take(&|c| prior[c]), 2.0 * b.margin));
            if let Some(p) = p {
                b.cols.iter().zip(p).for_each(|(&c, v)| z[c] = v);
            }
        }
        // A body beyond its extent starts as the prior's (inside it: `body_extents`).
        for row in &self.extents {
            if row.value(&z) <= 0.0 {
                let b = &self.bodies[row.body];
                let at_prior: [f64; PARAMETERS_PER_BODY] =
                    std::array::from_fn(|k| prior[b.cols[k]]);
                if let Some(p) = project(&at_prior, 2.0 * b.margin) {
                    b.cols.iter().zip(p).for_each(|(&c, v)| z[c] = v);
                }
            }
        }
        for row in &self.bounds {
            if Self::bound(row, &z) <= 0.0 {
                // A single column, or the Coulomb pair: F_c2 at the floor and F_c1 within
                // [0, floor], so that both 10 F_c1 + F_c2 and F_c1 + F_c2 are positive.
                match row.as_slice() {
                    [(c, _)] => z[*c] = floor[*c],
                    [(first, _), (second, _)] => {
                        let f = floor[*first];
                        z[*first] = z[*first].max(0.0).min(f);
                        z[*second] = f;
                    }
                    _ => {}
                }
            }
        }
        z
    }
}

/// The minimiser of the ridge least squares over physically possible arms (bodies possible
/// when `physical`, each within `extents[b]` when given, joint terms always). Returns the
/// full solution vector (inactive columns, and bodies the URDF gives no mass, at the prior).
pub(crate) fn solve_physical(
    normal: &Normal,
    active: &[bool],
    prior: &DVector<f64>,
    ridge: f64,
    bodies: usize,
    physical: bool,
    extents: &[BodyExtent],
) -> Option<DVector<f64>> {
    // A massless prior body has no cone to be kept in: it stays at the prior.
    let mut active = active.to_vec();
    if physical {
        for b in 0..bodies {
            let rows = b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY;
            if !(prior[rows.start] > 0.0) {
                rows.for_each(|c| active[c] = false);
            }
        }
    }
    let (a, c, idx) = reduced_system(normal, &active, prior, ridge);
    let from_prior: Vec<f64> = idx.iter().map(|&col| prior[col]).collect();
    let set = Set::new(&idx, bodies, physical, &from_prior, extents);
    let x = minimise(&a, &c, &set, &from_prior, normal.yy)?;
    let mut full = prior.clone();
    for (r, &col) in idx.iter().enumerate() {
        full[col] = x[r];
    }
    full.iter().all(|v| v.is_finite()).then_some(full)
}

/// The body minimising `|r p - z|^2` over bodies whose pseudo-inertia is at least `margin`
/// from singular (the payload's fit); `start` a possible body, the fallback start when the
/// unconstrained answer has no positive mass distribution at all.
pub(crate) fn fit_possible_body(
    r: &DMatrix<f64>,
    z: &DVector<f64>,
    start: &[f64; PARAMETERS_PER_BODY],
    margin: f64,
) -> Option<[f64; PARAMETERS_PER_BODY]> {
    let set = Set {
        bodies: vec![Body::new(std::array::from_fn(|k| k), margin)],
        bounds: Vec::new(),
        extents: Vec::new(),
    };
    let a = r.transpose() * r;
    let c = r.transpose() * z;
    let x = minimise(&a, &c, &set, start, z.norm_squared())?;
    Some(std::array::from_fn(|k| x[k]))
}

/// The barrier method on `f(x) = x^T A x - 2 c^T x` over `set`; `yy` the torques' sum of
/// squares (the scale of `f`).
fn minimise(
    a: &DMatrix<f64>,
    c: &DVector<f64>,
    set: &Set,
    prior: &[f64],
    yy: f64,
) -> Option<DVector<f64>> {
    let free = cholesky(a.clone())?.solve(c);
    let f = |x: &DVector<f64>| x.dot(&(a * x)) - 2.0 * c.dot(x);
    // Already possible (strictly inside): the unconstrained minimum is the minimum.
    if set.barrier(&free).is_some() {
        return Some(free);
    }
    // A thousandth of what each column alone would explain: a negligible start.
    let floor: Vec<f64> = (0..c.len())
        .map(|i| 1e-3 * c[i].abs() / a[(i, i)].max(1e-300) + 1e-12)
        .collect();
    let mut x = set.interior_near(&free, prior, &floor);
    let mut phi = set.barrier(&x)?;
    let order = set.order();
    let gap = (GAP * (yy + f(&free)).max(0.0))
        .max(GAP_FLOOR * yy)
        .max(1e-300);
    // The unconstrained minimum bounds the constrained one from below: the start's excess
    // over it sets the first t.
    let excess = (f(&x) - f(&free)).max(gap);
    let mut t = order / excess;
    let mut steps = 0;
    // `A x`, carried along the steps (`A d` is needed for the step's curvature anyway).
    let mut ax = a * &x;
    loop {
        let last = order / t <= gap;
        let decrement_reached = if last {
            FINAL_DECREMENT
        } else {
            PATH_DECREMENT
        };
        // Centring: Newton on t f + barrier.
        while steps < MAX_NEWTON_STEPS {
            steps += 1;
            let mut grad = (&ax - c) * (2.0 * t);
            let mut hess = a * (2.0 * t);
            set.add_derivatives(&x, &mut grad, &mut hess)?;
            let Some(chol) = cholesky(hess) else { break };
            let d = -chol.solve(&grad);
            let decrement = -grad.dot(&d);
            if !(decrement > 1e-9) {
                break;
            }
            // The change of t f along the step, exactly (the cost is quadratic), and of
            // the barrier: differences never taken between two large totals.
            let ad = a * &d;
            let (slope, curve) = (2.0 * (&ax - c).dot(&d), d.dot(&ad));
            let mut alpha = 1.0;
            let mut accepted = false;
            for _ in 0..MAX_HALVINGS {
                let trial = &x + &d * alpha;
                if let Some(p) = set.barrier(&trial) {
                    let change = t * (alpha * slope + alpha * alpha * curve) + (p - phi);
                    if change <= -0.25 * alpha * decrement {
                        x = trial;
                        ax.axpy(alpha, &ad, 1.0);
                        phi = p;
                        accepted = true;
                        break;
                    }
                }
                alpha *= 0.5;
            }
            if !accepted || decrement < decrement_reached {
                break;
            }
        }
        if last || steps >= MAX_NEWTON_STEPS {
            break;
        }
        t *= T_GROWTH;
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::consistency::is_physically_consistent;
    use crate::identification::joint_terms::JointTerms;
    use crate::spatial::Inertia;
    use rand::{Rng, SeedableRng};

    const P: usize = PARAMETERS_PER_BODY + JOINT_FEATURES;

    /// Normal equations of random rows for one body and one joint, fitted to `truth`.
    fn normal_toward(truth: &[f64; P], seed: u64) -> Normal {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let w = DMatrix::from_fn(400, P, |_, _| rng.random_range(-1.0..1.0));
        let x = DVector::from_column_slice(truth);
        let y = &w * &x + DVector::from_fn(400, |_, _| rng.random_range(-0.01..0.01));
        Normal {
            gram: w.transpose() * &w,
            rhs: w.transpose() * &y,
            yy: y.norm_squared(),
            rows: 400,
        }
    }

    fn prior() -> DVector<f64> {
        let body = Inertia {
            mass: 1.0,
            first_moment: nalgebra::Vector3::new(0.1, 0.0, 0.0),
            rotational: nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(0.01, 0.02, 0.02)),
        };
        let mut p = DVector::zeros(P);
        p.rows_mut(0, PARAMETERS_PER_BODY)
            .copy_from_slice(&body.to_parameters());
        p
    }

    fn active() -> Vec<bool> {
        (0..P).map(|c| c < PARAMETERS_PER_BODY + 5).collect()
    }

    fn physical(x: &DVector<f64>) -> bool {
        let mut p = [0.0; PARAMETERS_PER_BODY];
        p.copy_from_slice(&x.as_slice()[..PARAMETERS_PER_BODY]);
        let terms = JointTerms::from_coefficients(&x.as_slice()[PARAMETERS_PER_BODY..], 0.01);
        is_physically_consistent(&Inertia::from_parameters(&p)) && terms.is_physical()
    }

    /// Random neighbours of `x` (each active column moved by up to 10^`decades` of its size)
    /// that are `inside` cost no less than `x`, to the method's gap; returns how many were.
    fn no_better_neighbour(
        normal: &Normal,
        x: &DVector<f64>,
        active: &[bool],
        inside: impl Fn(&DVector<f64>) -> bool,
        seed: u64,
        trials: usize,
        decades: std::ops::Range<f64>,
    ) -> usize {
        let cost = |x: &DVector<f64>| normal.squared_error(x);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut tried = 0;
        for _ in 0..trials {
            let scale = 10f64.powf(rng.random_range(decades.clone()));
            let mut y = x.clone();
            for c in (0..P).filter(|&c| active[c]) {
                y[c] += scale * rng.random_range(-1.0..1.0) * x[c].abs().max(1e-3);
            }
            if inside(&y) {
                tried += 1;
                assert!(
                    cost(&y) >= cost(x) - 1e-7 * normal.yy,
                    "{} < {}",
                    cost(&y),
                    cost(x)
                );
            }
        }
        tried
    }

    #[test]
    fn a_physical_least_squares_solution_is_returned_as_it_is() {
        let mut truth = [0.0; P];
        truth[..PARAMETERS_PER_BODY].copy_from_slice(&prior().as_slice()[..PARAMETERS_PER_BODY]);
        truth[PARAMETERS_PER_BODY..PARAMETERS_PER_BODY + 5]
            .copy_from_slice(&[0.3, 0.5, 0.2, 0.1, -0.4]);
        let normal = normal_toward(&truth, 1);
        let free =
            crate::identification::normal::solve(&normal, &active(), &prior(), 1e-9).unwrap();
        assert!(physical(&free));
        let x = solve_physical(&normal, &active(), &prior(), 1e-9, 1, true, &[]).unwrap();
        assert!((&x - &free).amax() < 1e-6 * free.amax(), "{x} vs {free}");
    }

    /// Data that want the body ten times heavier, its mass far out: the extent holds the
    /// mass at its bound and the mass's spread inside the sphere, and the fit is still the
    /// best within them (each bound binds; nothing is clipped).
    #[test]
    fn a_body_stays_within_its_extent() {
        let mut truth = [0.0; P];
        let heavy = Inertia {
            mass: 10.0,
            first_moment: nalgebra::Vector3::new(5.0, 0.0, 0.0),
            rotational: nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(0.2, 3.0, 3.0)),
        };
        truth[..PARAMETERS_PER_BODY].copy_from_slice(&heavy.to_parameters());
        truth[PARAMETERS_PER_BODY..PARAMETERS_PER_BODY + 5]
            .copy_from_slice(&[0.3, 0.5, 0.2, 0.1, -0.4]);
        let normal = normal_toward(&truth, 4);
        let (active, prior) = (active(), prior());
        let extent = BodyExtent {
            max_mass: 2.5,
            centre: [0.0; 3],
            radius: 0.3,
        };
        let unbounded = solve_physical(&normal, &active, &prior, 1e-9, 1, true, &[]).unwrap();
        assert!(unbounded[0] > 9.0, "{}", unbounded[0]);
        let x = solve_physical(&normal, &active, &prior, 1e-9, 1, true, &[extent]).unwrap();
        assert!(physical(&x), "{x}");
        let mut p = [0.0; PARAMETERS_PER_BODY];
        p.copy_from_slice(&x.as_slice()[..PARAMETERS_PER_BODY]);
        let body = Inertia::from_parameters(&p);
        assert!(body.mass <= 2.5 && body.mass > 2.4, "mass {}", body.mass);
        // The mean square distance of the mass from the joint, tr(I_o) / (2 m), within r^2.
        let spread = 0.5 * body.rotational.trace() / body.mass;
        assert!(spread <= 0.09 && spread > 0.085, "spread {spread}");
        assert!((body.first_moment / body.mass).norm() <= 0.3);
        assert!(extent.reached(&p));
        // Inside it, or emptied to next to no mass (the sphere then holds only the cone's
        // margin): not reached.
        let prior_body: [f64; PARAMETERS_PER_BODY] = std::array::from_fn(|k| prior[k]);
        assert!(!extent.reached(&prior_body));
        let emptied = Inertia {
            mass: 1e-4,
            first_moment: nalgebra::Vector3::zeros(),
            rotational: nalgebra::Matrix3::identity() * 1e-5,
        };
        assert!(!extent.reached(&emptied.to_parameters()));
        // Worse than the unbounded fit on these data, as it must be, and no feasible
        // neighbour is better.
        let cost = |x: &DVector<f64>| normal.squared_error(x);
        assert!(cost(&x) > cost(&unbounded));
        let inside = |y: &DVector<f64>| {
            let mut q = [0.0; PARAMETERS_PER_BODY];
            q.copy_from_slice(&y.as_slice()[..PARAMETERS_PER_BODY]);
            let b = Inertia::from_parameters(&q);
            physical(y) && b.mass <= 2.5 && 0.5 * b.rotational.trace() <= 0.09 * b.mass
        };
        let tried = no_better_neighbour(&normal, &x, &active, inside, 5, 20000, -7.0..-3.0);
        assert!(tried > 100, "only {tried} neighbours inside");
    }

    #[test]
    fn an_impossible_fit_becomes_the_best_possible_one() {
        // Negative rotor inertia and viscous friction, a friction curve that pushes, and a
        // body with negative mass: the free solution is impossible.
        let mut truth = [0.0; P];
        truth[..PARAMETERS_PER_BODY]
            .copy_from_slice(&[-0.5, 0.2, 0.1, 0.0, 0.01, 0.0, -0.02, 0.0, 0.0, 0.03]);
        truth[PARAMETERS_PER_BODY..PARAMETERS_PER_BODY + 5]
            .copy_from_slice(&[-0.3, -0.5, -0.2, 0.1, 0.4]);
        let normal = normal_toward(&truth, 2);
        let (active, prior) = (active(), prior());
        let free = crate::identification::normal::solve(&normal, &active, &prior, 1e-9).unwrap();
        assert!(!physical(&free));
        let x = solve_physical(&normal, &active, &prior, 1e-9, 1, true, &[]).unwrap();
        assert!(physical(&x), "{x}");
        // A convex problem: no possible point nearby is better (to the method's gap).
        let tried = no_better_neighbour(&normal, &x, &active, physical, 3, 4000, -6.0..-1.0);
        assert!(tried > 100, "only {tried} possible neighbours");
    }
}
