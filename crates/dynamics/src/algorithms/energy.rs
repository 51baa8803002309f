//! Kinetic and potential energy, for integrator and conservation checks.

// Joint index addresses several parallel per-joint arrays; read clearest indexed.
#![allow(clippy::needless_range_loop)]

use crate::algorithms::{update_body_placements, update_joint_placements};
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;
use crate::spatial::Motion;

/// Kinetic energy `1/2 v^T M(q) v` (J).
pub fn kinetic_energy(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<f64, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    update_joint_placements(model, data, q);
    let mut parent = Motion::zero();
    let mut energy = 0.0;
    for i in 0..n {
        let vi = data.joint_placements[i].act_inv_motion(&parent)
            + model.joints[i].motion_subspace().scaled(v[i]);
        energy += model.bodies[i].kinetic_energy(&vi);
        parent = vi;
    }
    Ok(energy)
}

/// Potential energy in the model's gravity field, zero at the base origin (J).
pub fn potential_energy(model: &Model, data: &mut Data, q: &[f64]) -> Result<f64, DimensionError> {
    check_len("q", q, model.nq())?;
    update_joint_placements(model, data, q);
    update_body_placements(data);
    let mut energy = 0.0;
    for (body, o) in model.bodies.iter().zip(&data.body_placements) {
        let world_first_moment = o.rotation * body.first_moment + o.translation * body.mass;
        energy -= model.gravity.dot(&world_first_moment);
    }
    Ok(energy)
}
