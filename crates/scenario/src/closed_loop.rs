//! The wiring of one control period (docs/method.md sections 2-5), the only place it exists:
//! the runner, the 1 kHz example and the Python package all step a [`ClosedLoop`].
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

use admittance_control::{
    Admittance, CompliantReference, ControlInput, Controller, NeuralController, Observer,
    ObserverInput, ReferenceInput, Saturation, StepStatus, TaskSpaceAdmittance,
};
use admittance_sim::{InputConditioner, Measurement};

/// The controller of a loop, with the neural one kept reachable for its node events.
pub enum LoopController {
    /// The paper's adaptive neural controller.
    Neural(Box<NeuralController>),
    /// Any other controller.
    Other(Box<dyn Controller + Send>),
}

impl LoopController {
    fn as_dyn(&mut self) -> &mut dyn Controller {
        match self {
            LoopController::Neural(c) => c.as_mut(),
            LoopController::Other(c) => c.as_mut(),
        }
    }
}

/// An observer with what it is fed: the sensors' signals, optionally through a second
/// conditioning stage (`observer.input_filter_hz`), its estimate low-passed and held at
/// zero during a warm-up.
pub struct ObserverStage {
    observer: Box<dyn Observer + Send>,
    conditioner: Option<InputConditioner>,
    delayed_torque: bool,
    previous_filtered_torque: Vec<f64>,
    raw: Vec<f64>,
    alpha: f64,
    warmup: f64,
}

impl ObserverStage {
    /// `observer` fed through `conditioner` (if any); `delayed_torque`: feed the filtered
    /// command one sample late (the pairing with `q''` of the free-motion data the learned
    /// networks were trained on, docs/outputs.md); the estimate is low-passed at
    /// `cutoff_hz` (0: not filtered) at the control period `dt`, and zero before `warmup` s.
    pub fn new(
        observer: Box<dyn Observer + Send>,
        conditioner: Option<InputConditioner>,
        delayed_torque: bool,
        cutoff_hz: f64,
        warmup: f64,
        dt: f64,
    ) -> Self {
        let n = observer.dof();
        // First-order low-pass of the estimate: alpha = dt / (dt + 1 / (2 pi f_c)).
        let alpha = if cutoff_hz > 0.0 {
            dt / (dt + 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz))
        } else {
            1.0
        };
        Self {
            observer,
            conditioner,
            delayed_torque,
            previous_filtered_torque: vec![0.0; n],
            raw: vec![0.0; n],
            alpha,
            warmup,
        }
    }

    /// Updates `estimate` from the measurement at `time`; false when the observer
    /// reported a fault.
    fn update(&mut self, time: f64, m: &Measurement, dt: f64, estimate: &mut [f64]) -> bool {
        let tau_in: &[f64] = if self.delayed_torque {
            &self.previous_filtered_torque
        } else {
            &m.tau_filtered
        };
        let input = match self.conditioner.as_mut() {
            Some(c) => {
                c.update(&m.q_filtered, tau_in);
                ObserverInput {
                    time,
                    q: &c.q,
                    qdot: &c.qdot,
                    qddot: &c.qddot,
                    tau_commanded: &c.tau,
                }
            }
            None => ObserverInput {
                time,
                q: &m.q_filtered,
                qdot: &m.qdot,
                qddot: &m.qddot,
                tau_commanded: tau_in,
            },
        };
        let ok = self.observer.update(&input, dt, &mut self.raw).is_ok();
        if time < self.warmup {
            self.raw.fill(0.0);
        }
        for (e, r) in estimate.iter_mut().zip(&self.raw) {
            *e += self.alpha * (r - *e);
        }
        self.previous_filtered_torque
            .copy_from_slice(&m.tau_filtered);
        ok
    }
}

/// The admittance model that shapes the reference: joint space (docs/method.md section 2,
/// eq. 5-7 per joint) or task space (the hand's pose, `f_ext_hat = J^{+T} tau_ext_hat`).
#[allow(clippy::large_enum_variant)] // built once per loop
pub enum Compliance {
    /// `C_d (q_a' - q_d') + G_d (q_a - q_d) = tau_ext_hat`, saturated.
    Joint(Admittance),
    /// The hand's admittance mapped to the joints by differential inverse kinematics.
    Task(Box<TaskSpaceAdmittance>),
}

impl Compliance {
    fn as_dyn(&self) -> &dyn CompliantReference {
        match self {
            Compliance::Joint(a) => a,
            Compliance::Task(a) => a.as_ref(),
        }
    }

    fn as_dyn_mut(&mut self) -> &mut dyn CompliantReference {
        match self {
            Compliance::Joint(a) => a,
            Compliance::Task(a) => a.as_mut(),
        }
    }

    /// One step from the desired trajectory, the measured angles and the estimate.
    pub fn step(&mut self, input: &ReferenceInput<'_>, dt: f64) -> StepStatus {
        self.as_dyn_mut().step_reference(input, dt)
    }

    /// `q_r`.
    pub fn q_r(&self) -> &[f64] {
        self.as_dyn().q_r()
    }

    /// The reference saturation (eq. 7), if any.
    pub fn saturation(&self) -> Option<&Saturation> {
        self.as_dyn().saturation()
    }

    /// The task-space model, if that is the kind.
    pub fn task_space(&self) -> Option<&TaskSpaceAdmittance> {
        match self {
            Compliance::Task(a) => Some(a),
            Compliance::Joint(_) => None,
        }
    }
}

/// Where the external-torque estimate comes from.
pub enum EstimateSource {
    /// No estimate: zeros.
    None,
    /// The true external torque (an upper bound for any observer).
    Oracle,
    /// An observer.
    Observer(Box<ObserverStage>),
}

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

/// The parts of a loop, built by the scenario assembly or by hand.
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
    /// A loop of `parts` for the controller's joint count.
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
