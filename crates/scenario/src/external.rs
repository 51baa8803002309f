//! A variant whose plant is not this crate's simulator (the MuJoCo co-simulation of the
//! Python package): the caller steps its own plant and an `admittance_loop::ClosedLoop`, and
//! hands each control step to an [`ExternalVariant`], which gathers the same metrics, health
//! checks (divergence) and time series as a scenario's variant, with the same code
//! ([`crate::run_scenario`]'s); [`crate::write_external_run_folder`] writes them as a run
//! folder.

use admittance_control::ReferenceInput;
use admittance_dynamics::Model;
use admittance_loop::{ClosedLoop, Compliance, LoopConfig, LoopError, LoopStatus, Measurement};
use admittance_sim::StepRecord;

use crate::error::ScenarioError;
use crate::gather::{Gather, WindowSample};
use crate::hand::HandKinematics;
use crate::health::Divergence;
use crate::metrics::ObserverTrainingMetrics;
use crate::recorder::{Recorder, Row};
use crate::runner::{finish, VariantRun};

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

/// What the plant did in one control step, after the loop's command was applied.
#[derive(Clone, Copy, Debug)]
pub struct PlantStep<'a> {
    /// The true angles at the end of the step.
    pub q: &'a [f64],
    /// The true velocities at the end of the step.
    pub qdot: &'a [f64],
    /// The true external joint torque of the step (N m).
    pub tau_ext: &'a [f64],
    /// The torque the actuators applied (N m); the command when the plant applies it as
    /// it is.
    pub applied: &'a [f64],
}

/// The metrics and series of one variant of an external plant, gathered step by step.
pub struct ExternalVariant {
    name: String,
    model: Model,
    joints: Vec<String>,
    dt: f64,
    evaluation_start: f64,
    gather: Gather,
    recorder: Recorder,
    kinematics: HandKinematics,
    /// The admittance model driven by the true external torque (`admittance_error_rms`).
    oracle: Option<Compliance>,
    record: StepRecord,
    k: usize,
    stopped: bool,
}

impl ExternalVariant {
    /// For the arm `model` run by a loop of `config` for `duration` seconds (metrics over
    /// `[evaluation_start, duration]`), one row of `VARIANT.csv` every `decimation` steps.
    pub fn new<T>(
        name: &str,
        model: &Model,
        config: &LoopConfig<T>,
        duration: f64,
        evaluation_start: f64,
        decimation: usize,
    ) -> Result<Self, LoopError> {
        config.validate()?;
        if !(duration.is_finite() && duration > 0.0) {
            return Err(LoopError::invalid("duration", format!("is {duration}, must be > 0 s")));
        }
        if !(evaluation_start.is_finite() && evaluation_start >= 0.0 && evaluation_start < duration) {
            return Err(LoopError::invalid(
                "evaluation_start",
                format!("is {evaluation_start}, must be in [0, duration = {duration}) s"),
            ));
        }
        if decimation == 0 {
            return Err(LoopError::invalid("output.decimation", "must be at least 1"));
        }
        let n = model.nq();
        let joints: Vec<String> = model.joints.iter().map(|j| j.name.clone()).collect();
        let effort: Vec<f64> = model.joints.iter().map(|j| j.limits.effort).collect();
        let dt = 1.0 / config.control_rate_hz;
        let steps = (duration / dt).round() as usize;
        Ok(Self {
            name: name.to_string(),
            model: model.clone(),
            gather: Gather::new(model, &joints, &effort, steps, false),
            recorder: Recorder::new(&joints, decimation, false, false, false, false),
            kinematics: HandKinematics::new(model),
            oracle: config.compliance(model)?,
            record: StepRecord::new(n),
            joints,
            dt,
            evaluation_start,
            k: 0,
            stopped: false,
        })
    }

    /// The variant's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Control steps gathered.
    pub fn steps(&self) -> usize {
        self.k
    }

    /// The divergence that stopped the variant, if any.
    pub fn divergence(&self) -> Option<&Divergence> {
        self.gather.health.divergence.as_ref()
    }

    /// One control step at `time`: the loop `lp` has stepped on `measurement` towards
    /// `desired` (with `status`), and the plant has applied its command (`plant`). Returns
    /// the divergence when this step left the physical bounds (the variant must stop: later
    /// steps are ignored), as the scenario runner does.
    pub fn add(
        &mut self,
        time: f64,
        desired: &Desired<'_>,
        measurement: &Measurement,
        lp: &ClosedLoop,
        status: &LoopStatus,
        plant: &PlantStep<'_>,
    ) -> Option<&Divergence> {
        if self.stopped {
            return self.divergence();
        }
        let dt = self.dt;
        // The true torque the loop's step saw (that of the previous plant step).
        if let Some(adm) = self.oracle.as_mut() {
            let _ = adm.step(
                &ReferenceInput {
                    q_d: desired.q_d,
                    qdot_d: desired.qdot_d,
                    qddot_d: desired.qddot_d,
                    q: &measurement.q,
                    external_torque_estimate: &self.record.tau_ext,
                },
                dt,
            );
        }
        let k = self.k;
        self.k += 1;
        let stale_sample = measurement.sample_time.iter().any(|&ts| time - ts > 0.5 * dt);
        self.gather.after_control(k, status, lp, stale_sample);
        if self
            .gather
            .diverged(time, plant.q, plant.qdot, measurement, lp)
        {
            self.stopped = true;
            return self.divergence();
        }
        let record = &mut self.record;
        record.time = time + dt;
        copy(&mut record.command, lp.torque());
        copy(&mut record.applied, plant.applied);
        copy(&mut record.tau_ext, plant.tau_ext);
        let p_ref = self.kinematics.position(&self.model, lp.q_r());
        let p_hand = self.kinematics.position(&self.model, plant.q);
        let ee_error = (0..3)
            .map(|i| (p_hand[i] - p_ref[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        if time >= self.evaluation_start {
            self.gather.in_window(&WindowSample {
                q_r: lp.q_r(),
                q: plant.q,
                torque: lp.torque(),
                estimate: lp.external_torque_estimate(),
                record: &self.record,
                q_r_oracle: self.oracle.as_ref().map(|a| a.q_r()),
                ee_error,
                hand: None,
            });
        }
        if self.recorder.wants(k) {
            self.recorder.row(&Row {
                t: time,
                q_d: desired.q_d,
                q_r: lp.q_r(),
                q: plant.q,
                qdot: plant.qdot,
                measurement,
                torque: lp.torque(),
                record: &self.record,
                estimate: lp.external_torque_estimate(),
                ee_error,
                f: None,
                nodes: None,
                hand: None,
            });
        }
        None
    }

    /// The variant's metrics, series and divergence; `training`: how its observer's network
    /// was trained, if it has one. `lp` is the loop that ran (for the neural controller's
    /// node counts).
    pub fn finish(
        self,
        lp: &ClosedLoop,
        training: Option<ObserverTrainingMetrics>,
    ) -> Result<VariantRun, ScenarioError> {
        let with_oracle = self.oracle.is_some();
        finish(
            &self.name,
            lp,
            self.gather,
            self.recorder,
            None,
            self.joints,
            with_oracle,
            training,
            None,
        )
    }
}

fn copy(dst: &mut [f64], src: &[f64]) {
    let k = dst.len().min(src.len());
    dst[..k].copy_from_slice(&src[..k]);
}
