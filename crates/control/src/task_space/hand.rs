//! The hand's kinematics as the task-space admittance uses it: pose, twist and
//! acceleration from joint motion, products with the Jacobian, the task-axis masks, and the
//! relative rotation whose logarithm is the orientation error.

use admittance_dynamics::{tip_jacobian, tip_jdot_qdot, Data, Model, Transform};
use nalgebra::{Matrix3, Matrix6xX, Vector6};

use crate::error::Fault;

/// Pose, twist `J qdot` and acceleration `J qddot + J' qdot` of the hand (the tip frame) at
/// `q`; `jacobian` receives `J(q)`. The desired and the reference motion both go through
/// this one function, so that equal arguments give bit-identical results.
pub(super) fn hand_motion(
    model: &Model,
    data: &mut Data,
    jacobian: &mut Matrix6xX<f64>,
    q: &[f64],
    qdot: &[f64],
    qddot: &[f64],
) -> Result<(Transform, Vector6<f64>, Vector6<f64>), Fault> {
    let j = tip_jacobian(model, data, q).map_err(|_| Fault::Internal("tip Jacobian"))?;
    jacobian.copy_from(j);
    let pose = *data.tip_placement(model);
    let bias =
        *tip_jdot_qdot(model, data, q, qdot).map_err(|_| Fault::Internal("tip Jdot qdot"))?;
    let twist = jacobian_times(jacobian, qdot);
    let acceleration = jacobian_times(jacobian, qddot) + bias;
    Ok((pose, twist, acceleration))
}

/// Zeroes the rows of the axes outside the task.
pub(super) fn keep_task_rows(j: &mut Matrix6xX<f64>, task: &[bool; 6]) {
    for (r, keep) in task.iter().enumerate() {
        if !keep {
            j.row_mut(r).fill(0.0);
        }
    }
}

/// Zeroes the entries of the axes outside the task.
pub(super) fn keep_task_entries(v: &mut Vector6<f64>, task: &[bool; 6]) {
    for (r, keep) in task.iter().enumerate() {
        if !keep {
            v[r] = 0.0;
        }
    }
}

/// `J v`.
pub(super) fn jacobian_times(j: &Matrix6xX<f64>, v: &[f64]) -> Vector6<f64> {
    let mut out = Vector6::zeros();
    for (c, x) in v.iter().enumerate() {
        out += j.column(c) * *x;
    }
    out
}

/// `a b^T`, entry `(i, j) = sum_k a_ik b_jk` in a fixed order, so that `a a^T` is exactly
/// symmetric (and its [`so3::log`](super::so3::log) exactly zero).
pub(super) fn relative_rotation(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| a[(i, 0)] * b[(j, 0)] + a[(i, 1)] * b[(j, 1)] + a[(i, 2)] * b[(j, 2)])
}
