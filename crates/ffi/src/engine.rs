//! The loop behind a handle: [`RobotLoop`] of `admittance-loop` (gates, signal chain,
//! closed loop, wrench, contact), and how its status maps onto the ABI's flags and fault
//! codes. This crate adds no control logic of its own.
//!
//! ```text
//!   q, tau ──► RobotLoop::step (gates -> SignalChain -> observer -> admittance -> controller)
//!          ──► tau_cmd, tau_ext, q_r, wrench, contact
//! ```

use admittance_control::Fault;
use admittance_loop::RobotStatus;
pub use admittance_loop::{RobotInput, RobotLoop};

use crate::abi::*;

/// What a step reports besides its arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepReport {
    /// `ADM_OUT_*` bits.
    pub flags: u32,
    /// `ADM_FAULT_*`.
    pub fault: i32,
    /// The joint the fault names.
    pub fault_joint: u32,
    /// The touched link of the contact detector (the last loaded joint), -1 for none.
    pub contact_link: i32,
}

/// The ABI's view of one step's status. The fault named is the cause: no angle yet before
/// an implausible sample before the controller's own fault (which an implausible angle,
/// replaced by NaN, also raises).
pub fn report_of(status: &RobotStatus, wrench: bool) -> StepReport {
    let mut flags = 0;
    let mut set = |on: bool, bit: u32| {
        if on {
            flags |= bit;
        }
    };
    set(status.controller_fault.is_some(), ADM_OUT_CONTROLLER_FAULT);
    set(status.observer_fault, ADM_OUT_OBSERVER_FAULT);
    set(status.nonfinite_input, ADM_OUT_NONFINITE_INPUT);
    set(status.warmup, ADM_OUT_WARMUP);
    set(wrench, ADM_OUT_WRENCH);
    set(status.implausible.is_some(), ADM_OUT_IMPLAUSIBLE_INPUT);
    set(status.waiting_for_angles, ADM_OUT_WAITING_FOR_ANGLES);
    set(status.holding_pose, ADM_OUT_HOLDING_POSE);
    set(status.stale_input, ADM_OUT_STALE_INPUT);
    set(
        status.outside_training_range,
        ADM_OUT_OUTSIDE_TRAINING_RANGE,
    );
    set(status.faster_than_training, ADM_OUT_FASTER_THAN_TRAINING);
    let contact = status.contact.unwrap_or_default();
    set(contact.contact, ADM_OUT_CONTACT);
    set(contact.collision, ADM_OUT_COLLISION);
    let (fault, fault_joint) = if status.waiting_for_angles {
        (ADM_FAULT_NO_ANGLE_YET, 0)
    } else if let Some(g) = status.implausible {
        (ADM_FAULT_IMPLAUSIBLE_MEASUREMENT, g.joint as u32)
    } else if let Some(f) = &status.controller_fault {
        fault_code(f)
    } else {
        (ADM_FAULT_NONE, 0)
    };
    StepReport {
        flags,
        fault,
        fault_joint,
        contact_link: if contact.contact { contact.link } else { -1 },
    }
}

/// `ADM_FAULT_*` and the joint of a controller fault.
fn fault_code(f: &Fault) -> (i32, u32) {
    match *f {
        Fault::WrongLength { .. } => (ADM_FAULT_WRONG_LENGTH, 0),
        Fault::NonFiniteMeasurement { joint, .. } => {
            (ADM_FAULT_NONFINITE_MEASUREMENT, joint as u32)
        }
        Fault::StaleMeasurement { joint, .. } => (ADM_FAULT_STALE_MEASUREMENT, joint as u32),
        Fault::NonFiniteReference { joint, .. } => (ADM_FAULT_NONFINITE_REFERENCE, joint as u32),
        Fault::NonFiniteEstimate { joint } => (ADM_FAULT_NONFINITE_ESTIMATE, joint as u32),
        Fault::InvalidTimeStep => (ADM_FAULT_INVALID_TIME_STEP, 0),
        Fault::NonFiniteOutput { joint } => (ADM_FAULT_NONFINITE_OUTPUT, joint as u32),
        Fault::Internal(_) => (ADM_FAULT_INTERNAL, 0),
    }
}

/// The `AdmOutput` of the step `loop_` just took, as `adm_step` writes it (also for a
/// Rust program that compares with the C ABI, `examples/reference_run.rs`).
pub fn output_of(loop_: &RobotLoop, report: &StepReport, time: f64, step: u64) -> AdmOutput {
    let n = loop_.dof();
    let mut out = AdmOutput::ZERO;
    out.time = time;
    out.step = step;
    out.n_joints = n as u32;
    out.flags = report.flags;
    out.fault = report.fault;
    out.fault_joint = report.fault_joint;
    out.implausible_samples = loop_.implausible_samples();
    out.contact_link = report.contact_link;
    out.tau_cmd[..n].copy_from_slice(loop_.torque());
    out.tau_ext[..n].copy_from_slice(loop_.external_torque_estimate());
    let [q_r, qdot_r, qddot_r] = loop_.reference();
    out.q_r[..n].copy_from_slice(q_r);
    out.qdot_r[..n].copy_from_slice(qdot_r);
    out.qddot_r[..n].copy_from_slice(qddot_r);
    if let Some((base, tip)) = loop_.wrench() {
        out.wrench.copy_from_slice(base);
        out.wrench_tip.copy_from_slice(tip);
    }
    if let Some((base, link)) = loop_.contact_wrench() {
        out.contact_wrench.copy_from_slice(base);
        out.contact_wrench_link.copy_from_slice(link);
    }
    out
}
