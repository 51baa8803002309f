//! Geometric Jacobians of frames and the bias term `Jdot qdot`.

// Joint index addresses several parallel per-joint arrays; read clearest indexed.
#![allow(clippy::needless_range_loop)]

use nalgebra::{Matrix6xX, Vector3, Vector6};

use crate::algorithms::{update_body_placements, update_joint_placements};
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::{JointKind, Model};
use crate::spatial::{Motion, Transform};

/// The geometric Jacobian of frame `frame` (index into [`Model::frames`]) into
/// `data.jacobian`: `6 x n`, linear rows first, base-frame axes, linear velocity of the
/// frame's origin. Also refreshes the forward kinematics in `data`.
///
/// # Panics
/// Never for a valid frame index; an out-of-range index is reported as a
/// [`DimensionError`] on argument `frame`.
pub fn frame_jacobian<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    frame: usize,
) -> Result<&'d Matrix6xX<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    if frame >= model.frames.len() {
        return Err(DimensionError {
            argument: "frame",
            expected: model.frames.len(),
            found: frame,
        });
    }
    update_joint_placements(model, data, q);
    update_body_placements(data);
    let origin = update_one_frame(model, data, frame).translation;
    let last = model.frames[frame].parent_joint;
    for j in 0..n {
        let mut col = data.jacobian.column_mut(j);
        match last {
            Some(k) if j <= k => {
                let o = &data.body_placements[j];
                let axis = o.rotation * model.joints[j].axis;
                match model.joints[j].kind {
                    JointKind::Prismatic => {
                        col.fixed_rows_mut::<3>(0).copy_from(&axis);
                        col.fixed_rows_mut::<3>(3).fill(0.0);
                    }
                    _ => {
                        col.fixed_rows_mut::<3>(0)
                            .copy_from(&axis.cross(&(origin - o.translation)));
                        col.fixed_rows_mut::<3>(3).copy_from(&axis);
                    }
                }
            }
            _ => col.fill(0.0),
        }
    }
    Ok(&data.jacobian)
}

/// The tip frame's Jacobian (see [`frame_jacobian`]).
pub fn tip_jacobian<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
) -> Result<&'d Matrix6xX<f64>, DimensionError> {
    frame_jacobian(model, data, q, model.tip_frame)
}

/// `Jdot(q, v) v` of frame `frame` into `data.jdot_qdot`: the frame origin's classical
/// linear acceleration and the angular acceleration when `qddot = 0`, linear first,
/// base axes. Task-space controllers use `xddot = J qddot + Jdot qdot`.
pub fn frame_jdot_qdot<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    frame: usize,
) -> Result<&'d Vector6<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    if frame >= model.frames.len() {
        return Err(DimensionError {
            argument: "frame",
            expected: model.frames.len(),
            found: frame,
        });
    }
    update_joint_placements(model, data, q);
    update_body_placements(data);
    let p = update_one_frame(model, data, frame).translation;
    // Spatial (base-origin) quantities: v = sum S_j qd_j, a = sum (v_j x S_j) qd_j.
    let mut velocity = Motion::zero();
    let mut acceleration = Motion::zero();
    if let Some(k) = model.frames[frame].parent_joint {
        for j in 0..=k {
            let s = data.body_placements[j].act_motion(&model.joints[j].motion_subspace());
            velocity = velocity + s.scaled(v[j]);
            acceleration = acceleration + velocity.cross_motion(&s).scaled(v[j]);
        }
    }
    let w = velocity.angular;
    let point_velocity: Vector3<f64> = velocity.linear + w.cross(&p);
    let linear = acceleration.linear + acceleration.angular.cross(&p) + w.cross(&point_velocity);
    data.jdot_qdot = Vector6::new(
        linear.x,
        linear.y,
        linear.z,
        acceleration.angular.x,
        acceleration.angular.y,
        acceleration.angular.z,
    );
    Ok(&data.jdot_qdot)
}

/// `Jdot qdot` of the tip frame (see [`frame_jdot_qdot`]).
pub fn tip_jdot_qdot<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<&'d Vector6<f64>, DimensionError> {
    frame_jdot_qdot(model, data, q, v, model.tip_frame)
}

/// Places one frame from `data.body_placements` (the Jacobians need only theirs).
#[inline(always)]
fn update_one_frame(model: &Model, data: &mut Data, frame: usize) -> Transform {
    let f = &model.frames[frame];
    let placement = match f.parent_joint {
        Some(j) => data.body_placements[j].compose(&f.placement),
        None => f.placement,
    };
    data.frame_placements[frame] = placement;
    placement
}
