//! The parts a [`crate::ClosedLoop`] is made of: its controller, its admittance model (joint
//! or task space) and the source of its external-torque estimate.

use admittance_control::{
    Admittance, CompliantReference, ConfigError, Controller, NeuralController, ReferenceInput,
    Saturation, StepStatus, TaskSpaceAdmittance,
};

use crate::stage::ObserverStage;

/// The controller of a loop, with the neural one kept reachable for its node events.
pub enum LoopController {
    /// The paper's adaptive neural controller.
    Neural(Box<NeuralController>),
    /// Any other controller.
    Other(Box<dyn Controller + Send>),
}

impl LoopController {
    pub(crate) fn as_dyn(&mut self) -> &mut dyn Controller {
        match self {
            LoopController::Neural(c) => c.as_mut(),
            LoopController::Other(c) => c.as_mut(),
        }
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
    pub(crate) fn as_dyn(&self) -> &dyn CompliantReference {
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

    /// Sets a deadband on the estimate per joint (N m), e.g. a contact floor's contact
    /// thresholds (issue 31: an untouched arm does not drift); see
    /// [`Admittance::with_deadband`].
    pub fn set_deadband(&mut self, deadband: &[f64]) -> Result<(), ConfigError> {
        match self {
            Compliance::Joint(a) => a.set_deadband(deadband),
            Compliance::Task(a) => a.set_deadband(deadband),
        }
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
