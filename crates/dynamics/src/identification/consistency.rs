//! Physical consistency of inertial parameters: a body is physically possible exactly when
//! its pseudo-inertia matrix
//!
//! ```text
//!   J = [ Sigma  h ]      Sigma = tr(I_o) / 2 * 1 - I_o,  h = m c
//!       [ h^T    m ]
//! ```
//!
//! is positive definite (Wensing et al. 2017): positive mass, positive definite rotational
//! inertia about the centre of mass, and the triangle inequalities of its principal moments.
//! Least squares knows none of this, so the fitted bodies are projected onto that set.

use nalgebra::{Matrix3, Matrix4, Vector3};

use crate::algorithms::regressor::PARAMETERS_PER_BODY;
use crate::spatial::Inertia;

/// Smallest eigenvalue kept in the pseudo-inertia, relative to its largest (a body may
/// be thin, never flat or massless).
const MIN_RELATIVE_EIGENVALUE: f64 = 1e-6;

fn pseudo_inertia(b: &Inertia) -> Matrix4<f64> {
    let sigma = Matrix3::identity() * (0.5 * b.rotational.trace()) - b.rotational;
    let mut j = Matrix4::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&sigma);
    j.fixed_view_mut::<3, 1>(0, 3).copy_from(&b.first_moment);
    j.fixed_view_mut::<1, 3>(3, 0).copy_from(&b.first_moment.transpose());
    j[(3, 3)] = b.mass;
    j
}

fn from_pseudo_inertia(j: &Matrix4<f64>) -> Inertia {
    let sigma: Matrix3<f64> = j.fixed_view::<3, 3>(0, 0).into_owned();
    Inertia {
        mass: j[(3, 3)],
        first_moment: Vector3::new(j[(0, 3)], j[(1, 3)], j[(2, 3)]),
        rotational: Matrix3::identity() * sigma.trace() - sigma,
    }
}

/// Whether the body is physically possible (its pseudo-inertia positive definite with
/// eigenvalues above the relative floor).
pub fn is_physically_consistent(b: &Inertia) -> bool {
    let e = pseudo_inertia(b).symmetric_eigenvalues();
    let max = e.max();
    max > 0.0 && e.min() >= MIN_RELATIVE_EIGENVALUE * max * 0.999
}

/// The nearest physically possible body (in the pseudo-inertia's Frobenius norm): its
/// eigenvalues raised to the floor. `None` when nothing positive is left to keep (the fit
/// gave a body with no positive mass distribution at all).
pub(crate) fn project(p: &[f64; PARAMETERS_PER_BODY]) -> Option<[f64; PARAMETERS_PER_BODY]> {
    let j = pseudo_inertia(&Inertia::from_parameters(p));
    let eig = j.symmetric_eigen();
    let max = eig.eigenvalues.max();
    if !(max > 0.0) {
        return None;
    }
    let floor = MIN_RELATIVE_EIGENVALUE * max;
    let clamped = eig.eigenvalues.map(|e| e.max(floor));
    let j = eig.eigenvectors * Matrix4::from_diagonal(&clamped) * eig.eigenvectors.transpose();
    Some(from_pseudo_inertia(&(0.5 * (j + j.transpose()))).to_parameters())
}
