//! The loop behind a handle, in Rust: the one file of this crate that names the loop's
//! types (`ClosedLoop`, `LoopInput`, `Measurement`, the scenario's assembly), so that moving
//! them to another crate is an edit of this file's imports.
//!
//! One step, as the scenario runner and the 1 kHz example wire it
//! (`crates/cli/examples/control_loop.rs`):
//!
//! ```text
//!   q, tau ──► SignalChain (2nd-order low-pass, backward differences) ──► Measurement
//!   Measurement, q_d ──► ClosedLoop::step (observer -> admittance -> controller) ──► tau_cmd
//! ```
//!
//! The signal chain is the scenario's sensors without their simulated imperfections (no
//! noise, no quantisation, no injected faults: the robot's encoders bring their own): only
//! `plant.sensors.filter_cutoff_hz` and the control rate are read. After [`RustLoop::new`]
//! a step allocates nothing.

use std::path::Path;

use admittance_control::{Fault, StepStatus};
use admittance_dynamics::{tip_jacobian, Data, Model};
use admittance_loop::{ClosedLoop, LoopInput, Measurement, ObserverKind, SignalChain};
use admittance_scenario::{robot_loop, RunOptions, ScenarioSource, Trajectory};
use nalgebra::{Matrix6, Vector6};

use crate::abi::*;

/// What a loop is built from (the Rust side of `AdmConfig`).
#[derive(Clone, Debug)]
pub struct LoopSettings<'a> {
    /// The scenario file.
    pub scenario: &'a Path,
    /// The variant, if any.
    pub variant: Option<&'a str>,
    /// `KEY=VALUE` overrides, applied in order.
    pub overrides: Vec<&'a str>,
    /// `Some(damping)`: estimate the hand wrench each step.
    pub wrench_damping: Option<f64>,
}

/// One period's inputs as slices of the loop's joint count.
#[derive(Clone, Copy, Debug)]
pub struct StepInput<'a> {
    /// Time (s).
    pub time: f64,
    /// Measured positions (rad).
    pub q: &'a [f64],
    /// Measured velocities (rad/s), if any.
    pub qdot: Option<&'a [f64]>,
    /// Measured joint torques (N m), if any; else the last command.
    pub tau: Option<&'a [f64]>,
    /// `q_d`, `q_d'`, `q_d''`, if given; else the scenario's trajectory at `time`.
    pub desired: Option<[&'a [f64]; 3]>,
}

/// What a step reports besides its arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepReport {
    /// `ADM_OUT_*` bits.
    pub flags: u32,
    /// `ADM_FAULT_*`.
    pub fault: i32,
    /// The joint the fault names.
    pub fault_joint: u32,
}

/// The loop of one scenario variant for a robot: signal chain, closed loop, optional wrench.
pub struct RustLoop {
    n: usize,
    joints: Vec<String>,
    model: Model,
    plant: admittance_sim::PlantConfig,
    closed_loop: ClosedLoop,
    sensors: SignalChain,
    measurement: Measurement,
    trajectory: Trajectory,
    /// Seconds the estimate is held at zero (0 without an observer).
    warmup: f64,
    desired: [Vec<f64>; 3],
    tau_in: Vec<f64>,
    zeros: Vec<f64>,
    wrench: Option<Wrench>,
}

impl RustLoop {
    /// Loads the scenario (arm, controller, admittance, observer and its network) and
    /// allocates everything a step uses. Errors name the file, line and key.
    pub fn new(settings: &LoopSettings<'_>) -> Result<Self, String> {
        let path = settings.scenario;
        let mut source = ScenarioSource::load(path).map_err(|e| e.to_string())?;
        for o in &settings.overrides {
            source.set(o).map_err(|e| e.to_string())?;
        }
        let built = robot_loop(&source, path, settings.variant, &RunOptions::default())
            .map_err(|e| e.to_string())?;
        let n = built.joints.len();
        if n > ADM_MAX_JOINTS {
            return Err(format!(
                "{}: [arm] chain has {n} joints, more than ADM_MAX_JOINTS ({ADM_MAX_JOINTS})",
                path.display()
            ));
        }
        let scenario = built.scenario;
        let rate = scenario.plant.control_rate_hz;
        let sensors =
            SignalChain::new(n, scenario.plant.sensors.filter_cutoff_hz, rate).map_err(|e| {
                format!(
                    "{}: plant.sensors / plant.control_rate_hz: {e}",
                    path.display()
                )
            })?;
        let warmup = match scenario.observer.kind {
            ObserverKind::None | ObserverKind::Oracle => 0.0,
            _ => scenario.observer.warmup,
        };
        let wrench = settings
            .wrench_damping
            .map(|d| Wrench::new(&built.model, d))
            .transpose()
            .map_err(|e| format!("AdmConfig.wrench_damping: {e}"))?;
        let measurement = sensors.measurement().clone();
        Ok(Self {
            n,
            joints: built.joints,
            plant: scenario.plant.clone(),
            model: built.model,
            closed_loop: built.closed_loop,
            sensors,
            measurement,
            trajectory: built.trajectory,
            warmup,
            desired: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            tau_in: vec![0.0; n],
            zeros: vec![0.0; n],
            wrench,
        })
    }

    /// The joint count.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Joint names in chain order.
    pub fn joints(&self) -> &[String] {
        &self.joints
    }

    /// The arm.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The scenario's plant section (a simulator standing in for the robot uses it).
    pub fn plant_config(&self) -> &admittance_sim::PlantConfig {
        &self.plant
    }

    /// The control period (s).
    pub fn dt(&self) -> f64 {
        self.closed_loop.dt()
    }

    /// The scenario's desired trajectory at `t` into `q`, `qd`, `qdd`.
    pub fn desired_at(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        self.trajectory.eval(t, q, qd, qdd);
    }

    /// One control period. Slices shorter than the joint count are the caller's bug
    /// (`adm_step` checks `n_joints` before): the controller reports a wrong-length fault.
    pub fn step(&mut self, input: &StepInput<'_>) -> StepReport {
        let n = self.n;
        let mut flags = 0;
        let finite = |s: &[f64]| s.iter().take(n).all(|x| x.is_finite());
        let mut inputs_finite = finite(input.q);
        // The torque the observer pairs with the motion: measured, or the last command.
        match input.tau {
            Some(tau) => {
                inputs_finite &= finite(tau);
                copy(&mut self.tau_in, tau);
            }
            None => self.tau_in.copy_from_slice(self.closed_loop.torque()),
        }
        let q = &input.q[..n.min(input.q.len())];
        if let Ok(m) = self.sensors.sample(input.time, q, &self.tau_in) {
            copy_measurement(&mut self.measurement, m);
        }
        if let Some(qdot) = input.qdot {
            inputs_finite &= finite(qdot);
            copy(&mut self.measurement.qdot, qdot);
        }
        let [q_d, qdot_d, qddot_d] = &mut self.desired;
        match input.desired {
            Some([a, b, c]) => {
                inputs_finite &= finite(a) && finite(b) && finite(c);
                copy(q_d, a);
                copy(qdot_d, b);
                copy(qddot_d, c);
            }
            None => self.trajectory.eval(input.time, q_d, qdot_d, qddot_d),
        }
        let status = self.closed_loop.step(&LoopInput {
            time: input.time,
            q_d,
            qdot_d,
            qddot_d,
            measurement: &self.measurement,
            true_external_torque: &self.zeros,
        });
        if !inputs_finite {
            flags |= ADM_OUT_NONFINITE_INPUT;
        }
        if !status.observer_ok {
            flags |= ADM_OUT_OBSERVER_FAULT;
        }
        if input.time < self.warmup {
            flags |= ADM_OUT_WARMUP;
        }
        let (fault, fault_joint) = match status.controller {
            StepStatus::Ok => (ADM_FAULT_NONE, 0),
            StepStatus::Fault(f) => {
                flags |= ADM_OUT_CONTROLLER_FAULT;
                fault_code(&f)
            }
        };
        if let Some(w) = self.wrench.as_mut() {
            flags |= ADM_OUT_WRENCH;
            w.update(
                &self.model,
                &self.measurement.q,
                self.closed_loop.external_torque_estimate(),
            );
        }
        StepReport {
            flags,
            fault,
            fault_joint,
        }
    }

    /// The command of the last step (N m).
    pub fn torque(&self) -> &[f64] {
        self.closed_loop.torque()
    }

    /// The external-torque estimate of the last step (N m).
    pub fn external_torque_estimate(&self) -> &[f64] {
        self.closed_loop.external_torque_estimate()
    }

    /// `q_r`, `q_r'`, `q_r''` of the last step.
    pub fn reference(&self) -> [&[f64]; 3] {
        [
            self.closed_loop.q_r(),
            self.closed_loop.qdot_r(),
            self.closed_loop.qddot_r(),
        ]
    }

    /// The hand wrench estimate of the last step in the base axes and in the tip's
    /// (force N, moment N m), with a wrench estimator.
    pub fn wrench(&self) -> Option<(&[f64], &[f64])> {
        self.wrench
            .as_ref()
            .map(|w| (w.base.as_slice(), w.tip.as_slice()))
    }
}

/// Copies what fits.
fn copy(dst: &mut [f64], src: &[f64]) {
    let k = dst.len().min(src.len());
    dst[..k].copy_from_slice(&src[..k]);
}

/// Field by field (the derived `clone_from` would allocate).
fn copy_measurement(dst: &mut Measurement, src: &Measurement) {
    dst.time = src.time;
    copy(&mut dst.sample_time, &src.sample_time);
    copy(&mut dst.q, &src.q);
    copy(&mut dst.q_filtered, &src.q_filtered);
    copy(&mut dst.qdot, &src.qdot);
    copy(&mut dst.qddot, &src.qddot);
    copy(&mut dst.tau_commanded, &src.tau_commanded);
    copy(&mut dst.tau_filtered, &src.tau_filtered);
    dst.injected_nan.copy_from_slice(&src.injected_nan);
    dst.injected_stale.copy_from_slice(&src.injected_stale);
}

/// `ADM_FAULT_*` and the joint of a controller fault.
fn fault_code(f: &Fault) -> (i32, u32) {
    match *f {
        Fault::WrongLength { .. } => (ADM_FAULT_WRONG_LENGTH, 0),
        Fault::NonFiniteMeasurement { joint, .. } => {
            (ADM_FAULT_NONFINITE_MEASUREMENT, joint as u32)
        }
        Fault::StaleMeasurement { joint, .. } => (ADM_FAULT_STALE_MEASUREMENT, joint as u32),
        Fault::NonFiniteReference { joint, .. } => (ADM_FAULT_NONFINITE_REFERENCE, joint as u32),
        Fault::NonFiniteEstimate { joint } => (ADM_FAULT_NONFINITE_ESTIMATE, joint as u32),
        Fault::InvalidTimeStep => (ADM_FAULT_INVALID_TIME_STEP, 0),
        Fault::NonFiniteOutput { joint } => (ADM_FAULT_NONFINITE_OUTPUT, joint as u32),
        Fault::Internal(_) => (ADM_FAULT_INTERNAL, 0),
    }
}

/// The hand wrench from the joint estimate: `f = (J J^T + d^2 I)^-1 J tau_ext`, the
/// damped least-squares solution of `J^T f = tau_ext` (exact when `J` has full row rank
/// and `d = 0`), with `J` the tip's geometric Jacobian at the measured angles; and the
/// same wrench in the tip's axes.
struct Wrench {
    data: Data,
    damping: f64,
    base: Vector6<f64>,
    tip: Vector6<f64>,
}

impl Wrench {
    fn new(model: &Model, damping: f64) -> Result<Self, String> {
        let damping = if damping == 0.0 { 1e-3 } else { damping };
        if !(damping.is_finite() && damping > 0.0) {
            return Err(format!("must be finite and >= 0, got {damping}"));
        }
        Ok(Self {
            data: Data::new(model),
            damping,
            base: Vector6::zeros(),
            tip: Vector6::zeros(),
        })
    }

    /// Keeps the last value when `q` or the estimate is not finite or `J J^T` is singular.
    fn update(&mut self, model: &Model, q: &[f64], tau_ext: &[f64]) {
        if !q.iter().chain(tau_ext).all(|x| x.is_finite()) {
            return;
        }
        let Ok(j) = tip_jacobian(model, &mut self.data, q) else {
            return;
        };
        let mut a = Matrix6::<f64>::identity() * (self.damping * self.damping);
        let mut b = Vector6::<f64>::zeros();
        for (k, &t) in tau_ext.iter().enumerate().take(j.ncols()) {
            let col = j.column(k);
            for r in 0..6 {
                b[r] += col[r] * t;
                for c in 0..6 {
                    a[(r, c)] += col[r] * col[c];
                }
            }
        }
        if let Some(chol) = a.cholesky() {
            self.base = chol.solve(&b);
            // The Jacobian refreshed the tip's placement: its rotation maps tip axes to base.
            let r = self.data.frame_placements[model.tip_frame].rotation;
            let force = r.transpose() * self.base.fixed_rows::<3>(0);
            let moment = r.transpose() * self.base.fixed_rows::<3>(3);
            self.tip.fixed_rows_mut::<3>(0).copy_from(&force);
            self.tip.fixed_rows_mut::<3>(3).copy_from(&moment);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A torque that a hand wrench produces, `tau = J^T f`, gives that wrench back, in base
    /// axes and (rotated) in the tip's.
    #[test]
    fn wrench_inverts_the_jacobian_transpose() {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/baxter_left_arm.urdf"
        );
        let model = Model::from_urdf_file(urdf.as_ref(), Some("base"), Some("left_hand")).unwrap();
        let q = [0.1, -0.9, 1.1, 1.8, -0.6, 1.0, -0.4];
        let f = Vector6::new(3.0, -2.0, 5.0, 0.4, -0.3, 0.2);
        let mut data = Data::new(&model);
        let j = tip_jacobian(&model, &mut data, &q).unwrap().clone();
        let tau: Vec<f64> = (0..7).map(|k| j.column(k).dot(&f)).collect();
        let mut w = Wrench::new(&model, 1e-6).unwrap();
        w.update(&model, &q, &tau);
        assert!((w.base - f).norm() < 1e-6, "{} vs {f}", w.base);
        let r = data.frame_placements[model.tip_frame].rotation;
        let force = r.transpose() * f.fixed_rows::<3>(0);
        let moment = r.transpose() * f.fixed_rows::<3>(3);
        assert!((w.tip.fixed_rows::<3>(0) - force).norm() < 1e-6);
        assert!((w.tip.fixed_rows::<3>(3) - moment).norm() < 1e-6);
        // A non-finite estimate keeps the last value.
        w.update(&model, &q, &[f64::NAN; 7]);
        assert!((w.base - f).norm() < 1e-6);
        assert!(Wrench::new(&model, -1.0).is_err());
    }
}
