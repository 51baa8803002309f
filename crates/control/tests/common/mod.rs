//! Shared by the control integration tests: a small 2-joint arm (URDF text) and a
//! fixed-step simulation of it using `admittance_dynamics::aba`.
#![allow(dead_code)]

use std::sync::Arc;

use admittance_control::{ControlInput, Controller, StepStatus};
use admittance_dynamics::{aba, Data, Model};

/// Two revolute joints about y in a vertical plane (gravity acts on both).
pub const TWO_LINK_URDF: &str = r#"<?xml version="1.0"?>
<robot name="two_link">
  <link name="base"/>
  <link name="link1">
    <inertial>
      <origin xyz="0.15 0 0" rpy="0 0 0"/>
      <mass value="1.0"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
  </link>
  <link name="link2">
    <inertial>
      <origin xyz="0.12 0 0" rpy="0 0 0"/>
      <mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.005"/>
    </inertial>
  </link>
  <link name="tool"/>
  <joint name="j1" type="revolute">
    <parent link="base"/>
    <child link="link1"/>
    <origin xyz="0 0 0" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="30" velocity="5"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="link1"/>
    <child link="link2"/>
    <origin xyz="0.3 0 0" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="20" velocity="5"/>
  </joint>
  <joint name="tool_joint" type="fixed">
    <parent link="link2"/>
    <child link="tool"/>
    <origin xyz="0.25 0 0" rpy="0 0 0"/>
  </joint>
</robot>
"#;

pub fn two_link() -> Arc<Model> {
    Arc::new(
        Model::from_urdf_str(TWO_LINK_URDF, "two_link (test)", None, None).expect("test arm loads"),
    )
}

pub fn baxter() -> Arc<Model> {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/baxter_left_arm.urdf");
    Arc::new(
        Model::from_urdf_file(&path, Some("base"), Some("left_hand")).expect("Baxter model loads"),
    )
}

/// Actuator deadzone of docs/method.md section 1 (eq. 17), symmetric, unit slopes.
pub fn deadzone(tau: f64, d: f64) -> f64 {
    if tau >= d {
        tau - d
    } else if tau <= -d {
        tau + d
    } else {
        0.0
    }
}

/// A desired trajectory: position, velocity, acceleration at time t.
pub type Trajectory = dyn Fn(f64, &mut [f64], &mut [f64], &mut [f64]);

pub struct SimOptions {
    pub duration: f64,
    pub control_dt: f64,
    pub substeps: usize,
    /// Deadzone half-width per joint (0: none).
    pub deadzone: Vec<f64>,
    /// Viscous friction per joint (unknown to the controller).
    pub viscous: Vec<f64>,
}

impl SimOptions {
    pub fn new(n: usize, duration: f64) -> Self {
        SimOptions {
            duration,
            control_dt: 1e-3,
            substeps: 5,
            deadzone: vec![0.0; n],
            viscous: vec![0.0; n],
        }
    }
}

pub struct SimLog {
    pub time: Vec<f64>,
    /// Tracking error q_r - q per control step.
    pub error: Vec<Vec<f64>>,
    /// Commanded torque per control step.
    pub torque: Vec<Vec<f64>>,
    pub faults: usize,
}

impl SimLog {
    /// RMS of joint `j`'s error over `[t0, t1)`.
    pub fn rms(&self, j: usize, t0: f64, t1: f64) -> f64 {
        let (mut s, mut k) = (0.0, 0usize);
        for (t, e) in self.time.iter().zip(&self.error) {
            if *t >= t0 && *t < t1 {
                s += e[j] * e[j];
                k += 1;
            }
        }
        (s / k.max(1) as f64).sqrt()
    }

    pub fn max_abs(&self, j: usize, t0: f64, t1: f64) -> f64 {
        self.time
            .iter()
            .zip(&self.error)
            .filter(|(t, _)| **t >= t0 && **t < t1)
            .map(|(_, e)| e[j].abs())
            .fold(0.0, f64::max)
    }
}

/// Runs `controller` on the true `plant` model tracking `traj` (the reference is the
/// desired trajectory itself, no admittance), measuring the exact state, with zero-order
/// hold of the torque over `substeps` semi-implicit Euler plant steps. `each_step` is called
/// after every control step (for logging weight norms etc.).
pub fn simulate<C: Controller + ?Sized>(
    controller: &mut C,
    plant: &Model,
    traj: &Trajectory,
    opts: &SimOptions,
    mut each_step: impl FnMut(f64, &C),
) -> SimLog {
    let n = plant.nq();
    let mut data = Data::new(plant);
    let (mut qd, mut vd, mut ad) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    traj(0.0, &mut qd, &mut vd, &mut ad);
    let mut q = qd.clone();
    let mut v = vd.clone();
    let mut tau = vec![0.0; n];
    let mut applied = vec![0.0; n];
    let zero = vec![0.0; n];
    let steps = (opts.duration / opts.control_dt).round() as usize;
    let h = opts.control_dt / opts.substeps as f64;
    let mut log = SimLog {
        time: Vec::with_capacity(steps),
        error: Vec::new(),
        torque: Vec::new(),
        faults: 0,
    };
    for k in 0..steps {
        let t = k as f64 * opts.control_dt;
        traj(t, &mut qd, &mut vd, &mut ad);
        let input = ControlInput {
            time: t,
            q: &q,
            qdot: &v,
            q_ref: &qd,
            qdot_ref: &vd,
            qddot_ref: &ad,
            external_torque_estimate: &zero,
        };
        let status = controller.step(&input, opts.control_dt, &mut tau);
        if status != StepStatus::Ok {
            log.faults += 1;
        }
        log.time.push(t);
        log.error
            .push(qd.iter().zip(&q).map(|(a, b)| a - b).collect());
        log.torque.push(tau.clone());
        each_step(t, &*controller);
        for _ in 0..opts.substeps {
            for i in 0..n {
                applied[i] = deadzone(tau[i], opts.deadzone[i]) - opts.viscous[i] * v[i];
            }
            let a = aba(plant, &mut data, &q, &v, &applied).expect("plant step");
            for i in 0..n {
                v[i] += h * a[i];
                q[i] += h * v[i];
            }
        }
    }
    log
}

/// The sine trajectory used by the closed-loop tests (2 joints).
pub fn sine(t: f64, q: &mut [f64], v: &mut [f64], a: &mut [f64]) {
    let (w1, w2) = (2.0, 3.0);
    q[0] = 0.5 * (w1 * t).sin();
    v[0] = 0.5 * w1 * (w1 * t).cos();
    a[0] = -0.5 * w1 * w1 * (w1 * t).sin();
    q[1] = 0.4 + 0.3 * (w2 * t).cos();
    v[1] = -0.3 * w2 * (w2 * t).sin();
    a[1] = -0.3 * w2 * w2 * (w2 * t).cos();
}
