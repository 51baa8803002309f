//! The library in a 1 kHz control loop: the paper's neural controller tracking a compliant
//! reference from the admittance model, driven by a momentum observer's external-torque
//! estimate. Everything is built once; each tick only calls `update`/`step`, which never
//! allocate and never panic.
//!
//! The "robot" here is a stand-in (the rigid-body model integrated with semi-implicit Euler,
//! a push of 2 N m on s0 from 1 s to 2 s); on a real arm, `read_encoders` and
//! `send_torques` talk to its driver.
//!
//! Run: `cargo run --release -p admittance-cli --example control_loop`

use std::sync::Arc;

use admittance_control::{
    Admittance, AdmittanceConfig, AdmittanceInput, ControlInput, Controller, MomentumObserver,
    MomentumObserverConfig, NeuralController, NeuralControllerConfig, Observer, ObserverInput,
    StepStatus,
};
use admittance_dynamics::{aba, Data, Model};

/// A stand-in for the arm: integrates the model under the commanded torque.
struct SimulatedArm {
    model: Arc<Model>,
    data: Data,
    q: Vec<f64>,
    qdot: Vec<f64>,
    /// Work buffer: the commanded torque plus the push.
    total: Vec<f64>,
}

impl SimulatedArm {
    fn read_encoders(&self) -> (&[f64], &[f64]) {
        (&self.q, &self.qdot)
    }

    fn send_torques(&mut self, tau: &[f64], push: &[f64], dt: f64) {
        for ((t, a), b) in self.total.iter_mut().zip(tau).zip(push) {
            *t = a + b;
        }
        if let Ok(qddot) = aba(
            &self.model,
            &mut self.data,
            &self.q,
            &self.qdot,
            &self.total,
        ) {
            for i in 0..self.q.len() {
                self.qdot[i] += dt * qddot[i];
                self.q[i] += dt * self.qdot[i];
            }
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/baxter_left_arm.urdf"
    );
    let model = Arc::new(Model::from_urdf_file(
        urdf.as_ref(),
        Some("base"),
        Some("left_hand"),
    )?);
    let n = model.nq();
    let dt = 1e-3; // 1 kHz

    // Built once, before the loop.
    let mut controller = NeuralController::new(model.clone(), &NeuralControllerConfig::default())?;
    let mut admittance = Admittance::new(n, &AdmittanceConfig::paper())?;
    let mut observer = MomentumObserver::new(model.clone(), &MomentumObserverConfig::default())?;
    let pose = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
    let (zero, mut tau, mut tau_ext_hat) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut qddot_estimate = vec![0.0; n];
    let mut arm = SimulatedArm {
        data: Data::new(&model),
        model: model.clone(),
        q: pose.to_vec(),
        qdot: zero.clone(),
        total: zero.clone(),
    };
    let mut qdot_before = zero.clone();
    let mut q_d = pose.to_vec();
    let mut qdot_d = zero.clone();
    let mut qddot_d = zero.clone();
    let mut push = zero.clone();

    for tick in 0..3000 {
        let time = tick as f64 * dt;
        // The desired motion: s0 = 0.3 sin(t).
        (q_d[0], qdot_d[0], qddot_d[0]) = (0.3 * time.sin(), 0.3 * time.cos(), -0.3 * time.sin());
        let (q, qdot) = arm.read_encoders();

        // External-torque estimate from the measured state and the last command.
        let input = ObserverInput {
            time,
            q,
            qdot,
            qddot: &qddot_estimate,
            tau_commanded: &tau,
        };
        if let StepStatus::Fault(f) = observer.update(&input, dt, &mut tau_ext_hat) {
            eprintln!("observer fault at {time:.3} s: {f:?}");
        }
        // Compliant reference q_r from the admittance model.
        let input = AdmittanceInput {
            q_d: &q_d,
            qdot_d: &qdot_d,
            qddot_d: &qddot_d,
            external_torque_estimate: &tau_ext_hat,
        };
        if let StepStatus::Fault(f) = admittance.step(&input, dt) {
            eprintln!("admittance fault at {time:.3} s: {f:?} (reference held)");
        }
        // The controller tracks q_r.
        let input = ControlInput {
            time,
            q,
            qdot,
            q_ref: admittance.q_r(),
            qdot_ref: admittance.qdot_r(),
            qddot_ref: admittance.qddot_r(),
            external_torque_estimate: &tau_ext_hat,
        };
        if let StepStatus::Fault(f) = controller.step(&input, dt, &mut tau) {
            eprintln!("controller fault at {time:.3} s: {f:?} (safe hold applied)");
        }

        push[0] = if (1.0..2.0).contains(&time) { 2.0 } else { 0.0 };
        qdot_before.copy_from_slice(&arm.qdot);
        arm.send_torques(&tau, &push, dt);
        for i in 0..n {
            qddot_estimate[i] = (arm.qdot[i] - qdot_before[i]) / dt;
        }
        if tick % 500 == 0 {
            println!(
                "t = {time:.1} s  q_d[s0] = {:+.3}  q_r[s0] = {:+.3}  q[s0] = {:+.3}  tau_ext_hat[s0] = {:+.2} N m",
                q_d[0], admittance.q_r()[0], arm.q[0], tau_ext_hat[0]
            );
        }
    }
    Ok(())
}
