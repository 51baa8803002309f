//! Forward kinematics: the placement of every joint frame and every named frame.

use crate::algorithms::{update_body_placements, update_joint_placements};
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;

/// Computes `data.joint_placements`, `data.body_placements` and `data.frame_placements`
/// (every URDF link on the chain, the tip included) for configuration `q`.
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), DimensionError> {
    check_len("q", q, model.nq())?;
    update_joint_placements(model, data, q);
    update_body_placements(data);
    update_frame_placements(model, data);
    Ok(())
}

/// Recomputes `data.frame_placements` from `data.body_placements`.
pub fn update_frame_placements(model: &Model, data: &mut Data) {
    for (out, frame) in data.frame_placements.iter_mut().zip(&model.frames) {
        *out = match frame.parent_joint {
            Some(j) => data.body_placements[j].compose(&frame.placement),
            None => frame.placement,
        };
    }
}
