//! Composite-rigid-body algorithm: the joint-space inertia matrix M(q) (docs/method.md eq. 1).

use nalgebra::DMatrix;

use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;

/// `M(q)`, full and symmetric, into `data.mass_matrix`.
pub fn crba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
) -> Result<&'d DMatrix<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    update_joint_placements(model, data, q);
    crba_pass(model, data);
    Ok(&data.mass_matrix)
}

/// The CRBA on `data.joint_placements` as they are (already updated for `q`).
#[inline(always)]
pub(crate) fn crba_pass(model: &Model, data: &mut Data) {
    let n = model.nq();
    data.composite.copy_from_slice(&model.bodies);
    let m = data.mass_matrix.as_mut_slice();
    for i in (0..n).rev() {
        // Column i: the wrench needed to accelerate the composite body i..n at unit qddot_i,
        // carried back through the ancestors.
        let joint = &model.joints[i];
        let mut f = data.composite[i].mul_motion(&joint.motion_subspace());
        m[i * n + i] = joint.subspace_dot(&f);
        for j in (0..i).rev() {
            f = data.joint_placements[j + 1].act_force(&f);
            let value = model.joints[j].subspace_dot(&f);
            m[i * n + j] = value;
            m[j * n + i] = value;
        }
        if i > 0 {
            let moved = data.composite[i].transformed(&data.joint_placements[i]);
            data.composite[i - 1] = data.composite[i - 1].add(&moved);
        }
    }
}
