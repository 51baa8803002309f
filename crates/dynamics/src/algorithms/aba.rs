//! Articulated-body algorithm: forward dynamics `qddot = M^-1 (tau - C qdot - G)`
//! (docs/method.md eq. 1 solved for the acceleration; the simulator's plant).

// Joint index addresses several parallel per-joint arrays; read clearest indexed.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DVector, Vector3, Vector6};

use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::{JointKind, Model};
use crate::spatial::{transform_articulated_inertia, Force, Motion};

/// Joint accelerations for torques `tau`, into `data.qddot`.
pub fn aba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<&'d DVector<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    check_len("tau", tau, n)?;
    aba_pass(model, data, q, v, tau, None);
    Ok(&data.qddot)
}

/// Joint accelerations with an external wrench on the robot at the tip frame (base axes,
/// moment about the tip origin; see [`crate::rnea_with_tip_wrench`]).
pub fn aba_with_tip_wrench<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    wrench: &Vector6<f64>,
) -> Result<&'d DVector<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    check_len("tau", tau, n)?;
    aba_pass(model, data, q, v, tau, Some(wrench));
    Ok(&data.qddot)
}

#[inline(always)]
fn subspace_column(
    kind: JointKind,
    axis: &Vector3<f64>,
    ia: &nalgebra::Matrix6<f64>,
) -> Vector6<f64> {
    match kind {
        JointKind::Prismatic => ia.fixed_columns::<3>(0) * axis,
        _ => ia.fixed_columns::<3>(3) * axis,
    }
}

#[inline(always)]
fn aba_pass(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    wrench: Option<&Vector6<f64>>,
) {
    let n = model.nq();
    update_joint_placements(model, data, q);
    let mut v_parent = Motion::zero();
    for i in 0..n {
        let joint = &model.joints[i];
        let x = &data.joint_placements[i];
        let joint_velocity = joint.motion_subspace().scaled(v[i]);
        let vi = x.act_inv_motion(&v_parent) + joint_velocity;
        let inertia = &model.bodies[i];
        data.velocities[i] = vi;
        data.bias_acc[i] = vi.cross_motion(&joint_velocity);
        data.art_inertia[i] = inertia.to_matrix();
        data.art_bias[i] = vi.cross_force(&inertia.mul_motion(&vi));
        v_parent = vi;
    }
    if let Some(w) = wrench {
        crate::algorithms::update_body_placements(data);
        if let Some((body, f)) = crate::algorithms::rnea::tip_wrench_in_body(model, data, w) {
            data.art_bias[body] -= f;
        }
    }
    for i in (0..n).rev() {
        let joint = &model.joints[i];
        let s = joint.motion_subspace();
        let ia = data.art_inertia[i];
        let u_col = subspace_column(joint.kind, &joint.axis, &ia);
        let d = match joint.kind {
            JointKind::Prismatic => joint.axis.dot(&u_col.fixed_rows::<3>(0)),
            _ => joint.axis.dot(&u_col.fixed_rows::<3>(3)),
        };
        let u = tau[i] - data.art_bias[i].dot(&s);
        data.art_u[i] = u_col;
        data.art_d[i] = d;
        data.art_torque[i] = u;
        if i > 0 {
            let d_inv = 1.0 / d;
            let reduced = ia - u_col * u_col.transpose() * d_inv;
            let c = data.bias_acc[i].to_vector();
            let pa = data.art_bias[i].to_vector() + reduced * c + u_col * (u * d_inv);
            let pa = Force {
                linear: pa.fixed_rows::<3>(0).into_owned(),
                angular: pa.fixed_rows::<3>(3).into_owned(),
            };
            let x = data.joint_placements[i];
            let moved = transform_articulated_inertia(&x, &reduced);
            data.art_inertia[i - 1] += moved;
            let moved_bias = x.act_force(&pa);
            data.art_bias[i - 1] += moved_bias;
        }
    }
    let mut a_parent = Motion {
        linear: -model.gravity,
        angular: Vector3::zeros(),
    };
    for i in 0..n {
        let joint = &model.joints[i];
        let ai = data.joint_placements[i].act_inv_motion(&a_parent) + data.bias_acc[i];
        let u_col = &data.art_u[i];
        let ua =
            u_col.fixed_rows::<3>(0).dot(&ai.linear) + u_col.fixed_rows::<3>(3).dot(&ai.angular);
        let qdd = (data.art_torque[i] - ua) / data.art_d[i];
        data.qddot[i] = qdd;
        let ai = ai + joint.motion_subspace().scaled(qdd);
        data.accelerations[i] = ai;
        a_parent = ai;
    }
}
