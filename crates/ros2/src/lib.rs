//! ROS 2 without ROS (issue 24, part 3): `admittance ros2 bridge` subscribes to a robot's
//! `sensor_msgs/JointState` topic (best-effort; which fields give q, qdot, tau comes from
//! the bag profiles of `admittance import`), steps the robot's loop of a deployment folder
//! (`admittance deploy`; `admittance_loop::RobotLoop`, the loop `adm_create` wraps) on each
//! message
//! and publishes, reliably, the estimated external joint torques (a JointState whose
//! `effort` is the estimate: Franka's `external_joint_torques` convention) and the hand
//! wrench (`geometry_msgs/WrenchStamped`, `frame_id` naming its axes).
//!
//! DDS is RustDDS through `ros2-client`: no ROS installation. The messages are the serde
//! structs of `admittance_bag::msgs` (declared once, for the bag import and here).
//!
//! * [`bridge`]: the logic without DDS ([`bridge::Bridge::process`]), also run offline
//!   ([`bridge::offline`]);
//! * [`node`]: the DDS node, and a fake arm that stands in for a robot;
//! * [`cli`]: the arguments of `admittance ros2 ...` and `admittance-ros2 ...`;
//! * [`stats`]: counts and latency percentiles.
//!
//! docs/ros2.md: use, QoS, distributions, what was measured.
#![warn(missing_docs)]

pub mod bridge;
pub mod cli;
pub mod node;
pub mod stats;

pub use bridge::{
    contact_message, offline, status_message, Bridge, BridgeConfig, InputError, InputMap, Stepped,
    WrenchFrame, CONTACT_LABEL, STATUS_LABEL,
};
