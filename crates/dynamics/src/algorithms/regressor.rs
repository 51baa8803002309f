//! The joint-torque regressor: RNEA written as a product `tau = Y(q, q', q'') pi`, linear in
//! the inertial parameters `pi` (10 per body). What least-squares identification fits
//! (docs/method.md section 1: the left-hand side of eq. 1 is linear in the inertial
//! parameters).
//!
//! Each body's parameters are, in Pinocchio's order (`Inertia::toDynamicParameters`),
//! `[m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]`, with the rotational
//! inertia taken **about the joint frame's origin** in the joint frame's axes (the compact
//! form [`Inertia`] stores). Columns `10 j .. 10 j + 10` belong to body `j`.

use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;
use crate::spatial::{Force, Inertia, Motion};

/// Number of inertial parameters of one body.
pub const PARAMETERS_PER_BODY: usize = 10;

impl Inertia {
    /// The 10 inertial parameters `[m, h_x, h_y, h_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]`
    /// (`h = m c`, `I` about the frame origin): Pinocchio's order.
    pub fn to_parameters(&self) -> [f64; PARAMETERS_PER_BODY] {
        let (h, i) = (&self.first_moment, &self.rotational);
        [
            self.mass,
            h.x,
            h.y,
            h.z,
            i[(0, 0)],
            i[(0, 1)],
            i[(1, 1)],
            i[(0, 2)],
            i[(1, 2)],
            i[(2, 2)],
        ]
    }

    /// The inverse of [`Inertia::to_parameters`] (any values: physical consistency is
    /// not checked here).
    pub fn from_parameters(p: &[f64; PARAMETERS_PER_BODY]) -> Inertia {
        Inertia {
            mass: p[0],
            first_moment: Vector3::new(p[1], p[2], p[3]),
            rotational: Matrix3::new(p[4], p[5], p[7], p[5], p[6], p[8], p[7], p[8], p[9]),
        }
    }
}

/// The model's inertial parameters stacked body after body (length `10 n`), so that
/// `rnea(q, q', q'') == joint_torque_regressor(q, q', q'') * parameters`.
pub fn inertial_parameters(model: &Model) -> Vec<f64> {
    model
        .bodies
        .iter()
        .flat_map(|b| b.to_parameters())
        .collect()
}

/// A copy of `model` with its bodies' inertial parameters replaced by `parameters`
/// (length `10 n`, the order of [`inertial_parameters`]). Kinematics, limits and frames
/// are kept.
pub fn with_inertial_parameters(
    model: &Model,
    parameters: &[f64],
) -> Result<Model, DimensionError> {
    check_len("parameters", parameters, PARAMETERS_PER_BODY * model.nq())?;
    let mut out = model.clone();
    for (body, p) in out
        .bodies
        .iter_mut()
        .zip(parameters.chunks_exact(PARAMETERS_PER_BODY))
    {
        let mut fixed = [0.0; PARAMETERS_PER_BODY];
        fixed.copy_from_slice(p);
        *body = Inertia::from_parameters(&fixed);
    }
    Ok(out)
}

/// The joint-torque regressor `Y(q, q', q'')` (n x 10 n, into `data.regressor`), gravity
/// included through the base acceleration as in [`crate::rnea`]. Equal to Pinocchio's
/// `computeJointTorqueRegressor`. Allocation-free.
pub fn joint_torque_regressor<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> Result<&'d DMatrix<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    check_len("a", a, n)?;
    update_joint_placements(model, data, q);
    forward_motion_pass(model, data, v, a);
    data.regressor.fill(0.0);
    // Row i of body j's block is joint i's axis (in body j's frame) dotted with the body's
    // wrench for each unit parameter: one axis carried up the chain per body, instead of
    // ten wrenches carried down it (the same products, a tenth of the transforms).
    for j in 0..n {
        let x = &data.joint_placements[j];
        for axis in data.regressor_axes[..j].iter_mut() {
            *axis = x.act_inv_motion(axis);
        }
        data.regressor_axes[j] = model.joints[j].motion_subspace();
        let columns = body_regressor(&data.velocities[j], &data.accelerations[j]);
        for (i, axis) in data.regressor_axes[..=j].iter().enumerate() {
            for (k, f) in columns.iter().enumerate() {
                data.regressor[(i, PARAMETERS_PER_BODY * j + k)] = f.dot(axis);
            }
        }
    }
    Ok(&data.regressor)
}

/// Body velocities and accelerations (own frames, gravity as a base acceleration): the
/// forward pass of RNEA.
#[inline(always)]
fn forward_motion_pass(model: &Model, data: &mut Data, v: &[f64], a: &[f64]) {
    let mut v_parent = Motion::zero();
    let mut a_parent = Motion {
        linear: -model.gravity,
        angular: Vector3::zeros(),
    };
    for i in 0..model.nq() {
        let x = &data.joint_placements[i];
        let s = model.joints[i].motion_subspace();
        let joint_velocity = s.scaled(v[i]);
        let vi = x.act_inv_motion(&v_parent) + joint_velocity;
        let ai = x.act_inv_motion(&a_parent) + s.scaled(a[i]) + vi.cross_motion(&joint_velocity);
        data.velocities[i] = vi;
        data.accelerations[i] = ai;
        v_parent = vi;
        a_parent = ai;
    }
}

/// `f = I a + v x* (I v)` for each unit parameter vector: the 10 columns of the body
/// regressor, as wrenches in the body's frame (`v x* (l, n) = (w x l, w x n + v_l x l)`),
/// written out per kind of parameter so that no zero is multiplied.
#[inline(always)]
fn body_regressor(v: &Motion, a: &Motion) -> [Force; PARAMETERS_PER_BODY] {
    let (w, vl) = (&v.angular, &v.linear);
    let (aw, al) = (&a.angular, &a.linear);
    let mut out = [Force::zero(); PARAMETERS_PER_BODY];
    // The mass: I a = (a_l, 0), I v = (v_l, 0).
    out[0].linear = al + w.cross(vl);
    // The first moment h: I a = (a_w x h, h x a_l), I v = (w x h, h x v_l).
    for (c, f) in out[1..4].iter_mut().enumerate() {
        let h = Vector3::ith(c, 1.0);
        let wh = w.cross(&h);
        f.linear = aw.cross(&h) + w.cross(&wh);
        f.angular = h.cross(al) + w.cross(&h.cross(vl)) + vl.cross(&wh);
    }
    // The rotational inertia's entries (xx, xy, yy, xz, yz, zz): I a = (0, E a_w) with E
    // the entry's unit symmetric matrix, I v = (0, E w).
    const ENTRIES: [(usize, usize); 6] = [(0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)];
    let unit_times = |(r, c): (usize, usize), x: &Vector3<f64>| {
        let mut y = Vector3::zeros();
        y[r] = x[c];
        if r != c {
            y[c] = x[r];
        }
        y
    };
    for (f, &entry) in out[4..].iter_mut().zip(&ENTRIES) {
        f.angular = unit_times(entry, aw) + w.cross(&unit_times(entry, w));
    }
    out
}
