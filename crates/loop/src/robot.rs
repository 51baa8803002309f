//! [`RobotLoop`]: one control period of a real robot, the type the C ABI
//! (`admittance-ffi`), the ROS 2 bridge and Python's `RobotLoop` wrap. Raw measurements in,
//! as the robot gives them; command, estimate, reference, wrench, contact flags and a
//! status out.
//!
//! ```text
//!   q, tau (raw) ──► continuous joints unwrapped ──► plausibility gates ──► SignalChain
//!       ──► Measurement
//!   Measurement, q_d (the caller's, continuous joints on the measured branch, or a hold
//!       of the first measured pose)
//!       ──► ClosedLoop (observer -> admittance -> controller) ──► tau_cmd, tau_ext_hat
//!   tau_ext_hat ──► wrench at the tip, contact detector
//! ```
//!
//! Safe by default: no step commands anything before every joint has delivered a valid
//! angle (the command is zero and [`RobotStatus::waiting_for_angles`] says why), and
//! without a desired motion from the caller the loop holds the first measured pose. A
//! continuous joint reported wrapped at +-pi (or in 0-2 pi) is kept on one branch: its
//! angles in the reference and the estimate's inputs run on past the wrap. After
//! construction a step allocates nothing and never panics.

use std::path::Path;

use admittance_control::{
    BroadModel, ContactDetector, ContactFloor, ContactState, Fault, StepStatus, WrenchEstimator,
};
use admittance_dynamics::Model;

use crate::chain::SignalChain;
use crate::closed_loop::{ClosedLoop, LoopInput};
use crate::config::ObserverKind;
use crate::continuous::ContinuousAngles;
use crate::deployment::{Deployment, LOOP_FILE};
use crate::error::LoopError;
use crate::gates::{GateFault, PlausibilityGates};
use crate::robot_config::RobotConfig;

/// One period's raw inputs, slices of the arm's joint count.
#[derive(Clone, Copy, Debug)]
pub struct RobotInput<'a> {
    /// Time of the sample (s), from any origin; the observer's warm-up counts from 0.
    pub time: f64,
    /// Measured joint angles (rad or m).
    pub q: &'a [f64],
    /// Measured joint velocities, if the robot gives them (they replace the differentiated
    /// ones).
    pub qdot: Option<&'a [f64]>,
    /// Measured joint torques (N m), if the robot gives them; else the loop's last command.
    pub tau: Option<&'a [f64]>,
    /// `q_d`, `q_d'`, `q_d''` from the caller; `None`: hold the first measured pose.
    pub desired: Option<[&'a [f64]; 3]>,
}

/// What one step reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotStatus {
    /// The controller's fault of this step (its safe hold was commanded), if any.
    pub controller_fault: Option<Fault>,
    /// The observer's update failed (its estimate was held).
    pub observer_fault: bool,
    /// A value read was NaN or infinite.
    pub nonfinite_input: bool,
    /// The first implausible measurement of this sample (issue 34): it was replaced by
    /// NaN before any state saw it.
    pub implausible: Option<GateFault>,
    /// Some joint has not yet delivered a valid angle: the command is zero.
    pub waiting_for_angles: bool,
    /// The estimate is still held at zero (`observer.warmup`).
    pub warmup: bool,
    /// The desired motion is the hold of the first measured pose (no `desired` given).
    pub holding_pose: bool,
    /// Some joint's angle is a reading repeated while the joint was moving (a driver
    /// dropping packets and repeating the last one, or a frozen encoder; the signal chain's
    /// detection, issue 34): its sample time lies more than half a period back. Reported
    /// from the first stale sample, long before the controller's safe hold
    /// (`stale_steps`) acts.
    pub stale_input: bool,
    /// Some joint's measured angle lies outside the positions the observer's identification
    /// was fitted on (`summary.training_range`): its springs, offsets and gravity
    /// extrapolate there, so the estimate may hold a false torque its floor did not see.
    /// Never set without an identification that records its range.
    pub outside_training_range: bool,
    /// Some joint moved faster than the observer's identification was fitted at
    /// (`summary.training_speed`, beyond `TRAINING_SPEED_MARGIN`; its velocity conditioned
    /// as fitted): its friction extrapolates there. Never set without an identification
    /// that records its speeds, nor before the step's observer update.
    pub faster_than_training: bool,
    /// Contact flags (issue 31), with a contact floor.
    pub contact: Option<ContactState>,
}

impl RobotStatus {
    /// Whether the step ran its normal law on plausible, finite measurements.
    pub fn is_ok(&self) -> bool {
        self.controller_fault.is_none()
            && !self.observer_fault
            && !self.nonfinite_input
            && self.implausible.is_none()
            && !self.waiting_for_angles
    }
}

/// A robot's loop: gates, signal chain, closed loop, wrench and contact detection.
pub struct RobotLoop {
    n: usize,
    joints: Vec<String>,
    model: Model,
    closed_loop: ClosedLoop,
    chain: SignalChain,
    gates: PlausibilityGates,
    continuous: ContinuousAngles,
    warmup: f64,
    q_in: Vec<f64>,
    qdot_in: Vec<f64>,
    tau_in: Vec<f64>,
    desired: [Vec<f64>; 3],
    hold: Vec<f64>,
    held: bool,
    seen_angle: Vec<bool>,
    command: Vec<f64>,
    estimate: Vec<f64>,
    zeros: Vec<f64>,
    wrench: Option<WrenchEstimator>,
    contact: Option<ContactDetector>,
    /// With the contact detector: the wrench at the touched link, and each joint's child
    /// link frame.
    contact_wrench: Option<(WrenchEstimator, Vec<usize>)>,
}

impl RobotLoop {
    /// The loop of `config` for `model`; file paths in `config` are taken from `folder`;
    /// `trained` is the learned observers' network when the caller has it in memory (else
    /// `observer.network` is loaded), `floor` the contact floor (else `[contact] floor` is
    /// loaded).
    pub fn new(
        model: Model,
        config: &RobotConfig,
        folder: &Path,
        trained: Option<BroadModel>,
        floor: Option<ContactFloor>,
    ) -> Result<Self, LoopError> {
        if let Some(e) = config.problems().into_iter().next() {
            return Err(e);
        }
        if config.observer.kind == ObserverKind::Oracle {
            return Err(LoopError::invalid(
                "observer.kind",
                "`oracle` reads the true external torque, which a robot does not measure",
            )
            .hint("choose momentum, learned, hybrid or none"));
        }
        let loop_config = config.loop_config(folder);
        let mut closed_loop = ClosedLoop::from_config(&model, &loop_config, trained)?;
        let n = model.nq();
        let rate = config.control_rate_hz;
        let chain = SignalChain::new(n, config.signals.filter_cutoff_hz, rate)
            .map_err(|e| e.at("signals.filter_cutoff_hz"))?;
        let gates = PlausibilityGates::new(&model, &config.signals.gates, 1.0 / rate)?;
        let floor = match (floor, &config.contact) {
            (Some(f), _) => Some(f),
            (None, Some(section)) => Some(
                ContactFloor::load(&folder.join(&section.floor))
                    .map_err(|e| LoopError::from(e.within("contact.floor")))?,
            ),
            (None, None) => None,
        };
        let contact = floor
            .map(|f| {
                if f.dof() != n {
                    return Err(LoopError::invalid(
                        "contact.floor",
                        format!("has {} joints, the arm {n}", f.dof()),
                    ));
                }
                ContactDetector::new(&f).map_err(|e| LoopError::from(e.within("contact.floor")))
            })
            .transpose()?;
        if let (Some(det), true) = (
            &contact,
            config.contact.as_ref().is_some_and(|c| c.deadband),
        ) {
            let Some(compliance) = closed_loop.admittance_mut() else {
                return Err(LoopError::invalid(
                    "contact.deadband",
                    "needs an [admittance] or [task_admittance] table",
                ));
            };
            compliance
                .set_deadband(&det.floor().contact_thresholds)
                .map_err(|e| LoopError::from(e.within("contact.deadband")))?;
        }
        let contact_wrench = match &contact {
            Some(_) => Some((
                WrenchEstimator::new(&model, 0.0)
                    .map_err(|e| LoopError::from(e.within("contact")))?,
                link_frames(&model),
            )),
            None => None,
        };
        let continuous = ContinuousAngles::new(&model);
        let warmup = match config.observer.kind {
            ObserverKind::None | ObserverKind::Oracle => 0.0,
            _ => config.observer.warmup,
        };
        Ok(Self {
            n,
            joints: model.joint_names().map(String::from).collect(),
            model,
            closed_loop,
            chain,
            gates,
            continuous,
            warmup,
            q_in: vec![0.0; n],
            qdot_in: vec![0.0; n],
            tau_in: vec![0.0; n],
            desired: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            hold: vec![0.0; n],
            held: false,
            seen_angle: vec![false; n],
            command: vec![0.0; n],
            estimate: vec![0.0; n],
            zeros: vec![0.0; n],
            wrench: None,
            contact,
            contact_wrench,
        })
    }

    /// The loop of a deployment folder (`admittance deploy`), every file verified against
    /// its manifest; `overrides` are `KEY=VALUE` settings of `loop.toml` applied in order.
    /// Never trains: a missing or mismatched file is an error naming it.
    pub fn load(dir: &Path, overrides: &[&str]) -> Result<Self, LoopError> {
        Self::load_unlocated(dir, overrides).map_err(|e| e.located(&dir.join(LOOP_FILE)))
    }

    fn load_unlocated(dir: &Path, overrides: &[&str]) -> Result<Self, LoopError> {
        let deployment = Deployment::load_with(dir, overrides)?;
        let config = &deployment.config;
        let urdf = deployment
            .file_bytes(&config.arm.urdf)
            .and_then(|b| std::str::from_utf8(b).ok())
            .ok_or_else(|| LoopError::invalid("arm.urdf", "not UTF-8 text"))?;
        let urdf_path = dir.join(&config.arm.urdf);
        let model = Model::from_urdf_str_with(
            urdf,
            &urdf_path.display().to_string(),
            &config.arm.urdf_options(),
        )
        .map_err(|e| LoopError::invalid("arm.urdf", e.to_string()))?;
        let trained = match &config.observer.network {
            Some(path) => {
                let bytes = deployment.file_bytes(path).unwrap_or_default();
                let full = dir.join(path);
                let network = BroadModel::from_bytes(bytes, &full)
                    .map_err(|e| LoopError::invalid("observer.network", e.to_string()))?;
                Some(crate::build::checked_network(&model, network, &full)?)
            }
            None => None,
        };
        Self::new(model, config, dir, trained, None)
    }

    /// Estimate the hand wrench each step with the damped pseudo-inverse of damping
    /// `damping` (0 picks the default).
    pub fn enable_wrench(&mut self, damping: f64) -> Result<(), LoopError> {
        self.wrench = Some(WrenchEstimator::new(&self.model, damping)?);
        Ok(())
    }

    /// One control period. Slices shorter than the joint count leave the missing joints
    /// without a valid angle (the command stays zero); never panics, never allocates.
    pub fn step(&mut self, input: &RobotInput<'_>) -> RobotStatus {
        let n = self.n;
        let finite = |s: &[f64]| s.len() >= n && s[..n].iter().all(|x| x.is_finite());
        let mut nonfinite_input = !finite(input.q);
        self.q_in.fill(f64::NAN);
        copy(&mut self.q_in, input.q);
        // A continuous joint's reading wrapped at +-pi is brought back to its branch before
        // the jump gate sees it.
        self.continuous.unwrap(&mut self.q_in);
        match input.tau {
            Some(tau) => {
                nonfinite_input |= !finite(tau);
                self.tau_in.fill(f64::NAN);
                copy(&mut self.tau_in, tau);
            }
            None => self.tau_in.copy_from_slice(&self.command),
        }
        let measured_tau = input.tau.is_some().then_some(&mut self.tau_in[..]);
        let implausible = self.gates.check(input.time, &mut self.q_in, measured_tau);
        self.continuous.accept(&self.q_in);
        for (seen, q) in self.seen_angle.iter_mut().zip(&self.q_in) {
            *seen |= q.is_finite();
        }
        let waiting = !self.seen_angle.iter().all(|&s| s);
        // The filters see every sample (a NaN is held), so that they are started when the
        // last joint delivers.
        let _ = self.chain.sample(input.time, &self.q_in, &self.tau_in);
        let half_period = 0.5 * self.chain.dt();
        let stale_input = self
            .chain
            .measurement()
            .sample_time
            .iter()
            .any(|&t| input.time - t > half_period);
        // A NaN (a refused or missing angle) is not counted.
        let outside_training_range = admittance_dynamics::outside_training_range(
            self.closed_loop.observer_training_range(),
            &self.q_in,
            self.continuous.flags(),
        );
        let mut status = RobotStatus {
            controller_fault: None,
            observer_fault: false,
            nonfinite_input,
            implausible,
            waiting_for_angles: waiting,
            warmup: input.time < self.warmup,
            holding_pose: input.desired.is_none(),
            stale_input,
            outside_training_range,
            faster_than_training: false,
            contact: self.contact.as_ref().map(|c| c.state()),
        };
        if waiting {
            self.command.fill(0.0);
            return status;
        }
        if !self.held {
            // The first pose at which every joint has an angle: held until the caller sends
            // a desired motion.
            let filtered = &self.chain.measurement().q_filtered;
            for ((h, &q), &f) in self.hold.iter_mut().zip(&self.q_in).zip(filtered) {
                *h = if q.is_finite() { q } else { f };
            }
            self.held = true;
        }
        if let Some(qdot) = input.qdot {
            status.nonfinite_input |= !finite(qdot);
            self.qdot_in.fill(f64::NAN);
            copy(&mut self.qdot_in, qdot);
            let refused = self
                .gates
                .check_velocity(&mut self.qdot_in, status.implausible.is_some());
            status.implausible = status.implausible.or(refused);
            // A refused velocity leaves the chain's own (differentiated) one in place.
            let measured = &mut self.chain.measurement_mut().qdot;
            for ((m, &v), &given) in measured.iter_mut().zip(&self.qdot_in).zip(qdot) {
                if !(v.is_nan() && given.is_finite()) {
                    *m = v;
                }
            }
        }
        let [q_d, qdot_d, qddot_d] = &mut self.desired;
        match input.desired {
            Some([a, b, c]) => {
                status.nonfinite_input |= !(finite(a) && finite(b) && finite(c));
                copy(q_d, a);
                self.continuous.align(q_d);
                copy(qdot_d, b);
                copy(qddot_d, c);
            }
            None => {
                q_d.copy_from_slice(&self.hold);
                qdot_d.fill(0.0);
                qddot_d.fill(0.0);
            }
        }
        let measurement = self.chain.measurement();
        let result = self.closed_loop.step(&LoopInput {
            time: input.time,
            q_d,
            qdot_d,
            qddot_d,
            measurement,
            true_external_torque: &self.zeros,
        });
        self.command.copy_from_slice(self.closed_loop.torque());
        self.estimate
            .copy_from_slice(self.closed_loop.external_torque_estimate());
        status.observer_fault = !result.observer_ok;
        status.faster_than_training = self.closed_loop.observer_faster_than_training();
        if let StepStatus::Fault(f) = result.controller {
            status.controller_fault = Some(f);
        }
        if let Some(w) = self.wrench.as_mut() {
            w.update(&self.model, &measurement.q_filtered, &self.estimate);
        }
        if let Some(c) = self.contact.as_mut() {
            let state = c.update(&self.estimate, &measurement.qdot, &measurement.qddot);
            status.contact = Some(state);
            if let Some((w, frames)) = self.contact_wrench.as_mut() {
                match frames.get(state.link.max(0) as usize) {
                    Some(&frame) if state.contact && frame != usize::MAX => {
                        let joints = state.link as usize + 1;
                        w.update_at(
                            &self.model,
                            &measurement.q_filtered,
                            &self.estimate,
                            frame,
                            joints,
                        );
                    }
                    _ => w.clear(),
                }
            }
        }
        status
    }

    /// The joint count.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Whether the loop detects contact (a contact floor was given): each step's status
    /// then carries the flags.
    pub fn has_contact_floor(&self) -> bool {
        self.contact.is_some()
    }

    /// Joint names in chain order.
    pub fn joints(&self) -> &[String] {
        &self.joints
    }

    /// The arm.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The control period (s).
    pub fn dt(&self) -> f64 {
        self.closed_loop.dt()
    }

    /// The command of the last step (N m): zero before every joint has delivered a valid
    /// angle, else the controller's (finite, within the effort limits).
    pub fn torque(&self) -> &[f64] {
        &self.command
    }

    /// The external-torque estimate of the last step (N m).
    pub fn external_torque_estimate(&self) -> &[f64] {
        &self.estimate
    }

    /// `q_r`, `q_r'`, `q_r''` of the last step.
    pub fn reference(&self) -> [&[f64]; 3] {
        [
            self.closed_loop.q_r(),
            self.closed_loop.qdot_r(),
            self.closed_loop.qddot_r(),
        ]
    }

    /// With a contact floor, the wrench the environment applies at the touched link (the
    /// origin of the last loaded joint's child link), from the estimate of that joint and
    /// the ones before it, in the base axes and in the link's: force (N) then moment (N m).
    /// Zero while no contact is flagged. With fewer than six joints before the link it is
    /// the smallest wrench that explains their estimate (the part the Jacobian sees).
    pub fn contact_wrench(&self) -> Option<(&[f64], &[f64])> {
        self.contact_wrench
            .as_ref()
            .map(|(w, _)| (w.base(), w.tip()))
    }

    /// The hand wrench of the last step in the base axes and in the tip's, with
    /// [`RobotLoop::enable_wrench`].
    pub fn wrench(&self) -> Option<(&[f64], &[f64])> {
        self.wrench.as_ref().map(|w| (w.base(), w.tip()))
    }

    /// Samples refused by the plausibility gates so far.
    pub fn implausible_samples(&self) -> u64 {
        self.gates.faults()
    }

    /// The closed loop inside (its admittance model, its neural controller).
    pub fn closed_loop(&self) -> &ClosedLoop {
        &self.closed_loop
    }
}

/// Copies what fits.
fn copy(dst: &mut [f64], src: &[f64]) {
    let k = dst.len().min(src.len());
    dst[..k].copy_from_slice(&src[..k]);
}

/// The frame of each joint's child link (the first frame the joint carries), `usize::MAX`
/// for a joint that carries none.
fn link_frames(model: &Model) -> Vec<usize> {
    (0..model.nq())
        .map(|j| {
            model
                .frames
                .iter()
                .position(|f| f.parent_joint == Some(j))
                .unwrap_or(usize::MAX)
        })
        .collect()
}
