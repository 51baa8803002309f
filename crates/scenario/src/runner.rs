//! One variant of a scenario, run: the assembled parts stepped period by period (the
//! plant, its sensors, the [`ClosedLoop`], the dynamic-node events), with the metrics and
//! the time series gathered on the way (`step_gather.rs`, shared with an external plant).

use std::path::Path;

use admittance_control::NetworkId;
use admittance_loop::{ClosedLoop, LoopInput};
use admittance_sim::SimError;

use crate::assemble::{assemble, Assembly};
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::metrics::VariantMetrics;
use crate::node_events::NodeEvents;
use crate::progress::{RunOptions, Stage};
use crate::recorder::Recorder;
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
use crate::step_gather::{Desired, PlantAfter, RowExtras, StepGather};
use admittance_loop::Divergence;

/// The outcome of one variant.
#[derive(Clone, Debug)]
pub struct VariantRun {
    /// Variant name (`"base"` when the file has no variants).
    pub name: String,
    /// Metrics for summary.json.
    pub metrics: VariantMetrics,
    /// The time series.
    pub series: TimeSeries,
    /// Joint names in chain order.
    pub joints: Vec<String>,
    /// The free-motion recording (`[record] free_motion_csv = true`): one row per control
    /// sample, columns `t, q.*, qdot.*, qddot.*, tau.*` (docs/outputs.md).
    pub free_motion: Option<TimeSeries>,
    /// With dynamic nodes: the norm of each f-network node's weight row, every
    /// [`crate::NODE_WEIGHT_INTERVAL`] seconds; columns `t, w.ID`.
    pub node_weights: Option<TimeSeries>,
    /// With a learned observer: its network on the validation data.
    pub observer_validation: Option<TimeSeries>,
    /// Why and when the variant stopped early, if it did.
    pub divergence: Option<Divergence>,
    /// What the URDF loader accepted with a warning (`file:line: element: problem`), then
    /// the gain rules' warnings (`scenario:line: key ...: problem; hint: ...`).
    pub arm_warnings: Vec<String>,
    /// The thresholds of the health rules for this variant (`[health]`).
    pub health_settings: admittance_runfolder::health::HealthSettings,
    /// The variant's settings as the run applied them (`settings.json`).
    pub settings: admittance_runfolder::settings::VariantSettings,
    /// The contact floor the run detected with (`[contact]`), written to the run folder.
    pub contact_floor: Option<admittance_control::ContactFloor>,
}

/// Resolves, validates and runs one variant of a scenario file.
pub fn run_variant(
    source: &ScenarioSource,
    path: &Path,
    variant: Option<&str>,
    options: &RunOptions,
) -> Result<VariantRun, ScenarioError> {
    let simulate = |src: &ScenarioSource, p: &Path, o: &RunOptions| {
        run_variant(src, p, None, o).map(|r| (r.joints, r.free_motion))
    };
    let parts = assemble(source, path, variant, options, &simulate)?;
    let ctx = Ctx { source, variant };
    simulate_variant(&ctx, parts, options)
}

/// Steps the assembled parts to the end (or to a divergence) and gathers metrics and
/// series.
fn simulate_variant(
    ctx: &Ctx<'_>,
    parts: Assembly,
    options: &RunOptions,
) -> Result<VariantRun, ScenarioError> {
    let Assembly {
        scenario,
        joints,
        trajectory,
        mut plant,
        mut sensors,
        mut closed_loop,
        oracle_admittance,
        observer_training,
        observer_validation,
        identification,
        arm_warnings,
        contact,
    } = parts;
    let n = joints.len();
    let dt = closed_loop.dt();
    let sim_err = |e: SimError| ctx.plant_err(e);
    let steps = (scenario.duration / dt).round() as usize;
    let model = plant.model().clone();
    let effort = plant.effort_limits().to_vec();
    let with_hand = closed_loop
        .admittance()
        .is_some_and(|c| c.task_space().is_some());
    let mut events = scenario
        .dynamic_nodes
        .clone()
        .map(|spec| NodeEvents::new(spec, &model, scenario.duration, dt));
    let mut recorder = Recorder::new(
        &joints,
        scenario.output.decimation,
        scenario.record.free_motion_csv,
        events.is_some(),
        closed_loop.neural().is_some(),
        with_hand,
    );
    if closed_loop.estimate_coverage().is_some() {
        recorder.record_coverage();
    }
    let mut steps_gathered = StepGather::new(
        &model,
        &joints,
        &effort,
        steps,
        dt,
        scenario.evaluation_start,
        recorder,
        oracle_admittance,
        contact,
        with_hand,
    );
    let mut gates = crate::gate_stage::GateStage::new(&model, &scenario.gates, dt)
        .map_err(|e| ctx.loop_err(e))?;
    let (mut q_d, mut qd_d, mut qdd_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let zeros = vec![0.0; n];
    let variant_name = ctx.variant.unwrap_or("base");
    let settings =
        crate::settings::variant_settings(variant_name, &scenario, &joints, &plant, &closed_loop);
    let progress_stride = (steps / 100).max(1);

    for k in 0..steps {
        if k % progress_stride == 0 {
            options.report(variant_name, Stage::Simulate, k as u64, steps as u64);
        }
        let t = k as f64 * dt;
        trajectory.eval(t, &mut q_d, &mut qd_d, &mut qdd_d);
        let m = gates
            .sample(&mut sensors, t, plant.q(), closed_loop.torque())
            .map_err(sim_err)?;
        steps_gathered.recorder.sensed(t, m);
        if let Some(ev) = events.as_mut() {
            ev.before_step(ctx, t, &mut closed_loop)?;
        }
        let status = closed_loop.step(&LoopInput {
            time: t,
            q_d: &q_d,
            qdot_d: &qd_d,
            qddot_d: &qdd_d,
            measurement: m,
            true_external_torque: plant.tau_ext(),
        });
        if let Some(ev) = events.as_mut() {
            ev.after_step(k, t, &model, plant.q(), plant.qdot(), &closed_loop);
        }
        plant.step_control(closed_loop.torque()).map_err(sim_err)?;
        let desired = Desired {
            q_d: &q_d,
            qdot_d: &qd_d,
            qddot_d: &qdd_d,
        };
        let after = PlantAfter {
            q: plant.q(),
            qdot: plant.qdot(),
            record: plant.record(),
            hand_force: with_hand.then(|| plant.environment().tip_force()),
        };
        let extras = RowExtras {
            f: events.as_ref().map(|ev| {
                (
                    &ev.f_true[..],
                    closed_loop.neural().map(|c| c.f_hat()).unwrap_or(&zeros),
                )
            }),
            nodes: closed_loop.neural().map(|nn| nn.node_count(NetworkId::F)),
        };
        // A step that left the physical bounds ends the variant before it reaches the
        // metrics: what they hold is the run up to that point.
        if steps_gathered
            .add(t, &desired, m, &closed_loop, &status, &after, &extras)
            .is_some()
        {
            break;
        }
    }
    options.report(variant_name, Stage::Simulate, steps as u64, steps as u64);
    let mut run = finish(
        variant_name,
        &closed_loop,
        steps_gathered,
        events,
        joints,
        observer_training,
        observer_validation,
    )?;
    run.arm_warnings = arm_warnings;
    run.health_settings = scenario.health.clone();
    run.metrics.identification = identification;
    run.metrics.gated_samples = Some(gates.counts());
    run.settings = settings;
    Ok(run)
}

/// Everything gathered, as a [`VariantRun`].
pub(crate) fn finish(
    name: &str,
    closed_loop: &ClosedLoop,
    mut steps: StepGather,
    events: Option<NodeEvents>,
    joints: Vec<String>,
    observer_training: Option<crate::metrics::ObserverTrainingMetrics>,
    observer_validation: Option<TimeSeries>,
) -> Result<VariantRun, ScenarioError> {
    let with_oracle_reference = steps.with_oracle();
    let contact = steps.contact.take();
    let (mut metrics, health) = steps.gather.finish(with_oracle_reference);
    metrics.observer_training = observer_training;
    if let Some(nn) = closed_loop.neural() {
        metrics.nodes = nn
            .network_ids()
            .map(|id| (id.as_str().to_string(), nn.node_count(id)))
            .collect();
        metrics.weight_norm_final = Some(
            nn.network_ids()
                .map(|id| (id.as_str().to_string(), nn.weight_norm(id)))
                .collect(),
        );
    }
    let mut node_weights = None;
    if let Some((dynamic, weights)) = events.and_then(|ev| ev.finish(closed_loop)) {
        metrics.dynamic_nodes = Some(dynamic);
        node_weights = Some(weights);
    }
    let recorder = steps.recorder;
    let contact_floor = contact.as_ref().map(|c| c.floor().clone());
    metrics.contact = contact.map(|c| c.finish());
    Ok(VariantRun {
        name: name.to_string(),
        metrics,
        series: recorder.series,
        joints,
        free_motion: recorder.free_motion,
        node_weights,
        observer_validation,
        divergence: health.divergence,
        arm_warnings: Vec::new(),
        health_settings: Default::default(),
        settings: Default::default(),
        contact_floor,
    })
}
