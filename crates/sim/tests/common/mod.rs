//! Shared helpers of the simulator's integration tests.
#![allow(dead_code)]

use admittance_dynamics::Model;
use admittance_sim::{Integrator, PlantConfig};

pub const BAXTER: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../models/baxter_left_arm.urdf"
);

pub fn baxter() -> Model {
    Model::from_urdf_file(BAXTER.as_ref(), Some("base"), Some("left_hand")).expect("baxter model")
}

/// A mid-range pose of the Baxter arm (the middle of each joint's limits).
pub fn mid_pose(model: &Model) -> Vec<f64> {
    model
        .position_limits()
        .map(|(lo, hi)| 0.5 * (lo + hi))
        .collect()
}

/// A one-joint arm: a body of inertia `izz` about a vertical revolute axis through its
/// centre of mass, so gravity exerts no torque on it.
pub fn one_joint_urdf(izz: f64) -> String {
    format!(
        r#"<robot name="one_joint">
  <link name="base"/>
  <link name="arm">
    <inertial>
      <origin xyz="0 0 0" rpy="0 0 0"/>
      <mass value="1.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="{izz}"/>
    </inertial>
  </link>
  <joint name="j" type="revolute">
    <parent link="base"/>
    <child link="arm"/>
    <origin xyz="0 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="10"/>
  </joint>
</robot>"#
    )
}

pub fn one_joint(izz: f64) -> Model {
    Model::from_urdf_str(&one_joint_urdf(izz), "one_joint", Some("base"), Some("arm"))
        .expect("one-joint model")
}

/// A plant configuration at `rate_hz` with the command held for one plant step.
pub fn config(rate_hz: f64, integrator: Integrator) -> PlantConfig {
    PlantConfig {
        rate_hz,
        control_rate_hz: rate_hz,
        integrator,
        ..PlantConfig::default()
    }
}

pub const INTEGRATORS: [Integrator; 2] = [Integrator::SemiImplicitEuler, Integrator::Rk4Split];
