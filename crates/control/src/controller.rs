//! The interface every controller implements (docs/method.md sections 3 and 6: the paper's
//! controller and the baselines run in one harness).

use crate::error::StepStatus;

/// What a controller is given at each control step.
///
/// All slices have one value per joint. `q` and `qdot` are the *measured* (sensor-filtered)
/// joint positions and velocities; the controller never sees the plant's true state or true
/// acceleration (docs/method.md section 1, "Sensors"). `q_ref` and its derivatives are the
/// compliant reference `q_r, q_r', q_r''` (the output of [`crate::Admittance`], or the desired
/// trajectory itself when no admittance model is used).
#[derive(Clone, Copy, Debug)]
pub struct ControlInput<'a> {
    /// Time of the sample (s); informational, controllers do not require it to be monotone.
    pub time: f64,
    /// Measured joint positions.
    pub q: &'a [f64],
    /// Measured joint velocities.
    pub qdot: &'a [f64],
    /// Reference position `q_r`.
    pub q_ref: &'a [f64],
    /// Reference velocity `q_r'`.
    pub qdot_ref: &'a [f64],
    /// Reference acceleration `q_r''`.
    pub qddot_ref: &'a [f64],
    /// Estimated external torque `tau_ext_hat` (docs/method.md section 0 sign: the torque the
    /// environment applies to the robot); zeros when there is no observer.
    pub external_torque_estimate: &'a [f64],
}

/// A joint-torque controller.
///
/// Contract of [`step`](Controller::step), for every implementation in this crate:
/// * it writes `torque` (length [`dof`](Controller::dof)), always finite and within the
///   controller's effort limits;
/// * it never panics and never allocates;
/// * on a fault (wrong lengths, non-finite or stale measurement, non-finite reference or
///   estimate, invalid `dt`, or a non-finite law output) it writes the safe hold of
///   [`crate::SafeHold`] instead (gravity of the nominal model at the last valid position
///   minus damping, clamped), freezes any adaptation, and returns
///   [`StepStatus::Fault`]; it resumes the normal law at the first valid step (the neural
///   controller also zeroes a network whose weights are no longer finite, so that a
///   diverged network restarts learning instead of faulting forever).
pub trait Controller {
    /// A short identifier (`"nn"`, `"pd"`, `"pd_gravity"`, `"computed_torque"`).
    fn name(&self) -> &str;
    /// Number of joints.
    fn dof(&self) -> usize;
    /// One control step of length `dt` (s): writes the commanded torque into `torque`.
    fn step(&mut self, input: &ControlInput, dt: f64, torque: &mut [f64]) -> StepStatus;
    /// Back to the state just after construction (learned weights included).
    fn reset(&mut self);
}
