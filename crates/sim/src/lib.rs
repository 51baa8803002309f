//! Simulation layer of `admittance`: the plant that stands in for the robot
//! (docs/method.md section 1) and its fake encoders; what is real of the measurement (filters,
//! differentiation) is `admittance_loop`'s.
//!
//! * [`plant`]: the true arm: rigid-body dynamics of a (possibly perturbed) model,
//!   friction, actuator deadzone and effort limits, the counterbalance spring; fixed-step
//!   integration at the plant rate with zero-order hold of the command.
//! * [`environment`]: joint-space spring-damper-mass, Cartesian wall, scripted torques and
//!   forces, each in a time window.
//! * [`integrator`]: semi-implicit Euler (MuJoCo's scheme) and the default RK4 split,
//!   both with implicit friction.
//! * [`sensors`]: the fake encoders: quantisation and noise, fault injection, in front
//!   of the real signal chain of `admittance_loop` (filtered differentiation).
//!
//! ```
//! use admittance_dynamics::Model;
//! use admittance_sim::{Plant, PlantConfig, Sensors};
//! let model = Model::from_urdf_file("../../models/baxter_left_arm.urdf".as_ref(), Some("base"), Some("left_hand")).unwrap();
//! let mut config = PlantConfig::default();
//! config.spring.enabled = true;
//! let mut plant = Plant::new(&model, &config).unwrap();
//! let mut sensors = Sensors::new(&model, &config.sensors, config.control_rate_hz).unwrap();
//! let tau = [0.0; 7];
//! for _ in 0..10 {
//!     plant.step_control(&tau).unwrap();
//!     let m = sensors.sample(plant.time(), plant.q(), &tau).unwrap();
//!     assert!(m.q.iter().all(|q| q.is_finite()));
//! }
//! ```

// Scenario errors carry the file, line, key and hint by value; they are the cold path,
// returned once per bad file, so their size is not worth a box on every signature.
#![allow(clippy::result_large_err)]
#![warn(missing_docs)]

mod checks;
mod environment;
mod integrator;
mod plant;
mod sensors;

pub use environment::{
    Anchor, Environment, EnvironmentConfig, JointSpringConfig, JointTorqueProfileConfig,
    TipForceProfileConfig, WallConfig,
};
pub use integrator::Integrator;
pub use plant::actuator::{clamp_effort, Deadzone};
pub use plant::config::{
    DeadzoneConfig, FrictionConfig, FrictionSolve, PayloadConfig, PlantConfig, Solver,
    SpringConfig, SpringModel,
};
pub use plant::error::SimError;
pub use plant::friction::Friction;
pub use plant::{Plant, PlantCounters, StepRecord};
pub use sensors::{FaultConfig, FaultKind, SensorConfig, Sensors, DEFAULT_SPIKE_VALUE};
