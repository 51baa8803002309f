//! One control period of force-sensorless admittance control (docs/method.md sections 2-5 and
//! 7), everything a robot program needs and nothing simulated:
//!
//! * [`ClosedLoop`]: observer -> admittance model -> controller, one period,
//!   allocation-free, built by [`ClosedLoop::from_config`] from a [`LoopConfig`].
//! * [`LoopConfig`]: the serde settings (controller, joint or task admittance, the
//!   estimate, the rate), each with its unit and default, checked once
//!   ([`LoopConfig::problems`]), every error a [`LoopError`] at its dotted key.
//! * [`HealthMonitor`]: the divergence rule, checked every step (the rules on a finished
//!   run's metrics are `admittance_runfolder::health`).
//! * The real signal chain: [`SignalChain`] (low-pass and numerical differentiation of the
//!   encoder angles, the command through the same filter) into a [`Measurement`];
//!   [`InputConditioner`], the observers' second input filter; [`LowPass`].
//!
//! * [`RobotLoop`]: a real robot's period (raw angles and torques in, through the
//!   plausibility gates ([`PlausibilityGates`]) and the signal chain, command, estimate,
//!   wrench and contact flags out), built from a [`RobotConfig`] or a deployment folder
//!   ([`Deployment`], `admittance deploy`); the C ABI, the ROS 2 bridge and Python wrap it.
//!
//! The simulator (`admittance-sim`) puts a fake encoder in front of the same
//! [`SignalChain`]; the scenario runner (`admittance-scenario`) steps a [`ClosedLoop`]
//! against it.
//!
//! ```
//! use admittance_dynamics::Model;
//! use admittance_loop::{ClosedLoop, LoopConfig, LoopInput, SignalChain};
//! let model = Model::from_urdf_file("../../models/baxter_left_arm.urdf".as_ref(), Some("base"), Some("left_hand")).unwrap();
//! let config: LoopConfig = toml::from_str(r#"
//!     [controller]
//!     kind = "pd"
//!     pd = { kp = 100.0, kd = 20.0, gravity_compensation = true }
//!     [observer]
//!     kind = "momentum"
//!     cutoff_hz = 5.0
//! "#).unwrap();
//! let mut closed_loop = ClosedLoop::from_config(&model, &config, None).unwrap();
//! let mut chain = SignalChain::new(7, 20.0, config.control_rate_hz).unwrap();
//! let q = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
//! let zeros = [0.0; 7];
//! for k in 0..10 {
//!     let time = k as f64 / config.control_rate_hz;
//!     let measurement = chain.sample(time, &q, closed_loop.torque()).unwrap();
//!     let status = closed_loop.step(&LoopInput {
//!         time, q_d: &q, qdot_d: &zeros, qddot_d: &zeros,
//!         measurement, true_external_torque: &zeros,
//!     });
//!     assert!(status.observer_ok);
//! }
//! assert!(closed_loop.torque().iter().all(|t| t.is_finite()));
//! ```

#![warn(missing_docs)]

mod build;
mod chain;
mod closed_loop;
mod conditioning;
mod config;
mod continuous;
mod delay;
mod deployment;
mod error;
mod estimate_filter;
mod frozen;
mod gates;
mod health;
mod parts;
mod robot;
mod robot_config;
mod signal;
mod stage;
mod validate;

/// The one shape of a bad setting (issue 32), which [`LoopError::Setting`] holds.
pub use admittance_control::ConfigError;
/// The contact flags a [`RobotStatus`] carries (issue 31).
pub use admittance_control::ContactState;
pub use chain::SignalChain;
pub use closed_loop::{ClosedLoop, EstimateToController, LoopInput, LoopParts, LoopStatus};
pub use conditioning::InputConditioner;
pub use config::{
    ControllerConfig, ControllerKind, JointAdmittanceConfig, LoopConfig, NoTraining,
    ObserverConfig, ObserverKind, DEFAULT_CONTROL_RATE_HZ,
};
pub use delay::InputDelay;
pub use deployment::{
    write_deployment, Deployment, DEPLOYMENT_FORMAT, DEPLOYMENT_VERSION, LOOP_FILE, MANIFEST_FILE,
};
pub use error::LoopError;
pub use estimate_filter::EstimateLowPass;
pub use gates::{GateConfig, GateFault, Implausible, PlausibilityGates};
pub use health::{
    Divergence, HealthMonitor, ESTIMATE_FACTOR, MAX_ANGLE, MIN_SPEED_BOUND, SPEED_FACTOR,
};
pub use parts::{Compliance, EstimateSource, LoopController};
pub use robot::{RobotInput, RobotLoop, RobotStatus};
pub use robot_config::{
    ArmFile, ContactSection, RobotConfig, SignalsConfig, DEFAULT_SIGNAL_CUTOFF_HZ,
    LOOP_FILE_FORMAT, LOOP_FILE_VERSION,
};
pub use signal::{LowPass, Measurement};
pub use stage::{ObserverStage, ObserverStageSettings};
