//! The true lumped function of a model, the reference of experiment C.

use admittance_dynamics::{coriolis_matrix, crba, gravity_torque, Data, DimensionError, Model};

/// The "true" lumped function of docs/method.md section 3 / experiment C for a model:
/// `out = M(q) alpha' + C(q, q') alpha + G(q)` (Christoffel-form `C`; no friction).
/// Uses `data` as workspace; does not allocate.
pub fn true_lumped_f(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qdot: &[f64],
    alpha: &[f64],
    alpha_dot: &[f64],
    out: &mut [f64],
) -> Result<(), DimensionError> {
    let n = model.nq();
    for (argument, v) in [("alpha", alpha), ("alpha_dot", alpha_dot), ("out", &*out)] {
        if v.len() != n {
            return Err(DimensionError {
                argument,
                expected: n,
                found: v.len(),
            });
        }
    }
    let m = crba(model, data, q)?;
    for (i, o) in out.iter_mut().enumerate() {
        *o = (0..n).map(|j| m[(i, j)] * alpha_dot[j]).sum();
    }
    let c = coriolis_matrix(model, data, q, qdot)?;
    for (i, o) in out.iter_mut().enumerate() {
        *o += (0..n).map(|j| c[(i, j)] * alpha[j]).sum::<f64>();
    }
    let g = gravity_torque(model, data, q)?;
    for (o, gi) in out.iter_mut().zip(g.iter()) {
        *o += gi;
    }
    Ok(())
}
