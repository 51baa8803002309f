//! The Coriolis matrix C(q, qdot) in Christoffel form, so that `Mdot - 2C` is
//! skew-symmetric (docs/method.md section 1; the property the controller's stability proof
//! in section 3 relies on).
//!
//! Computed in the base frame: with each body's world Jacobian `J_k`, its world inertia
//! `I_k` and velocity `v_k`, `C = sum_k J_k^T (I_k Jdot_k + B_k J_k)` where
//! `B_k = 1/2 (v_k x* I_k - I_k v_k x + (I_k v_k) x-bar)` is the body-level Christoffel
//! matrix (Echeandia and Wensing's form, as in Pinocchio). On a serial chain the sums
//! over descendants become composite `I` and `B` accumulated from the tip.

use nalgebra::{DMatrix, Matrix3, Matrix6, Vector6};

use crate::algorithms::{update_body_placements, update_joint_placements};
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;
use crate::spatial::{add_force_cross_matrix, skew, Force, Inertia, Motion};

#[inline(always)]
pub(crate) fn motion_of(v: &Vector6<f64>) -> Motion {
    Motion {
        linear: v.fixed_rows::<3>(0).into_owned(),
        angular: v.fixed_rows::<3>(3).into_owned(),
    }
}

/// `B = 1/2 (v x* Y - Y v x) + 1/2 (Y v) x-bar` for a body of world inertia `Y`.
#[inline(always)]
fn body_christoffel(y: &Inertia, v: &Motion) -> Matrix6<f64> {
    // P = Y [v]x with Y = [[m 1, -[h]], [[h], I]] and [v]x = [[[w], [v]], [0, [w]]];
    // then v x* Y - Y v x = -(P + P^T) because Y is symmetric.
    let w = skew(&v.angular);
    let vl = skew(&v.linear);
    let h = skew(&y.first_moment);
    let hw = h * w;
    let p00: Matrix3<f64> = w * y.mass;
    let p01: Matrix3<f64> = vl * y.mass - hw;
    let p10: Matrix3<f64> = hw;
    let p11: Matrix3<f64> = h * vl + y.rotational * w;
    let mut b = Matrix6::zeros();
    b.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&((p00 + p00.transpose()) * -0.5));
    b.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&((p01 + p10.transpose()) * -0.5));
    b.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&((p10 + p01.transpose()) * -0.5));
    b.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&((p11 + p11.transpose()) * -0.5));
    let momentum = y.mul_motion(v);
    let half = Force {
        linear: momentum.linear * 0.5,
        angular: momentum.angular * 0.5,
    };
    add_force_cross_matrix(&half, &mut b);
    b
}

/// The forward pass shared with [`crate::momentum_observer_terms`]: joint and body
/// placements, then per body (base frame) its joint axis `s_i`, `sdot_i = v_i x s_i`, its
/// Christoffel matrix `B_i`, inertia `Y_i` (the composites start from them) and velocity
/// `v_i`. Lengths already checked.
#[inline(always)]
pub(crate) fn world_forward_pass(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) {
    update_joint_placements(model, data, q);
    update_body_placements(data);
    let mut velocity = Motion::zero();
    for (i, &vi) in v.iter().enumerate() {
        let o = &data.body_placements[i];
        let s = o.act_motion(&model.joints[i].motion_subspace());
        velocity = velocity + s.scaled(vi);
        let y = model.bodies[i].transformed(o);
        data.world_subspace[i] = s.to_vector();
        data.world_subspace_rate[i] = velocity.cross_motion(&s).to_vector();
        data.coriolis_b[i] = body_christoffel(&y, &velocity);
        data.composite[i] = y;
        data.world_velocity[i] = velocity;
    }
}

/// `C(q, v)` into `data.coriolis`. `C v + G = ` [`crate::nonlinear_effects`].
pub fn coriolis_matrix<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<&'d DMatrix<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    world_forward_pass(model, data, q, v);
    for i in (0..n).rev() {
        let s = &data.world_subspace[i];
        let ds = &data.world_subspace_rate[i];
        let y = data.composite[i];
        let b = data.coriolis_b[i];
        data.coriolis_dfdv[i] = y.mul_motion(&motion_of(ds)).to_vector() + b * s;
        for j in i..n {
            data.coriolis[(i, j)] = s.dot(&data.coriolis_dfdv[j]);
        }
        let ys = y.mul_motion(&motion_of(s)).to_vector();
        let bts = b.tr_mul(s);
        for j in 0..i {
            data.coriolis[(i, j)] =
                ys.dot(&data.world_subspace_rate[j]) + bts.dot(&data.world_subspace[j]);
        }
        if i > 0 {
            data.composite[i - 1] = data.composite[i - 1].add(&y);
            data.coriolis_b[i - 1] += b;
        }
    }
    Ok(&data.coriolis)
}
