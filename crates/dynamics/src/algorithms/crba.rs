//! Composite-rigid-body algorithm: the joint-space inertia matrix M(q) (METHOD.md eq. 1).

use nalgebra::DMatrix;

use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;

/// `M(q)`, full and symmetric, into `data.mass_matrix`.
pub fn crba<'d>(model: &Model, data: &'d mut Data, q: &[f64]) -> Result<&'d DMatrix<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    update_joint_placements(model, data, q);
    data.composite.copy_from_slice(&model.bodies);
    for i in (0..n).rev() {
        // Column i: the wrench needed to accelerate the composite body i..n at unit qddot_i,
        // carried back through the ancestors.
        let si = model.joints[i].motion_subspace();
        let mut f = data.composite[i].mul_motion(&si);
        data.mass_matrix[(i, i)] = f.dot(&si);
        for j in (0..i).rev() {
            f = data.joint_placements[j + 1].act_force(&f);
            let value = f.dot(&model.joints[j].motion_subspace());
            data.mass_matrix[(j, i)] = value;
            data.mass_matrix[(i, j)] = value;
        }
        if i > 0 {
            let moved = data.composite[i].transformed(&data.joint_placements[i]);
            data.composite[i - 1] = data.composite[i - 1].add(&moved);
        }
    }
    Ok(&data.mass_matrix)
}
