//! A variant whose plant is not this crate's simulator (the MuJoCo co-simulation of the
//! Python package): the caller steps its own plant and an `admittance_loop::ClosedLoop`, and
//! hands each control step to an [`ExternalVariant`], which gathers the same metrics, health
//! checks (divergence) and time series as a scenario's variant, with the same code
//! ([`crate::run_scenario`]'s); [`crate::write_external_run_folder`] writes them as a run
//! folder.

use admittance_dynamics::Model;
use admittance_loop::{ClosedLoop, Divergence, LoopConfig, LoopError, LoopStatus, Measurement};
use admittance_sim::StepRecord;

use crate::error::ScenarioError;
use crate::metrics::ObserverTrainingMetrics;
use crate::recorder::Recorder;
use crate::runner::{finish, VariantRun};
use crate::step_gather::{Desired, PlantAfter, RowExtras, StepGather};

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
    joints: Vec<String>,
    dt: f64,
    steps: StepGather,
    /// The plant's last step as the gathering reads it.
    record: StepRecord,
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
            return Err(LoopError::invalid(
                "duration",
                format!("is {duration}, must be > 0 s"),
            ));
        }
        if !(evaluation_start.is_finite() && evaluation_start >= 0.0 && evaluation_start < duration)
        {
            return Err(LoopError::invalid(
                "evaluation_start",
                format!("is {evaluation_start}, must be in [0, duration = {duration}) s"),
            ));
        }
        if decimation == 0 {
            return Err(LoopError::invalid(
                "output.decimation",
                "must be at least 1",
            ));
        }
        let n = model.nq();
        let joints: Vec<String> = model.joints.iter().map(|j| j.name.clone()).collect();
        let effort: Vec<f64> = model.joints.iter().map(|j| j.limits.effort).collect();
        let dt = 1.0 / config.control_rate_hz;
        let steps = (duration / dt).round() as usize;
        let mut recorder = Recorder::new(&joints, decimation, false, false, false, false);
        // The column the scenario runner adds for a loop whose observer reports coverage.
        if config.observer.kind == admittance_loop::ObserverKind::Hybrid {
            recorder.record_coverage();
        }
        let oracle = config.compliance(model)?;
        Ok(Self {
            name: name.to_string(),
            dt,
            steps: StepGather::new(
                model,
                &joints,
                &effort,
                steps,
                dt,
                evaluation_start,
                recorder,
                oracle,
                None,
                false,
            ),
            record: StepRecord::new(n),
            joints,
        })
    }

    /// Detects contact on the loop's estimate with `floor`'s levels (the contact columns and
    /// metrics of a scenario's `[contact]`, and the floor in the run folder); before the
    /// first step.
    pub fn detect_contact(
        &mut self,
        floor: &admittance_control::ContactFloor,
    ) -> Result<(), admittance_control::ConfigError> {
        self.steps.detect_contact(floor, &self.joints)
    }

    /// The variant's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Control steps gathered.
    pub fn steps(&self) -> usize {
        self.steps.steps()
    }

    /// The divergence that stopped the variant, if any.
    pub fn divergence(&self) -> Option<&Divergence> {
        self.steps.divergence()
    }

    /// One control step at `time`: the loop `lp` has stepped on `measurement` towards
    /// `desired` (with `status`), and the plant has applied its command (`plant`). Returns
    /// the divergence when this step left the physical bounds (the variant must stop: later
    /// steps are ignored), as the scenario runner does: both gather through one code path.
    pub fn add(
        &mut self,
        time: f64,
        desired: &Desired<'_>,
        measurement: &Measurement,
        lp: &ClosedLoop,
        status: &LoopStatus,
        plant: &PlantStep<'_>,
    ) -> Option<&Divergence> {
        if self.steps.divergence().is_none() {
            // The record of this step; once stopped, the gathering ignores every later one.
            let record = &mut self.record;
            record.time = time + self.dt;
            copy(&mut record.command, lp.torque());
            copy(&mut record.applied, plant.applied);
            copy(&mut record.tau_ext, plant.tau_ext);
        }
        self.steps.add(
            time,
            desired,
            measurement,
            lp,
            status,
            &PlantAfter {
                q: plant.q,
                qdot: plant.qdot,
                record: &self.record,
                hand_force: None,
            },
            &RowExtras::default(),
        )
    }

    /// The variant's metrics, series and divergence; `training`: how its observer's network
    /// was trained, if it has one. `lp` is the loop that ran (for the neural controller's
    /// node counts).
    pub fn finish(
        self,
        lp: &ClosedLoop,
        training: Option<ObserverTrainingMetrics>,
    ) -> Result<VariantRun, ScenarioError> {
        finish(
            &self.name,
            lp,
            self.steps,
            None,
            self.joints,
            training,
            None,
        )
    }
}

fn copy(dst: &mut [f64], src: &[f64]) {
    let k = dst.len().min(src.len());
    dst[..k].copy_from_slice(&src[..k]);
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use admittance_loop::LoopInput;

    use super::*;
    use crate::assemble::{assemble, Assembly};
    use crate::progress::RunOptions;
    use crate::runner::run_variant;
    use crate::source::ScenarioSource;

    /// The scenario runner's own plant, stepped from outside through an [`ExternalVariant`],
    /// gives the runner's metrics and series exactly: the external path gathers with the
    /// same code, not a copy of it.
    #[test]
    fn an_external_plant_gets_the_runners_metrics_and_series() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/admittance.toml"
        ));
        let mut source = ScenarioSource::load(path).unwrap();
        source.set("duration=13").unwrap();
        source.set("evaluation_start=11").unwrap();
        let options = RunOptions::default();
        let expected = run_variant(&source, path, Some("momentum"), &options).unwrap();
        let simulate = |s: &ScenarioSource, p: &Path, o: &RunOptions| {
            run_variant(s, p, None, o).map(|r| (r.joints, r.free_motion))
        };
        let Assembly {
            scenario,
            trajectory,
            mut plant,
            mut sensors,
            mut closed_loop,
            ..
        } = assemble(&source, path, Some("momentum"), &options, &simulate).unwrap();
        let model = plant.model().clone();
        let mut external = ExternalVariant::new(
            "momentum",
            &model,
            &scenario.loop_config(),
            scenario.duration,
            scenario.evaluation_start,
            scenario.output.decimation,
        )
        .unwrap();
        let n = model.nq();
        let (mut q_d, mut qdot_d, mut qddot_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let dt = closed_loop.dt();
        for k in 0..(scenario.duration / dt).round() as usize {
            let t = k as f64 * dt;
            trajectory.eval(t, &mut q_d, &mut qdot_d, &mut qddot_d);
            let m = sensors.sample(t, plant.q(), closed_loop.torque()).unwrap();
            let status = closed_loop.step(&LoopInput {
                time: t,
                q_d: &q_d,
                qdot_d: &qdot_d,
                qddot_d: &qddot_d,
                measurement: m,
                true_external_torque: plant.tau_ext(),
            });
            plant.step_control(closed_loop.torque()).unwrap();
            let record = plant.record().clone();
            let desired = Desired {
                q_d: &q_d,
                qdot_d: &qdot_d,
                qddot_d: &qddot_d,
            };
            let step = PlantStep {
                q: plant.q(),
                qdot: plant.qdot(),
                tau_ext: &record.tau_ext,
                applied: &record.applied,
            };
            assert!(external
                .add(t, &desired, m, &closed_loop, &status, &step)
                .is_none());
        }
        let run = external.finish(&closed_loop, None).unwrap();
        let (a, b) = (&run.metrics, &expected.metrics);
        assert!(b.external_torque_nrmse.is_some_and(|x| x > 0.0));
        assert_eq!(a.external_torque_nrmse, b.external_torque_nrmse);
        assert_eq!(a.external_torque_rmse, b.external_torque_rmse);
        assert_eq!(a.false_torque_rms, b.false_torque_rms);
        assert_eq!(a.admittance_error_rms, b.admittance_error_rms);
        assert_eq!(a.tracking_rmse, b.tracking_rmse);
        assert_eq!(a.torque_rms, b.torque_rms);
        assert_eq!(a.ee_error_rms, b.ee_error_rms);
        assert_eq!(a.reference_bound_violations, b.reference_bound_violations);
        assert_eq!(a.q_limit_violation_fraction, b.q_limit_violation_fraction);
        assert_eq!(run.series.columns, expected.series.columns);
        assert_eq!(run.series.rows, expected.series.rows);
    }
}
