//! One variant of a scenario, run: the assembled parts stepped period by period (the
//! plant, its sensors, the [`ClosedLoop`], the dynamic-node events), with the metrics
//! ([`Gather`]) and the time series ([`Recorder`]) gathered on the way.

use std::path::Path;

use admittance_control::{NetworkId, ReferenceInput};
use admittance_loop::{ClosedLoop, LoopInput};
use admittance_sim::SimError;

use crate::assemble::{assemble, Assembly};
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::gather::{Gather, WindowSample};
use crate::hand::HandKinematics;
use crate::metrics::VariantMetrics;
use crate::node_events::NodeEvents;
use crate::progress::{RunOptions, Stage};
use crate::recorder::{Recorder, Row};
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
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
        mut oracle_admittance,
        observer_training,
        observer_validation,
        identification,
        arm_warnings,
        mut contact,
    } = parts;
    let n = joints.len();
    let dt = closed_loop.dt();
    let sim_err = |e: SimError| ctx.err("plant", e.to_string(), None);
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
    if contact.is_some() {
        recorder.record_contact(&joints);
    }
    let mut gather = Gather::new(&model, &joints, &effort, steps, with_hand);
    let mut gates = crate::gate_stage::GateStage::new(&model, &scenario.gates, dt)
        .map_err(|e| ctx.err("plant", e.to_string(), None))?;
    let mut kinematics = HandKinematics::new(&model);
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
        recorder.sensed(t, m);
        if let Some(adm) = oracle_admittance.as_mut() {
            let input = ReferenceInput {
                q_d: &q_d,
                qdot_d: &qd_d,
                qddot_d: &qdd_d,
                q: &m.q,
                external_torque_estimate: plant.tau_ext(),
            };
            let _ = adm.step(&input, dt);
        }
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
        // A sample older than this period (the driver repeated a joint's last reading) is
        // stale whether or not the controller could tell from the values.
        let stale_sample = m.sample_time.iter().any(|&ts| t - ts > 0.5 * dt);
        if let Some(c) = contact.as_mut() {
            c.update(closed_loop.external_torque_estimate(), &m.qdot, &m.qddot);
        }
        gather.after_control(k, &status, &closed_loop, stale_sample);
        if let Some(ev) = events.as_mut() {
            ev.after_step(k, t, &model, plant.q(), plant.qdot(), &closed_loop);
        }
        plant.step_control(closed_loop.torque()).map_err(sim_err)?;
        // A step that left the physical bounds ends the variant before it reaches the
        // metrics: what they hold is the run up to that point.
        if gather.diverged(t, plant.q(), plant.qdot(), m, &closed_loop) {
            break;
        }
        let record = plant.record();
        // Hand error by forward kinematics of the true angles against the reference.
        let p_ref = kinematics.position(&model, closed_loop.q_r());
        let p_hand = kinematics.position(&model, plant.q());
        let ee_error = (0..3)
            .map(|i| (p_hand[i] - p_ref[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let hand_force = plant.environment().tip_force();
        let hand_estimate = closed_loop
            .admittance()
            .and_then(|c| c.task_space())
            .map(|a| &a.wrench_estimate()[..3]);
        if t >= scenario.evaluation_start {
            if let Some(c) = contact.as_mut() {
                c.in_window(t, &record.tau_ext, closed_loop.q_r(), &q_d);
            }
            gather.in_window(&WindowSample {
                q_r: closed_loop.q_r(),
                q: plant.q(),
                torque: closed_loop.torque(),
                estimate: closed_loop.external_torque_estimate(),
                record,
                q_r_oracle: oracle_admittance.as_ref().map(|a| a.q_r()),
                ee_error,
                hand: hand_estimate.map(|f_hat| (&hand_force, f_hat)),
                coverage: closed_loop.estimate_coverage(),
            });
        }
        if recorder.wants(k) {
            let p_d = if with_hand {
                kinematics.position(&model, &q_d)
            } else {
                [0.0; 3]
            };
            recorder.row(&Row {
                t,
                q_d: &q_d,
                q_r: closed_loop.q_r(),
                q: plant.q(),
                qdot: plant.qdot(),
                measurement: m,
                torque: closed_loop.torque(),
                record,
                estimate: closed_loop.external_torque_estimate(),
                ee_error,
                f: events.as_ref().map(|ev| {
                    (
                        &ev.f_true[..],
                        closed_loop.neural().map(|c| c.f_hat()).unwrap_or(&zeros),
                    )
                }),
                nodes: closed_loop.neural().map(|nn| nn.node_count(NetworkId::F)),
                hand: hand_estimate
                    .map(|f_hat| [&hand_force[..], f_hat, &p_hand[..], &p_ref[..], &p_d[..]]),
                coverage: closed_loop.estimate_coverage(),
                contact: contact.as_ref().map(|c| c.flags()),
            });
        }
    }
    options.report(variant_name, Stage::Simulate, steps as u64, steps as u64);
    let mut run = finish(
        variant_name,
        &closed_loop,
        gather,
        recorder,
        events,
        joints,
        oracle_admittance.is_some(),
        observer_training,
        observer_validation,
    )?;
    run.arm_warnings = arm_warnings;
    if let Some(c) = contact {
        run.contact_floor = Some(c.floor().clone());
        run.metrics.contact = Some(c.finish());
    }
    run.health_settings = scenario.health.clone();
    run.metrics.identification = identification;
    run.metrics.gated_samples = Some(gates.counts());
    run.settings = settings;
    Ok(run)
}

/// Everything gathered, as a [`VariantRun`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish(
    name: &str,
    closed_loop: &ClosedLoop,
    gather: Gather,
    recorder: Recorder,
    events: Option<NodeEvents>,
    joints: Vec<String>,
    with_oracle_reference: bool,
    observer_training: Option<crate::metrics::ObserverTrainingMetrics>,
    observer_validation: Option<TimeSeries>,
) -> Result<VariantRun, ScenarioError> {
    let (mut metrics, health) = gather.finish(with_oracle_reference);
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
        contact_floor: None,
    })
}
