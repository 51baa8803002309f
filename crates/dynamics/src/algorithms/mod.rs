//! One algorithm per file, each a free function `(model, data, inputs) -> result in data`.

pub mod aba;
pub mod coriolis;
pub mod crba;
pub mod energy;
pub mod jacobian;
pub mod kinematics;
pub mod mass_and_bias;
pub mod momentum;
pub mod regressor;
pub mod rnea;

use crate::data::Data;
use crate::model::Model;

/// Fills `data.joint_placements` for configuration `q` (length already checked).
#[inline(always)]
pub(crate) fn update_joint_placements(model: &Model, data: &mut Data, q: &[f64]) {
    for ((x, joint), &qi) in data.joint_placements.iter_mut().zip(&model.joints).zip(q) {
        *x = joint.transform(qi);
    }
}

/// Fills `data.body_placements` from `data.joint_placements`.
#[inline(always)]
pub(crate) fn update_body_placements(data: &mut Data) {
    let mut prev = crate::spatial::Transform::identity();
    for (o, l) in data.body_placements.iter_mut().zip(&data.joint_placements) {
        *o = prev.compose(l);
        prev = *o;
    }
}
