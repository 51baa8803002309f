//! One variant of a scenario, run: the assembled parts stepped period by period (the
//! plant, its sensors, the [`ClosedLoop`], the dynamic-node events), with the metrics and
//! the time series gathered on the way.

use std::path::Path;

use admittance_control::{true_lumped_f, GrowthRequest, NetworkId, ReferenceInput};
use admittance_dynamics::{forward_kinematics, Data};
use admittance_sim::SimError;

use crate::assemble::{assemble, Assembly};
use crate::closed_loop::{ClosedLoop, LoopInput};
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::hand::{hand_columns, HandStats};
use crate::health::{Divergence, Health};
use crate::metrics::{median, rms, DynamicNodeMetrics, JointStats, ObserverStats, VariantMetrics};
use crate::progress::{RunOptions, Stage};
use crate::series::{
    free_motion_columns, variant_columns, NodeWeightTrace, TimeSeries, NODE_WEIGHT_INTERVAL,
};
use crate::source::ScenarioSource;
use crate::spec::DynamicNodesSpec;

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
    /// [`NODE_WEIGHT_INTERVAL`] seconds; columns `t, w.ID`.
    pub node_weights: Option<TimeSeries>,
    /// With a learned observer: its network on the validation data.
    pub observer_validation: Option<TimeSeries>,
    /// Why and when the variant stopped early, if it did.
    pub divergence: Option<Divergence>,
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

/// Dynamic-node events of experiment C and the approximation error of each phase.
struct NodeEvents {
    spec: DynamicNodesSpec,
    discarded: Option<usize>,
    growth_requested: bool,
    approx: [Vec<f64>; 3],
    f_true: Vec<f64>,
    f_data: Data,
    max_weight_norm: f64,
    trace: NodeWeightTrace,
}

impl NodeEvents {
    fn before_step(
        &mut self,
        ctx: &Ctx<'_>,
        t: f64,
        lp: &mut ClosedLoop,
    ) -> Result<(), ScenarioError> {
        let Some(nn) = lp.neural_mut() else {
            return Ok(());
        };
        if self.discarded.is_none() && t >= self.spec.discard_time {
            self.discarded = Some(nn.discard(NetworkId::F, self.spec.upsilon));
        }
        if !self.growth_requested && t >= self.spec.grow_time {
            let request = GrowthRequest {
                nodes: self.spec.grow_nodes,
                interval_steps: self.spec.grow_interval_steps,
                params: self.spec.growth,
            };
            nn.request_growth(NetworkId::F, request)
                .map_err(|e| ctx.err("dynamic_nodes.growth", e.to_string(), None))?;
            self.growth_requested = true;
        }
        Ok(())
    }
}

/// Steps the assembled parts to the end and gathers metrics and series.
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
    } = parts;
    let n = joints.len();
    let dt = closed_loop.dt();
    let sim_err = |e: SimError| ctx.err("plant", e.to_string(), None);
    let mut free_motion = scenario.record.free_motion_csv.then(|| TimeSeries {
        columns: free_motion_columns(&joints),
        rows: Vec::new(),
    });
    let mut tau_filtered_prev = vec![0.0; n];
    let effort: Vec<f64> = plant.effort_limits().to_vec();
    let mut kin_data = Data::new(plant.model());
    let tip = plant.model().tip_frame;
    let mut events = scenario.dynamic_nodes.clone().map(|spec| NodeEvents {
        spec,
        discarded: None,
        growth_requested: false,
        approx: [Vec::new(), Vec::new(), Vec::new()],
        f_true: vec![0.0; n],
        f_data: Data::new(plant.model()),
        max_weight_norm: 0.0,
        trace: NodeWeightTrace::default(),
    });
    let steps = (scenario.duration / dt).round() as usize;
    let decimation = scenario.output.decimation;
    let with_nodes = closed_loop.neural().is_some();
    // A task-space run records the hand: forces and positions.
    let with_hand = closed_loop
        .admittance()
        .is_some_and(|c| c.task_space().is_some());
    let mut hand_stats = with_hand.then(HandStats::default);
    let mut columns = variant_columns(&joints, events.is_some(), with_nodes);
    if with_hand {
        columns.extend(hand_columns());
    }
    let mut series = TimeSeries {
        columns,
        rows: Vec::new(),
    };
    let (mut q_d, mut qd_d, mut qdd_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let zeros = vec![0.0; n];
    let mut tracking = JointStats::new(n);
    let mut torque = JointStats::new(n);
    let mut estimate_error = JointStats::new(n);
    let mut observer_stats = ObserverStats::new(n);
    let mut ee_errors = Vec::new();
    let mut deadzone_steps = vec![0usize; n];
    let mut window_steps = 0usize;
    let mut step_times: Vec<f64> = Vec::with_capacity(steps.min(200_000));
    let timing_stride = (steps / 200_000).max(1);
    let (mut faults, mut limit_violations, mut nonfinite_torques, mut observer_faults) =
        (0, 0, 0, 0);
    let weight_stride = ((NODE_WEIGHT_INTERVAL / dt).round() as usize).max(1);
    let variant_name = ctx.variant.unwrap_or("base");
    let progress_stride = (steps / 100).max(1);
    let mut health = Health::new(plant.model(), &joints, &effort);

    for k in 0..steps {
        if k % progress_stride == 0 {
            options.report(variant_name, Stage::Simulate, k as u64, steps as u64);
        }
        let t = k as f64 * dt;
        trajectory.eval(t, &mut q_d, &mut qd_d, &mut qdd_d);
        sensors
            .sample(t, plant.q(), closed_loop.torque())
            .map_err(sim_err)?;
        let m = sensors.measurement();
        // Free-motion data: what the sensors saw, with the filtered command delayed by one
        // sample to match qddot's delay (METHOD.md section 7, docs/outputs.md).
        if let Some(fm) = free_motion.as_mut() {
            let mut row = Vec::with_capacity(1 + 4 * n);
            row.push(t);
            for v in [&m.q_filtered[..], &m.qdot, &m.qddot, &tau_filtered_prev] {
                row.extend_from_slice(v);
            }
            fm.rows.push(row);
        }
        tau_filtered_prev.copy_from_slice(&m.tau_filtered);
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
        if !status.observer_ok {
            observer_faults += 1;
        }
        if k % timing_stride == 0 && step_times.len() < step_times.capacity() {
            step_times.push(closed_loop.controller_seconds() * 1e6);
        }
        if !status.controller.is_ok() {
            faults += 1;
        }
        let tau = closed_loop.torque();
        for (i, t_i) in tau.iter().enumerate() {
            if !t_i.is_finite() {
                nonfinite_torques += 1;
            } else if t_i.abs() > effort[i] * (1.0 + 1e-12) {
                limit_violations += 1;
            }
        }
        // Approximation of f (experiment C) with the controller's alpha.
        if let (Some(ev), Some(nn)) = (events.as_mut(), closed_loop.neural()) {
            let _ = true_lumped_f(
                plant.model(),
                &mut ev.f_data,
                plant.q(),
                plant.qdot(),
                nn.alpha(),
                nn.alpha_dot(),
                &mut ev.f_true,
            );
            let phase_ends = [ev.spec.discard_time, ev.spec.grow_time, scenario.duration];
            for (p, end) in phase_ends.iter().enumerate() {
                if t >= end - ev.spec.approximation_window && t < *end {
                    for (a, b) in ev.f_true.iter().zip(nn.f_hat()) {
                        ev.approx[p].push(a - b);
                    }
                }
            }
            ev.max_weight_norm = ev.max_weight_norm.max(nn.weight_norm(NetworkId::F));
            if let Some(layer) = nn.network(NetworkId::F) {
                if k % weight_stride == 0 {
                    ev.trace.sample(t, layer);
                }
            }
        }
        let q_r = closed_loop.q_r();
        if let Some(sat) = closed_loop.admittance().and_then(|a| a.saturation()) {
            for (i, r) in q_r.iter().enumerate() {
                let (c, h) = (sat.centre()[i], sat.half_range()[i]);
                if !(*r > c - h && *r < c + h) {
                    observer_stats.bound_violations += 1;
                }
            }
        }
        plant.step_control(closed_loop.torque()).map_err(sim_err)?;
        let record = plant.record();
        let estimate = closed_loop.external_torque_estimate();
        let q_r = closed_loop.q_r();
        let tau = closed_loop.torque();
        // A step that left the physical bounds ends the variant before it reaches the
        // metrics: what they hold is the run up to that point.
        if health
            .add(t, plant.q(), plant.qdot(), m, tau, estimate)
            .is_some()
        {
            break;
        }
        // Hand error by forward kinematics of the true angles against the reference.
        let _ = forward_kinematics(plant.model(), &mut kin_data, q_r);
        let p_ref = kin_data.frame_placements[tip].translation;
        let _ = forward_kinematics(plant.model(), &mut kin_data, plant.q());
        let p_hand = kin_data.frame_placements[tip].translation;
        let ee_error = (p_hand - p_ref).norm();
        let hand_force = plant.environment().tip_force();
        let hand_estimate = closed_loop
            .admittance()
            .and_then(|c| c.task_space())
            .map(|a| &a.wrench_estimate()[..3]);
        if t >= scenario.evaluation_start {
            tracking.add(q_r.iter().zip(plant.q()).map(|(r, q)| r - q));
            torque.add(tau.iter().copied());
            estimate_error.add(estimate.iter().zip(&record.tau_ext).map(|(e, t)| e - t));
            observer_stats.add(
                estimate,
                &record.tau_ext,
                q_r,
                oracle_admittance.as_ref().map(|a| a.q_r()),
            );
            ee_errors.push(ee_error);
            if let (Some(h), Some(f_hat)) = (hand_stats.as_mut(), hand_estimate) {
                h.add(&hand_force, f_hat);
            }
            window_steps += 1;
            for (c, dz) in deadzone_steps.iter_mut().zip(&record.in_deadzone) {
                *c += *dz as usize;
            }
        }
        if k % decimation == 0 {
            let mut row = Vec::with_capacity(series.columns.len());
            row.push(t);
            for v in [
                &q_d[..],
                q_r,
                plant.q(),
                plant.qdot(),
                &m.q[..],
                tau,
                &record.applied,
                &record.tau_ext,
                estimate,
            ] {
                row.extend_from_slice(v);
            }
            row.push(ee_error);
            if let Some(ev) = events.as_ref() {
                row.extend_from_slice(&ev.f_true);
                row.extend_from_slice(closed_loop.neural().map(|c| c.f_hat()).unwrap_or(&zeros));
            }
            if let Some(nn) = closed_loop.neural() {
                row.push(nn.node_count(NetworkId::F) as f64);
            }
            if let Some(f_hat) = hand_estimate {
                row.extend_from_slice(&hand_force);
                row.extend_from_slice(f_hat);
                row.extend_from_slice(p_hand.as_slice());
                row.extend_from_slice(p_ref.as_slice());
                let _ = forward_kinematics(plant.model(), &mut kin_data, &q_d);
                row.extend_from_slice(kin_data.frame_placements[tip].translation.as_slice());
            }
            series.rows.push(row);
        }
    }
    options.report(variant_name, Stage::Simulate, steps as u64, steps as u64);

    let [q_limit_violation_fraction, torque_saturation_fraction, estimate_saturation_fraction] =
        health.fractions_all();
    let mut metrics = VariantMetrics {
        diverged: health.divergence.is_some(),
        diverged_at: health.divergence.as_ref().map(|d| d.time),
        q_limit_violation_fraction,
        torque_saturation_fraction,
        estimate_saturation_fraction,
        tracking_rmse: tracking.rms(),
        tracking_max_abs: tracking.max_abs.clone(),
        ee_error_rms: rms(&ee_errors),
        ee_error_max: ee_errors.iter().cloned().fold(0.0, f64::max),
        torque_rms: torque.rms(),
        torque_max_abs: torque.max_abs.clone(),
        deadzone_time_fraction: deadzone_steps
            .iter()
            .map(|c| *c as f64 / window_steps.max(1) as f64)
            .collect(),
        controller_step_median_us: median(&mut step_times),
        faults,
        torque_limit_violations: limit_violations,
        nonfinite_torques,
        steps,
        external_torque_rmse: estimate_error.rms(),
        observer_faults,
        observer_training,
        ..VariantMetrics::default()
    };
    observer_stats.finish(&mut metrics, oracle_admittance.is_some());
    metrics.hand = hand_stats.map(|h| h.finish());
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
    if let (Some(ev), Some(nn)) = (events, closed_loop.neural()) {
        metrics.dynamic_nodes = Some(DynamicNodeMetrics {
            approx_rmse_full: rms(&ev.approx[0]),
            approx_rmse_after_discard: rms(&ev.approx[1]),
            approx_rmse_after_growth: rms(&ev.approx[2]),
            nodes_discarded: ev.discarded.unwrap_or(0),
            nodes_added: nn.growth_progress(NetworkId::F).added,
            weight_norm_max: ev.max_weight_norm,
        });
        node_weights = Some(ev.trace.into_series());
    }
    Ok(VariantRun {
        name: variant_name.to_string(),
        metrics,
        series,
        joints,
        free_motion,
        node_weights,
        observer_validation,
        divergence: health.divergence,
    })
}
