//! The task-space admittance (docs/method.md section 2, task-space variant; the paper's eq. 5 and
//! eq. 19 `f_ext_hat = J^-T tau_ext_hat`; issue 16 part 1): compliance at the hand, driven
//! by the joint-space external-torque estimate, mapped back to a joint reference.
//!
//! Rooms: `config.rs` (the serde configuration), `deviation.rs` (the admittance on the six
//! task axes), `damped_inverse.rs` (the pseudo-inverse that stays bounded near
//! singularities), `so3.rs` (rotation vectors), `hand.rs` (the hand's kinematics on the task
//! axes), `admittance.rs` (the model: wrench estimate,
//! admittance, inverse kinematics, saturation).

mod admittance;
mod config;
mod damped_inverse;
mod deviation;
mod hand;
mod so3;

pub use admittance::{TaskSpaceAdmittance, TaskSpaceInput};

use crate::admittance::Saturation;
use crate::error::StepStatus;
use crate::reference::{CompliantReference, ReferenceInput};
pub use config::{
    AxisAdmittanceConfig, InverseKinematicsConfig, SingularityDampingConfig, TaskAxis,
    TaskSaturationConfig, TaskSpaceAdmittanceConfig,
};

impl CompliantReference for TaskSpaceAdmittance {
    fn dof(&self) -> usize {
        TaskSpaceAdmittance::dof(self)
    }
    fn step_reference(&mut self, input: &ReferenceInput, dt: f64) -> StepStatus {
        self.step(input, dt)
    }
    fn q_r(&self) -> &[f64] {
        TaskSpaceAdmittance::q_r(self)
    }
    fn qdot_r(&self) -> &[f64] {
        TaskSpaceAdmittance::qdot_r(self)
    }
    fn qddot_r(&self) -> &[f64] {
        TaskSpaceAdmittance::qddot_r(self)
    }
    fn saturation(&self) -> Option<&Saturation> {
        TaskSpaceAdmittance::saturation(self)
    }
    fn reset(&mut self) {
        TaskSpaceAdmittance::reset(self)
    }
}
