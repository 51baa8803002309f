//! What one control step leaves behind, gathered by one code path for the scenario runner's
//! simulated plant and for an external plant's variant (`external.rs`, the MuJoCo
//! co-simulation): the oracle admittance, the health checks, the metrics over the evaluation
//! window, contact detection and its scoring, and the recorded row.

use admittance_control::ReferenceInput;
use admittance_dynamics::Model;
use admittance_loop::{ClosedLoop, Compliance, Divergence, LoopStatus, Measurement};
use admittance_sim::StepRecord;

use crate::contact_run::ContactRun;
use crate::gather::{Gather, WindowSample};
use crate::hand::HandKinematics;
use crate::recorder::{Recorder, Row};

/// The plant after a control step's command was applied.
#[derive(Clone, Copy)]
pub(crate) struct PlantAfter<'a> {
    /// True angles and velocities at the end of the step.
    pub q: &'a [f64],
    pub qdot: &'a [f64],
    /// The step's record (command, applied torque, true external torque).
    pub record: &'a StepRecord,
    /// The true force at the hand (N, base axes), when the loop is in task space.
    pub hand_force: Option<[f64; 3]>,
}

/// Series only the scenario runner has (dynamic nodes).
#[derive(Clone, Copy, Default)]
pub(crate) struct RowExtras<'a> {
    /// The true `f` and the controller's `f_hat`.
    pub f: Option<(&'a [f64], &'a [f64])>,
    /// The controller's node count.
    pub nodes: Option<usize>,
}

/// The desired trajectory of one control step (what the loop was given).
#[derive(Clone, Copy, Debug)]
pub struct Desired<'a> {
    /// `q_d`.
    pub q_d: &'a [f64],
    /// `q_d'`.
    pub qdot_d: &'a [f64],
    /// `q_d''`.
    pub qddot_d: &'a [f64],
}

/// The gathering of one variant, step by step.
pub(crate) struct StepGather {
    model: Model,
    dt: f64,
    evaluation_start: f64,
    with_hand: bool,
    pub(crate) gather: Gather,
    pub(crate) recorder: Recorder,
    kinematics: HandKinematics,
    /// The admittance model driven by the true external torque (`admittance_error_rms`).
    oracle: Option<Compliance>,
    pub(crate) contact: Option<ContactRun>,
    /// The true external torque of the plant's last step: what this step's loop saw.
    last_tau_ext: Vec<f64>,
    k: usize,
    stopped: bool,
}

impl StepGather {
    /// For `steps` control steps of period `dt`, metrics from `evaluation_start` on.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        model: &Model,
        joints: &[String],
        effort: &[f64],
        steps: usize,
        dt: f64,
        evaluation_start: f64,
        recorder: Recorder,
        oracle: Option<Compliance>,
        contact: Option<ContactRun>,
        with_hand: bool,
    ) -> Self {
        let mut recorder = recorder;
        if contact.is_some() {
            recorder.record_contact(joints);
        }
        StepGather {
            model: model.clone(),
            dt,
            evaluation_start,
            with_hand,
            gather: Gather::new(model, joints, effort, steps, with_hand),
            recorder,
            kinematics: HandKinematics::new(model),
            oracle,
            contact,
            last_tau_ext: vec![0.0; model.nq()],
            k: 0,
            stopped: false,
        }
    }

    /// The divergence that stopped the variant, if any.
    pub fn divergence(&self) -> Option<&Divergence> {
        self.gather.health.divergence.as_ref()
    }

    /// Control steps gathered.
    pub fn steps(&self) -> usize {
        self.k
    }

    /// Detects contact on the loop's estimate from the next step on, with `floor`'s levels
    /// (columns `contact`, `collision`, `contact_link`, `contact_level.J`; the contact
    /// metrics). Refused once a step was gathered.
    pub fn detect_contact(
        &mut self,
        floor: &admittance_control::ContactFloor,
        joints: &[String],
    ) -> Result<(), admittance_control::ConfigError> {
        if self.k > 0 || self.contact.is_some() {
            return Err(admittance_control::ConfigError::new(
                "contact_floor",
                "set before the first step, once",
            ));
        }
        if floor.dof() != joints.len() {
            return Err(admittance_control::ConfigError::new(
                "contact_floor",
                format!(
                    "is for {} joints, the arm has {}",
                    floor.dof(),
                    joints.len()
                ),
            ));
        }
        self.contact = Some(ContactRun::new(floor)?);
        self.recorder.record_contact(joints);
        Ok(())
    }

    /// Whether an oracle admittance runs beside the loop.
    pub fn with_oracle(&self) -> bool {
        self.oracle.is_some()
    }

    /// One control step at `time`: the loop `lp` stepped on `measurement` towards `desired`
    /// (with `status`), then the plant applied its command (`plant`). Returns the divergence
    /// when this step left the physical bounds: the variant stops there, and later steps are
    /// ignored.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &mut self,
        time: f64,
        desired: &Desired<'_>,
        measurement: &Measurement,
        lp: &ClosedLoop,
        status: &LoopStatus,
        plant: &PlantAfter<'_>,
        extras: &RowExtras<'_>,
    ) -> Option<&Divergence> {
        if self.stopped {
            return self.divergence();
        }
        let dt = self.dt;
        if let Some(adm) = self.oracle.as_mut() {
            let _ = adm.step(
                &ReferenceInput {
                    q_d: desired.q_d,
                    qdot_d: desired.qdot_d,
                    qddot_d: desired.qddot_d,
                    q: &measurement.q,
                    external_torque_estimate: &self.last_tau_ext,
                },
                dt,
            );
        }
        // A sample older than this period (the driver repeated a joint's last reading) is
        // stale whether or not the controller could tell from the values.
        let stale_sample = measurement
            .sample_time
            .iter()
            .any(|&ts| time - ts > 0.5 * dt);
        if let Some(c) = self.contact.as_mut() {
            c.update(
                lp.external_torque_estimate(),
                &measurement.qdot,
                &measurement.qddot,
            );
        }
        let k = self.k;
        self.k += 1;
        self.gather
            .after_control(k, status, lp, &measurement.q, stale_sample);
        if self
            .gather
            .diverged(time, plant.q, plant.qdot, measurement, lp)
        {
            self.stopped = true;
            return self.divergence();
        }
        let n = self.last_tau_ext.len().min(plant.record.tau_ext.len());
        self.last_tau_ext[..n].copy_from_slice(&plant.record.tau_ext[..n]);
        self.window_and_row(time, desired, measurement, lp, plant, extras);
        None
    }

    /// The evaluation window's metrics and the recorded row of the step `add` took.
    fn window_and_row(
        &mut self,
        time: f64,
        desired: &Desired<'_>,
        measurement: &Measurement,
        lp: &ClosedLoop,
        plant: &PlantAfter<'_>,
        extras: &RowExtras<'_>,
    ) {
        let k = self.k - 1;
        // Hand error by forward kinematics of the true angles against the reference.
        let p_ref = self.kinematics.position(&self.model, lp.q_r());
        let p_hand = self.kinematics.position(&self.model, plant.q);
        let ee_error = (0..3)
            .map(|i| (p_hand[i] - p_ref[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let hand_force = plant.hand_force.unwrap_or([0.0; 3]);
        let hand_estimate = lp
            .admittance()
            .and_then(|c| c.task_space())
            .map(|a| &a.wrench_estimate()[..3])
            .filter(|_| self.with_hand);
        if time >= self.evaluation_start {
            if let Some(c) = self.contact.as_mut() {
                c.in_window(time, &plant.record.tau_ext, lp.q_r(), desired.q_d);
            }
            self.gather.in_window(&WindowSample {
                q_r: lp.q_r(),
                q: plant.q,
                torque: lp.torque(),
                estimate: lp.external_torque_estimate(),
                record: plant.record,
                q_r_oracle: self.oracle.as_ref().map(|a| a.q_r()),
                ee_error,
                hand: hand_estimate.map(|f_hat| (&hand_force, f_hat)),
                coverage: lp.estimate_coverage(),
            });
        }
        if self.recorder.wants(k) {
            let p_d = if self.with_hand {
                self.kinematics.position(&self.model, desired.q_d)
            } else {
                [0.0; 3]
            };
            self.recorder.row(&Row {
                t: time,
                q_d: desired.q_d,
                q_r: lp.q_r(),
                q: plant.q,
                qdot: plant.qdot,
                measurement,
                torque: lp.torque(),
                record: plant.record,
                estimate: lp.external_torque_estimate(),
                ee_error,
                f: extras.f,
                nodes: extras.nodes,
                hand: hand_estimate
                    .map(|f_hat| [&hand_force[..], f_hat, &p_hand[..], &p_ref[..], &p_d[..]]),
                coverage: lp.estimate_coverage(),
                contact: self.contact.as_ref().map(|c| c.flags()),
            });
        }
    }
}
