//! The wiring of one control period (docs/method.md sections 2-5), the only place it exists:
//! the scenario runner, the 1 kHz example (`crates/cli/examples/control_loop.rs`) and the
//! C interface all step a [`ClosedLoop`], built by [`ClosedLoop::from_config`].
//!
//! ```text
//!   measurement ──► observer (input conditioning, low-pass, warm-up) ──► tau_ext_hat
//!   q_d, q_d', q_d'' ──► admittance model (eq. 5-7, driven by tau_ext_hat) ──► q_r, q_r', q_r''
//!   measurement, q_r, tau_ext_hat ──► controller (eq. 26) ──► tau
//! ```
//!
//! The plant and the sensors stay outside: the caller samples its robot (or a simulator)
//! into a [`Measurement`], calls [`ClosedLoop::step`], and sends [`ClosedLoop::torque`].
//! After construction a step allocates nothing and never panics.

use std::time::Instant;

use admittance_control::{ControlInput, NeuralController, ReferenceInput, StepStatus};

use crate::parts::{Compliance, EstimateSource, LoopController};
use crate::signal::Measurement;

/// Whether the controller's law subtracts the estimate (docs/method.md section 3, eq. 26:
/// `tau = ... - tau_ext_hat`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EstimateToController {
    /// The paper's law: the controller gets the estimate.
    #[default]
    Passed,
    /// The controller gets zeros while an admittance model shapes the reference (the
    /// estimate acts only through `q_r`).
    OnlyWithoutAdmittance,
}

/// What one step reports.
#[derive(Clone, Copy, Debug)]
pub struct LoopStatus {
    /// The controller's status (a fault means the safe hold was applied).
    pub controller: StepStatus,
    /// Whether the observer's update succeeded (true without an observer).
    pub observer_ok: bool,
}

/// One control period's inputs.
#[derive(Clone, Copy, Debug)]
pub struct LoopInput<'a> {
    /// Time of the sample (s).
    pub time: f64,
    /// Desired position `q_d`.
    pub q_d: &'a [f64],
    /// Desired velocity.
    pub qdot_d: &'a [f64],
    /// Desired acceleration.
    pub qddot_d: &'a [f64],
    /// What the sensors delivered.
    pub measurement: &'a Measurement,
    /// The true external torque: read only by [`EstimateSource::Oracle`] (a simulation
    /// knows it; on a robot pass zeros).
    pub true_external_torque: &'a [f64],
}

/// The parts of a loop, for one wired by hand ([`ClosedLoop::from_config`] builds them from
/// a configuration).
pub struct LoopParts {
    /// The controller.
    pub controller: LoopController,
    /// The admittance model; `None`: `q_r = q_d`.
    pub admittance: Option<Compliance>,
    /// The source of `tau_ext_hat`.
    pub estimate: EstimateSource,
    /// Whether the controller gets the estimate.
    pub estimate_to_controller: EstimateToController,
    /// Control period (s).
    pub dt: f64,
}

/// One control period's wiring: observer -> admittance model -> controller.
pub struct ClosedLoop {
    controller: LoopController,
    admittance: Option<Compliance>,
    estimate_source: EstimateSource,
    estimate_to_controller: EstimateToController,
    dt: f64,
    estimate: Vec<f64>,
    zeros: Vec<f64>,
    q_r: Vec<f64>,
    qdot_r: Vec<f64>,
    qddot_r: Vec<f64>,
    torque: Vec<f64>,
    controller_seconds: f64,
}

impl ClosedLoop {
    /// A loop of `parts` for the controller's joint count (by hand; the usual builder is
    /// [`ClosedLoop::from_config`]).
    pub fn new(mut parts: LoopParts) -> Self {
        let n = parts.controller.as_dyn().dof();
        Self {
            controller: parts.controller,
            admittance: parts.admittance,
            estimate_source: parts.estimate,
            estimate_to_controller: parts.estimate_to_controller,
            dt: parts.dt,
            estimate: vec![0.0; n],
            zeros: vec![0.0; n],
            q_r: vec![0.0; n],
            qdot_r: vec![0.0; n],
            qddot_r: vec![0.0; n],
            torque: vec![0.0; n],
            controller_seconds: 0.0,
        }
    }

    /// One control period: estimate, compliant reference, torque. Lengths are the
    /// controller's joint count (shorter slices are a controller fault, never a panic).
    pub fn step(&mut self, input: &LoopInput<'_>) -> LoopStatus {
        let dt = self.dt;
        let observer_ok = match &mut self.estimate_source {
            EstimateSource::None => {
                self.estimate.fill(0.0);
                true
            }
            EstimateSource::Oracle => {
                let k = input.true_external_torque.len().min(self.estimate.len());
                self.estimate[..k].copy_from_slice(&input.true_external_torque[..k]);
                true
            }
            EstimateSource::Observer(stage) => {
                stage.update(input.time, input.measurement, dt, &mut self.estimate)
            }
        };
        match self.admittance.as_mut() {
            Some(adm) => {
                let _ = adm.step(
                    &ReferenceInput {
                        q_d: input.q_d,
                        qdot_d: input.qdot_d,
                        qddot_d: input.qddot_d,
                        q: &input.measurement.q,
                        external_torque_estimate: &self.estimate,
                    },
                    dt,
                );
                let adm = adm.as_dyn();
                copy(&mut self.q_r, adm.q_r());
                copy(&mut self.qdot_r, adm.qdot_r());
                copy(&mut self.qddot_r, adm.qddot_r());
            }
            None => {
                copy(&mut self.q_r, input.q_d);
                copy(&mut self.qdot_r, input.qdot_d);
                copy(&mut self.qddot_r, input.qddot_d);
            }
        }
        let passed = match self.estimate_to_controller {
            EstimateToController::Passed => true,
            EstimateToController::OnlyWithoutAdmittance => self.admittance.is_none(),
        };
        let m = input.measurement;
        let control = ControlInput {
            time: input.time,
            q: &m.q,
            qdot: &m.qdot,
            q_ref: &self.q_r,
            qdot_ref: &self.qdot_r,
            qddot_ref: &self.qddot_r,
            external_torque_estimate: if passed { &self.estimate } else { &self.zeros },
        };
        let start = Instant::now();
        let controller = self
            .controller
            .as_dyn()
            .step(&control, dt, &mut self.torque);
        self.controller_seconds = start.elapsed().as_secs_f64();
        LoopStatus {
            controller,
            observer_ok,
        }
    }

    /// The command of the last step (N m): finite and within the effort limits.
    pub fn torque(&self) -> &[f64] {
        &self.torque
    }

    /// The external-torque estimate of the last step (N m).
    pub fn external_torque_estimate(&self) -> &[f64] {
        &self.estimate
    }

    /// How well the last step's observer input lies inside its network's training data,
    /// in [0, 1] (the hybrid observer fades its correction by it; docs/method.md section
    /// 8); `None` when the estimate has no learned part that reports one.
    pub fn estimate_coverage(&self) -> Option<f64> {
        match &self.estimate_source {
            EstimateSource::Observer(stage) => stage.coverage(),
            _ => None,
        }
    }

    /// Per joint, the positions `[min, max]` the observer's identification was fitted on
    /// (`IdentificationSummary::training_range`); empty when the estimate runs on no
    /// identification or it records none.
    pub fn observer_training_range(&self) -> &[[f64; 2]] {
        match &self.estimate_source {
            EstimateSource::Observer(stage) => stage.training_range(),
            _ => &[],
        }
    }

    /// Per joint, the highest speed the observer's identification was fitted at
    /// (`IdentificationSummary::training_speed`); empty when the estimate runs on no
    /// identification or it records none.
    pub fn observer_training_speed(&self) -> &[f64] {
        match &self.estimate_source {
            EstimateSource::Observer(stage) => stage.training_speed(),
            _ => &[],
        }
    }

    /// Whether the observer's last input moved faster than its identification's training
    /// speeds (`IdentificationSummary::training_speed`, beyond their margin); false when the
    /// estimate runs on no identification or it records none.
    pub fn observer_faster_than_training(&self) -> bool {
        match &self.estimate_source {
            EstimateSource::Observer(stage) => stage.faster_than_training(),
            _ => false,
        }
    }

    /// The compliant reference `q_r` of the last step.
    pub fn q_r(&self) -> &[f64] {
        &self.q_r
    }

    /// `q_r'`.
    pub fn qdot_r(&self) -> &[f64] {
        &self.qdot_r
    }

    /// `q_r''`.
    pub fn qddot_r(&self) -> &[f64] {
        &self.qddot_r
    }

    /// The admittance model, if any.
    pub fn admittance(&self) -> Option<&Compliance> {
        self.admittance.as_ref()
    }

    /// The admittance model, mutable (a deadband set after construction).
    pub fn admittance_mut(&mut self) -> Option<&mut Compliance> {
        self.admittance.as_mut()
    }

    /// The neural controller, if that is the controller.
    pub fn neural(&self) -> Option<&NeuralController> {
        match &self.controller {
            LoopController::Neural(c) => Some(c),
            LoopController::Other(_) => None,
        }
    }

    /// The neural controller, mutable (dynamic-node events).
    pub fn neural_mut(&mut self) -> Option<&mut NeuralController> {
        match &mut self.controller {
            LoopController::Neural(c) => Some(c),
            LoopController::Other(_) => None,
        }
    }

    /// Wall time of the last controller step (s).
    pub fn controller_seconds(&self) -> f64 {
        self.controller_seconds
    }

    /// The control period (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }
}

/// Copies what fits (the controller reports wrong lengths as a fault).
fn copy(dst: &mut [f64], src: &[f64]) {
    let k = dst.len().min(src.len());
    dst[..k].copy_from_slice(&src[..k]);
}
