//! The serde configuration of a loop ([`LoopConfig`]): what a scenario file (or a Python
//! dict) says about the controller, the admittance model and the external-torque estimate.
//! Every table rejects unknown keys; every field has a unit (where it has one) and a
//! default, stated in its documentation.
//!
//! ```toml
//! control_rate_hz = 1000.0     # Hz; in a scenario file: plant.control_rate_hz
//!
//! [controller]
//! kind = "neural"              # "neural" | "pd" | "computed_torque"
//! subtract_estimate = true     # eq. 26: tau = ... - tau_ext_hat
//! [controller.neural]          # NeuralControllerConfig (also [controller.pd], [controller.computed_torque])
//!
//! [admittance]                 # joint space (eq. 5-7); or [task_admittance]: the hand's
//! enabled = true
//! inertia = [0.1, ...]         # AdmittanceConfig, flattened
//!
//! [observer]                   # the estimate
//! kind = "momentum"            # "none" | "oracle" | "momentum" | "learned" | "hybrid"
//! nominal_inertia_scale = 1.0
//! cutoff_hz = 5.0              # Hz, first-order low-pass of the estimate; 0: none
//! input_filter_hz = 0.0        # Hz, second low-pass of the observer's inputs; 0: none
//! warmup = 0.5                 # s, estimate held at zero
//! identification = "ident.json" # the momentum part's nominal model (admittance identify)
//! network = "observer.broad"    # learned / hybrid: the trained network (admittance train)
//! [observer.momentum]          # MomentumObserverConfig
//! ```

use admittance_control::{
    AdmittanceConfig, ComputedTorqueConfig, MomentumObserverConfig, NeuralControllerConfig,
    PdConfig, TaskSpaceAdmittanceConfig,
};
use serde::{Deserialize, Deserializer, Serialize};

/// The control rate a loop runs at unless told otherwise (Hz).
pub const DEFAULT_CONTROL_RATE_HZ: f64 = 1000.0;

/// Everything a [`crate::ClosedLoop`] is built from, besides the arm's model and the
/// trained networks ([`crate::ClosedLoop::from_config`]).
///
/// `Training` is what the application that trains the learned observers' networks reads
/// under `[observer.training]`; a loop itself is given the trained networks, and
/// [`NoTraining`] (the default) refuses the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoopConfig<Training = NoTraining> {
    /// Control rate (Hz): one [`crate::ClosedLoop::step`] per period `1 / control_rate_hz`.
    /// Default 1000. A scenario file sets it as `plant.control_rate_hz`.
    #[serde(default = "default_control_rate_hz")]
    pub control_rate_hz: f64,
    /// The controller (`[controller]`).
    pub controller: ControllerConfig,
    /// The joint-space admittance model (`[admittance]`); absent: `q_r = q_d`.
    #[serde(default)]
    pub admittance: Option<JointAdmittanceConfig>,
    /// The task-space admittance model at the hand (`[task_admittance]`), exclusive with an
    /// enabled `[admittance]`. Default: absent.
    #[serde(default)]
    pub task_admittance: Option<TaskSpaceAdmittanceConfig>,
    /// The external-torque estimate (`[observer]`). Default: none (zeros).
    #[serde(default = "ObserverConfig::default")]
    pub observer: ObserverConfig<Training>,
}

fn default_control_rate_hz() -> f64 {
    DEFAULT_CONTROL_RATE_HZ
}

/// Which controller runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// The paper's adaptive neural controller (docs/method.md section 3).
    Neural,
    /// Joint PD (optionally with nominal gravity compensation).
    Pd,
    /// Computed torque with the nominal model.
    ComputedTorque,
}

/// The controller section: a kind and the settings of each kind (only the chosen one is
/// used, so variants can switch kinds).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerConfig {
    /// The controller that runs (no default).
    pub kind: ControllerKind,
    /// Settings of the neural controller. Default: `NeuralControllerConfig::default()`.
    #[serde(default)]
    pub neural: NeuralControllerConfig,
    /// Settings of the PD controller; required by `kind = "pd"`.
    #[serde(default)]
    pub pd: Option<PdConfig>,
    /// Settings of computed torque; required by `kind = "computed_torque"`.
    #[serde(default)]
    pub computed_torque: Option<ComputedTorqueConfig>,
    /// Whether the control law subtracts the external-torque estimate (docs/method.md section 3,
    /// the paper's eq. 26: `tau = ... - tau_ext_hat`). Default true. With false and an
    /// admittance model, the estimate acts only through the compliant reference
    /// (docs/experiments.md shows both on experiment B).
    #[serde(default = "yes")]
    pub subtract_estimate: bool,
}

/// The joint-space admittance section (`[admittance]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointAdmittanceConfig {
    /// Whether the reference is shaped by the admittance model (otherwise `q_r = q_d`).
    /// Default true.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// The model (eq. 5-6) and its saturation (eq. 7).
    #[serde(flatten)]
    pub config: AdmittanceConfig,
}

fn yes() -> bool {
    true
}

/// Where the external-torque estimate that drives the admittance model comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObserverKind {
    /// No estimate (zeros).
    #[default]
    None,
    /// The true external torque of the plant (an upper bound for any observer; a
    /// simulation knows it).
    Oracle,
    /// The generalised-momentum observer with a nominal model (docs/method.md section 5,
    /// baseline): settings in `[observer.momentum]`, model error in `nominal_inertia_scale`.
    Momentum,
    /// The paper's learned observer (eq. 19): a flat RBF network trained on free-motion
    /// data predicts the free-motion torque.
    Learned,
    /// The momentum observer with a flat RBF network trained on what its nominal model
    /// misses in free motion (`admittance_control::HybridObserver`).
    Hybrid,
}

impl ObserverKind {
    /// Whether the observer needs a trained network.
    pub fn is_learned(self) -> bool {
        matches!(self, ObserverKind::Learned | ObserverKind::Hybrid)
    }
}

/// The estimate section (`[observer]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverConfig<Training = NoTraining> {
    /// The estimate's source. Default `none`.
    #[serde(default)]
    pub kind: ObserverKind,
    /// The observer's nominal model is the arm's model with every link mass and inertia
    /// multiplied by this (0.8: a 20% model error). Default 1. Used by `momentum` and
    /// `hybrid`.
    #[serde(default = "unit")]
    pub nominal_inertia_scale: f64,
    /// An identification file of this arm (`admittance identify`, docs/outputs.md): the
    /// momentum observer runs on the identified model with its joint terms (docs/method.md
    /// section 8) instead of the URDF. Default: absent. Used by `momentum` and `hybrid`
    /// (whose network must have learned this identification's residual); with it
    /// `nominal_inertia_scale` must stay 1. A relative path is taken from the scenario
    /// file's folder (by the scenario runner) or the working directory.
    #[serde(default)]
    pub identification: Option<std::path::PathBuf>,
    /// The trained network of `learned` and `hybrid` (a file of `admittance train`,
    /// `adm.train` or a scenario's training cache): the loop loads it and checks that it
    /// was made for this arm. Default: absent (the caller hands the loop its network, or
    /// the scenario runner trains it from `[observer.training]`). A relative path is taken
    /// as `identification`'s.
    #[serde(default)]
    pub network: Option<std::path::PathBuf>,
    /// Cut-off (Hz) of a first-order low-pass applied to the estimate of every observer
    /// but `oracle` (docs/method.md sections 5 and 7); 0 disables it. Default 0.
    #[serde(default)]
    pub cutoff_hz: f64,
    /// Cut-off (Hz) of a second 2nd-order low-pass on the angles and torques every observer
    /// but `oracle` is fed, with velocities and accelerations differentiated again after it
    /// ([`crate::InputConditioner`]); the learned observers' training data pass the same
    /// stage. Below half the control rate; 0 (default) feeds the sensors' signals as they
    /// are.
    #[serde(default)]
    pub input_filter_hz: f64,
    /// Warm-up (s): the estimate of every observer but `oracle` is held at zero for this
    /// long after the start while the observer runs, so that the start-up transients of
    /// the sensors' and the observer's filters (the torque filters start from zero
    /// command) do not reach the admittance model. Default 0.5 s.
    #[serde(default = "default_warmup")]
    pub warmup: f64,
    /// Settings of the momentum observer (also the momentum part of `hybrid`). Default:
    /// `MomentumObserverConfig::default()`.
    #[serde(default)]
    pub momentum: MomentumObserverConfig,
    /// How the network of `learned` and `hybrid` is trained: read by the application
    /// that trains it (the scenario runner's `[observer.training]`). Default: absent.
    #[serde(default = "Option::default")]
    pub training: Option<Training>,
}

impl<Training> Default for ObserverConfig<Training> {
    fn default() -> Self {
        Self {
            kind: ObserverKind::None,
            nominal_inertia_scale: unit(),
            identification: None,
            network: None,
            cutoff_hz: 0.0,
            input_filter_hz: 0.0,
            warmup: default_warmup(),
            momentum: MomentumObserverConfig::default(),
            training: None,
        }
    }
}

fn unit() -> f64 {
    1.0
}

fn default_warmup() -> f64 {
    0.5
}

/// The `Training` of a loop that is given its trained networks: an `[observer.training]`
/// table is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum NoTraining {}

impl<'de> Deserialize<'de> for NoTraining {
    fn deserialize<D: Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom(
            "a loop is given its trained networks: `observer.training` is read by the scenario runner, not by the loop",
        ))
    }
}
