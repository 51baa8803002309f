//! The mutable workspace every algorithm writes into: built once per model, reused for
//! every call, so that no call allocates.

use nalgebra::{DMatrix, DVector, Matrix6, Matrix6xX, Vector6};

use crate::model::Model;
use crate::spatial::{Force, Inertia, Motion, Transform};

/// Results and scratch space of the dynamics algorithms for one [`Model`].
///
/// Outputs are public fields; which algorithm fills which is said on each field. Scratch
/// fields are private. A `Data` must only be used with the model it was built for (the
/// algorithms check argument lengths, not model identity).
#[derive(Clone, Debug)]
pub struct Data {
    /// Placement of each joint frame in the previous body's frame (filled by every algorithm).
    pub joint_placements: Vec<Transform>,
    /// Placement of each joint frame in the base frame ([`crate::forward_kinematics`],
    /// the Jacobians, the Coriolis matrix).
    pub body_placements: Vec<Transform>,
    /// Placement of every frame of [`Model::frames`] in the base frame
    /// ([`crate::forward_kinematics`]).
    pub frame_placements: Vec<Transform>,
    /// Body spatial velocities in their own frames (RNEA, ABA).
    pub velocities: Vec<Motion>,
    /// Body spatial accelerations in their own frames, gravity included as a base
    /// acceleration (RNEA, ABA).
    pub accelerations: Vec<Motion>,
    /// Body wrenches transmitted through each joint, own frames (RNEA).
    pub forces: Vec<Force>,
    /// Joint torques (RNEA).
    pub tau: DVector<f64>,
    /// Joint-space inertia matrix M(q), full symmetric (CRBA).
    pub mass_matrix: DMatrix<f64>,
    /// Generalised gravity G(q).
    pub gravity_torque: DVector<f64>,
    /// Nonlinear effects C(q, qdot) qdot + G(q).
    pub nonlinear_effects: DVector<f64>,
    /// Coriolis matrix C(q, qdot) (Christoffel form, `Mdot - 2C` skew-symmetric).
    pub coriolis: DMatrix<f64>,
    /// Generalised momentum M(q) qdot ([`crate::momentum_observer_terms`]).
    pub momentum: DVector<f64>,
    /// C(q, qdot)^T qdot ([`crate::momentum_observer_terms`]).
    pub coriolis_transpose_v: DVector<f64>,
    /// Joint accelerations (ABA).
    pub qddot: DVector<f64>,
    /// Geometric Jacobian of a frame: linear rows first, base axes, at the frame origin.
    pub jacobian: Matrix6xX<f64>,
    /// `Jdot qdot` of a frame: the classical acceleration at zero joint acceleration,
    /// linear part first, base axes.
    pub jdot_qdot: Vector6<f64>,
    /// Joint-torque regressor `Y(q, q', q'')`, n x 10 n ([`crate::joint_torque_regressor`]).
    pub regressor: DMatrix<f64>,

    pub(crate) composite: Vec<Inertia>,
    /// Body weights carried down the chain by `mass_matrix_and_bias`'s gravity recursion.
    pub(crate) gravity_forces: Vec<Force>,
    pub(crate) world_subspace: Vec<Vector6<f64>>,
    pub(crate) world_subspace_rate: Vec<Vector6<f64>>,
    pub(crate) world_velocity: Vec<Motion>,
    pub(crate) coriolis_b: Vec<Matrix6<f64>>,
    pub(crate) coriolis_dfdv: Vec<Vector6<f64>>,
    pub(crate) art_inertia: Vec<Matrix6<f64>>,
    pub(crate) art_bias: Vec<Force>,
    pub(crate) art_u: Vec<Vector6<f64>>,
    pub(crate) art_d: Vec<f64>,
    pub(crate) art_torque: Vec<f64>,
    pub(crate) bias_acc: Vec<Motion>,
    /// The joints' axes up to a body, in that body's frame (the regressor's backward pass).
    pub(crate) regressor_axes: Vec<Motion>,
}

impl Data {
    /// A workspace sized for `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.nq();
        Self {
            joint_placements: vec![Transform::identity(); n],
            body_placements: vec![Transform::identity(); n],
            frame_placements: vec![Transform::identity(); model.frames.len()],
            velocities: vec![Motion::zero(); n],
            accelerations: vec![Motion::zero(); n],
            forces: vec![Force::zero(); n],
            tau: DVector::zeros(n),
            mass_matrix: DMatrix::zeros(n, n),
            gravity_torque: DVector::zeros(n),
            nonlinear_effects: DVector::zeros(n),
            coriolis: DMatrix::zeros(n, n),
            momentum: DVector::zeros(n),
            coriolis_transpose_v: DVector::zeros(n),
            qddot: DVector::zeros(n),
            jacobian: Matrix6xX::zeros(n),
            jdot_qdot: Vector6::zeros(),
            regressor: DMatrix::zeros(n, 10 * n),
            composite: vec![Inertia::zero(); n],
            gravity_forces: vec![Force::zero(); n],
            world_subspace: vec![Vector6::zeros(); n],
            world_subspace_rate: vec![Vector6::zeros(); n],
            world_velocity: vec![Motion::zero(); n],
            coriolis_b: vec![Matrix6::zeros(); n],
            coriolis_dfdv: vec![Vector6::zeros(); n],
            art_inertia: vec![Matrix6::zeros(); n],
            art_bias: vec![Force::zero(); n],
            art_u: vec![Vector6::zeros(); n],
            art_d: vec![0.0; n],
            art_torque: vec![0.0; n],
            bias_acc: vec![Motion::zero(); n],
            regressor_axes: vec![Motion::zero(); n],
        }
    }

    /// Placement of the model's tip frame in the base frame, as of the last
    /// [`crate::forward_kinematics`] call.
    pub fn tip_placement(&self, model: &Model) -> &Transform {
        &self.frame_placements[model.tip_frame]
    }
}
