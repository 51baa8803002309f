//! Controllers of `admittance` (docs/method.md sections 2-4; issue 3, part "control").
//!
//! * [`Controller`]: the small interface every controller implements, so that the paper's
//!   method and the baselines run in one harness ([`ControlInput`] in, torque out,
//!   [`StepStatus`] back).
//! * [`SafeHold`]: input validation, staleness detection and the safe output on faults
//!   ("hold with damping": `tau = G_nominal(q_hold) - K_hold qdot`, clamped).
//! * [`Admittance`]: the admittance model `C_d (q_a' - q_d') + G_d (q_a - q_d) = tau_ext_hat`
//!   (optionally with `M_d`) and the smooth reference saturation of eq. 7 (docs/method.md
//!   section 2).
//! * [`NeuralController`]: the paper's adaptive RBF controller (docs/method.md section 3,
//!   eq. 24-27 with METHOD's sign set), lumped or split f networks, the deadzone
//!   compensation network, and the dynamic-node hooks (discard/grow, docs/method.md section 4).
//! * Baselines: [`PdController`] (PD, PD + nominal gravity) and
//!   [`ComputedTorqueController`].
//! * [`Observer`]: the interface of external-torque estimators, with [`NoObserver`] and
//!   [`OracleObserver`]; [`MomentumObserver`], the generalised-momentum observer with a
//!   nominal model (docs/method.md section 5, baseline); [`LearnedObserver`], the flat RBF
//!   network's estimate `f_hat(q, q', q'') - tau`, low-pass filtered (eq. 19).
//!
//! Every `step`/`update` is allocation-free and panic-free after construction, and every
//! torque written is finite and within the effort limits. Configurations are serde structs
//! with `deny_unknown_fields`; construction errors are [`ConfigError`]s naming the key.
//!
//! ```
//! use std::sync::Arc;
//! use admittance_control::*;
//! use admittance_dynamics::Model;
//!
//! let model = Arc::new(Model::from_urdf_file("../../models/baxter_left_arm.urdf".as_ref(), Some("base"), Some("left_hand")).unwrap());
//! let mut nn = NeuralController::new(model.clone(), &NeuralControllerConfig::default()).unwrap();
//! let q = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
//! let zero = [0.0; 7];
//! let input = ControlInput { time: 0.0, q: &q, qdot: &zero, q_ref: &q, qdot_ref: &zero, qddot_ref: &zero, external_torque_estimate: &zero };
//! let mut tau = [0.0; 7];
//! assert!(nn.step(&input, 1e-3, &mut tau).is_ok());
//! assert!(tau.iter().all(|t| t.is_finite()));
//! assert_eq!(nn.node_count(NetworkId::F), 512);
//! ```

#![warn(missing_docs)]

mod admittance;
mod baselines;
mod config;
mod contact;
mod controller;
mod error;
pub mod gains;
mod hybrid;
mod learned;
mod momentum;
mod neural;
mod number_or_list;
mod observer;
mod reference;
mod safe_hold;
mod task_space;
mod wrench;

pub use admittance::{
    saturate, Admittance, AdmittanceConfig, AdmittanceInput, Saturation, SaturationConfig,
};
pub use baselines::{ComputedTorqueConfig, ComputedTorqueController, PdConfig, PdController};
pub use config::{AxisValues, JointValues};
pub use contact::{
    calibrate_contact, calibrate_contact_with, soft_deadband, ContactCalibration,
    ContactCalibrationConfig, ContactDetector, ContactFloor, ContactState, LevelShape,
    CONTACT_FLOOR_FORMAT, CONTACT_FLOOR_FORMAT_VERSION, DEADBAND_KNEE,
};
pub use controller::{ControlInput, Controller};
pub use error::{ConfigError, Fault, StepStatus};
pub use hybrid::HybridObserver;
pub use learned::LearnedObserver;
pub use momentum::{MomentumObserver, MomentumObserverConfig};
pub use neural::{
    true_lumped_f, DeadzoneInverseConfig, FNetworkConfig, GrowthProgress, GrowthRequest,
    NetworkConfig, NetworkId, NeuralController, NeuralControllerConfig,
};
pub use observer::{NoObserver, Observer, ObserverInput, OracleObserver};
pub use reference::{CompliantReference, ReferenceInput};
pub use safe_hold::{SafeHold, SafeHoldConfig};
pub use task_space::{
    AxisAdmittanceConfig, InverseKinematicsConfig, SingularityDampingConfig, TaskAxis,
    TaskSaturationConfig, TaskSpaceAdmittance, TaskSpaceAdmittanceConfig, TaskSpaceInput,
};
pub use wrench::{WrenchEstimator, DEFAULT_WRENCH_DAMPING};

/// Re-exports from the learning layer used in the configuration of the networks.
pub use admittance_learning::rbf::{
    GaussianRbfLayer, GrowOutcome, GrowthParams, Integrator, Placement,
};

/// The trained network of the learned observers (`LearnedObserver`, `HybridObserver`), so
/// that a loop built from a configuration can be handed one without naming the learning
/// layer.
pub use admittance_learning::broad::BroadModel;
