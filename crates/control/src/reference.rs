//! The surface shared by the joint-space and the task-space admittance, so that a closed
//! loop can hold either: one input ([`ReferenceInput`]) and the compliant reference
//! `q_r, q_r', q_r''` it produces ([`CompliantReference`]).

use crate::admittance::{Admittance, AdmittanceInput, Saturation};
use crate::error::{Fault, StepStatus};
use crate::safe_hold::first_non_finite;

/// What an admittance model is given at each control step. All slices have one value per
/// joint.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceInput<'a> {
    /// Desired position `q_d`.
    pub q_d: &'a [f64],
    /// Desired velocity `q_d'`.
    pub qdot_d: &'a [f64],
    /// Desired acceleration `q_d''`.
    pub qddot_d: &'a [f64],
    /// Measured (sensor-filtered) position `q`: where the task-space model evaluates the
    /// Jacobian of its wrench estimate. The joint-space model does not use it.
    pub q: &'a [f64],
    /// Estimated external torque `tau_ext_hat` (docs/method.md section 0 sign).
    pub external_torque_estimate: &'a [f64],
}

impl ReferenceInput<'_> {
    /// Lengths of every slice, then finiteness of the desired trajectory and of the
    /// estimate (the measured `q` is checked by the models that use it).
    pub(crate) fn check(&self, n: usize) -> Result<(), Fault> {
        for (argument, v) in [
            ("q_d", self.q_d),
            ("qdot_d", self.qdot_d),
            ("qddot_d", self.qddot_d),
            ("q", self.q),
            ("external_torque_estimate", self.external_torque_estimate),
        ] {
            if v.len() != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        for (argument, v) in [
            ("q_d", self.q_d),
            ("qdot_d", self.qdot_d),
            ("qddot_d", self.qddot_d),
        ] {
            if let Some(joint) = first_non_finite(v) {
                return Err(Fault::NonFiniteReference { argument, joint });
            }
        }
        if let Some(joint) = first_non_finite(self.external_torque_estimate) {
            return Err(Fault::NonFiniteEstimate { joint });
        }
        Ok(())
    }
}

/// An admittance model that turns the desired trajectory and the external-torque estimate
/// into the compliant joint reference `q_r, q_r', q_r''` for the controller: the
/// joint-space [`Admittance`] and the [`TaskSpaceAdmittance`](crate::TaskSpaceAdmittance) (whose
/// implementation lives beside it, so that this file imports nothing of the task space).
///
/// Contract of [`step_reference`](Self::step_reference), for both: it never panics and
/// never allocates; on a fault the state is unchanged, `q_r` is held with zero velocity and
/// acceleration, and the fault is returned.
pub trait CompliantReference {
    /// Number of joints.
    fn dof(&self) -> usize;
    /// One step of length `dt` (s).
    fn step_reference(&mut self, input: &ReferenceInput, dt: f64) -> StepStatus;
    /// Reference position `q_r`.
    fn q_r(&self) -> &[f64];
    /// Reference velocity `q_r'`.
    fn qdot_r(&self) -> &[f64];
    /// Reference acceleration `q_r''`.
    fn qddot_r(&self) -> &[f64];
    /// The joint saturation (eq. 7) keeping `q_r` inside its bounds, if any.
    fn saturation(&self) -> Option<&Saturation>;
    /// Back to the state just after construction.
    fn reset(&mut self);
}

impl CompliantReference for Admittance {
    fn dof(&self) -> usize {
        Admittance::dof(self)
    }
    /// The joint-space model's own [`Admittance::step`]; `input.q` is not used (its length
    /// is not checked either).
    fn step_reference(&mut self, input: &ReferenceInput, dt: f64) -> StepStatus {
        let input = AdmittanceInput {
            q_d: input.q_d,
            qdot_d: input.qdot_d,
            qddot_d: input.qddot_d,
            external_torque_estimate: input.external_torque_estimate,
        };
        self.step(&input, dt)
    }
    fn q_r(&self) -> &[f64] {
        Admittance::q_r(self)
    }
    fn qdot_r(&self) -> &[f64] {
        Admittance::qdot_r(self)
    }
    fn qddot_r(&self) -> &[f64] {
        Admittance::qddot_r(self)
    }
    fn saturation(&self) -> Option<&Saturation> {
        Admittance::saturation(self)
    }
    fn reset(&mut self) {
        Admittance::reset(self)
    }
}
