//! Recursive Newton-Euler inverse dynamics (docs/method.md eq. 1: the left-hand side
//! `M(q) qddot + C(q, qdot) qdot + G(q)`), and its special cases G(q) and C qdot + G.

use nalgebra::{DVector, Vector3, Vector6};

use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;
use crate::spatial::{Force, Motion};

/// Joint torques `tau = M(q) a + C(q, v) v + G(q)`, into `data.tau`.
pub fn rnea<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> Result<&'d DVector<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    check_len("a", a, n)?;
    rnea_pass(model, data, q, Some(v), Some(a), None);
    Ok(&data.tau)
}

/// Joint torques with an external wrench acting on the robot at the tip frame:
/// `tau = M a + C v + G - J^T w`. `wrench = [fx, fy, fz, nx, ny, nz]` in base-frame axes,
/// the moment taken about the tip frame's origin; `J` is [`crate::tip_jacobian`].
pub fn rnea_with_tip_wrench<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    wrench: &Vector6<f64>,
) -> Result<&'d DVector<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    check_len("a", a, n)?;
    rnea_pass(model, data, q, Some(v), Some(a), Some(wrench));
    Ok(&data.tau)
}

/// Generalised gravity `G(q)`, into `data.gravity_torque`.
pub fn gravity_torque<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
) -> Result<&'d DVector<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    update_joint_placements(model, data, q);
    gravity_pass(model, data);
    Ok(&data.gravity_torque)
}

/// `G(q)` on `data.joint_placements` as they are.
#[inline(always)]
pub(crate) fn gravity_pass(model: &Model, data: &mut Data) {
    let n = model.nq();
    // With v = 0 and a = 0 every body acceleration is the (linear) gravity acceleration
    // seen in the body frame, and each body wrench is its weight.
    let mut a = -model.gravity;
    for i in 0..n {
        a = data.joint_placements[i].rotation.tr_mul(&a);
        let inertia = &model.bodies[i];
        data.forces[i] = Force {
            linear: a * inertia.mass,
            angular: inertia.first_moment.cross(&a),
        };
    }
    for i in (0..n).rev() {
        let f = data.forces[i];
        data.gravity_torque[i] = model.joints[i].subspace_dot(&f);
        if i > 0 {
            let moved = data.joint_placements[i].act_force(&f);
            data.forces[i - 1] += moved;
        }
    }
}

/// Nonlinear effects `C(q, v) v + G(q)`, into `data.nonlinear_effects`.
pub fn nonlinear_effects<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<&'d DVector<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    rnea_pass(model, data, q, Some(v), None, None);
    data.nonlinear_effects.copy_from(&data.tau);
    Ok(&data.nonlinear_effects)
}

/// The wrench `w` (base axes, moment about the tip origin) expressed in the frame of the
/// body that carries the tip, moment about that body's origin. Needs `data.body_placements`.
pub(crate) fn tip_wrench_in_body(
    model: &Model,
    data: &Data,
    wrench: &Vector6<f64>,
) -> Option<(usize, Force)> {
    let tip = model.tip();
    let body = tip.parent_joint?;
    let o = &data.body_placements[body];
    let tip_origin = o.transform_point(&tip.placement.translation);
    let f = Vector3::new(wrench[0], wrench[1], wrench[2]);
    let n = Vector3::new(wrench[3], wrench[4], wrench[5]) + (tip_origin - o.translation).cross(&f);
    let rt = o.rotation.transpose();
    Some((
        body,
        Force {
            linear: rt * f,
            angular: rt * n,
        },
    ))
}

/// Shared pass; `None` velocity or acceleration means zero.
#[inline(always)]
fn rnea_pass(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: Option<&[f64]>,
    a: Option<&[f64]>,
    wrench: Option<&Vector6<f64>>,
) {
    update_joint_placements(model, data, q);
    rnea_pass_at_placements(model, data, v, a, wrench);
}

/// Body `i`'s velocity and acceleration from its parent's and the joint's rate and
/// acceleration, and the wrench that moves it (into `data.velocities`, `data.accelerations`
/// and `data.forces`): one step of the RNEA's forward recursion. Returns the velocity and
/// acceleration, the next body's parent motion.
#[inline(always)]
pub(crate) fn forward_step(
    model: &Model,
    data: &mut Data,
    i: usize,
    (v_parent, a_parent): (&Motion, &Motion),
    qd: f64,
    qdd: f64,
) -> (Motion, Motion) {
    let x = &data.joint_placements[i];
    let s = model.joints[i].motion_subspace();
    let joint_velocity = s.scaled(qd);
    let vi = x.act_inv_motion(v_parent) + joint_velocity;
    let ai = x.act_inv_motion(a_parent) + s.scaled(qdd) + vi.cross_motion(&joint_velocity);
    let inertia = &model.bodies[i];
    let fi = inertia.mul_motion(&ai) + vi.cross_force(&inertia.mul_motion(&vi));
    data.velocities[i] = vi;
    data.accelerations[i] = ai;
    data.forces[i] = fi;
    (vi, ai)
}

/// [`rnea_pass`] on `data.joint_placements` as they are.
#[inline(always)]
pub(crate) fn rnea_pass_at_placements(
    model: &Model,
    data: &mut Data,
    v: Option<&[f64]>,
    a: Option<&[f64]>,
    wrench: Option<&Vector6<f64>>,
) {
    let n = model.nq();
    let mut v_parent = Motion::zero();
    let mut a_parent = Motion {
        linear: -model.gravity,
        angular: Vector3::zeros(),
    };
    for i in 0..n {
        let qd = v.map_or(0.0, |v| v[i]);
        let qdd = a.map_or(0.0, |a| a[i]);
        let (vi, ai) = forward_step(model, data, i, (&v_parent, &a_parent), qd, qdd);
        v_parent = vi;
        a_parent = ai;
    }
    if let Some(w) = wrench {
        crate::algorithms::update_body_placements(data);
        if let Some((body, f)) = tip_wrench_in_body(model, data, w) {
            data.forces[body] -= f;
        }
    }
    for i in (0..n).rev() {
        data.tau[i] = model.joints[i].subspace_dot(&data.forces[i]);
        if i > 0 {
            let f = data.joint_placements[i].act_force(&data.forces[i]);
            data.forces[i - 1] += f;
        }
    }
}
