//! Dynamic-node events of experiment C (docs/method.md section 4): the discard and the growth
//! requests at their times, the approximation error of `f` at the end of each phase, and the
//! f network's node weights over time.

use admittance_control::{true_lumped_f, GrowthRequest, NetworkId};
use admittance_dynamics::{Data, Model};
use admittance_loop::ClosedLoop;

use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::metrics::{rms, DynamicNodeMetrics};
use crate::series::{NodeWeightTrace, TimeSeries, NODE_WEIGHT_INTERVAL};
use crate::spec::DynamicNodesSpec;

/// The events and what they are measured with.
pub(crate) struct NodeEvents {
    spec: DynamicNodesSpec,
    duration: f64,
    discarded: Option<usize>,
    growth_requested: bool,
    /// `f - f_hat` samples at the end of each phase (before the discard, before growth, end).
    approx: [Vec<f64>; 3],
    /// `f` of the true arm with the controller's `alpha`, `alpha'`.
    pub f_true: Vec<f64>,
    f_data: Data,
    max_weight_norm: f64,
    trace: NodeWeightTrace,
    weight_stride: usize,
}

impl NodeEvents {
    /// For the true arm `model` and a run of `duration` s at control period `dt`.
    pub fn new(spec: DynamicNodesSpec, model: &Model, duration: f64, dt: f64) -> Self {
        Self {
            spec,
            duration,
            discarded: None,
            growth_requested: false,
            approx: [Vec::new(), Vec::new(), Vec::new()],
            f_true: vec![0.0; model.nq()],
            f_data: Data::new(model),
            max_weight_norm: 0.0,
            trace: NodeWeightTrace::default(),
            weight_stride: ((NODE_WEIGHT_INTERVAL / dt).round() as usize).max(1),
        }
    }

    /// The discard and the growth request when their times come, before the loop steps.
    pub fn before_step(
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

    /// After step `k` at `t`: `f` of the true arm in state `(q, qdot)` against `f_hat`, in
    /// each phase's window, and the node weights.
    pub fn after_step(
        &mut self,
        k: usize,
        t: f64,
        model: &Model,
        q: &[f64],
        qdot: &[f64],
        lp: &ClosedLoop,
    ) {
        let Some(nn) = lp.neural() else {
            return;
        };
        let _ = true_lumped_f(
            model,
            &mut self.f_data,
            q,
            qdot,
            nn.alpha(),
            nn.alpha_dot(),
            &mut self.f_true,
        );
        let phase_ends = [self.spec.discard_time, self.spec.grow_time, self.duration];
        for (p, end) in phase_ends.iter().enumerate() {
            if t >= end - self.spec.approximation_window && t < *end {
                for (a, b) in self.f_true.iter().zip(nn.f_hat()) {
                    self.approx[p].push(a - b);
                }
            }
        }
        self.max_weight_norm = self.max_weight_norm.max(nn.weight_norm(NetworkId::F));
        if let Some(layer) = nn.network(NetworkId::F) {
            if k.is_multiple_of(self.weight_stride) {
                self.trace.sample(t, layer);
            }
        }
    }

    /// The metrics of experiment C and the node-weight series.
    pub fn finish(self, lp: &ClosedLoop) -> Option<(DynamicNodeMetrics, TimeSeries)> {
        let nn = lp.neural()?;
        Some((
            DynamicNodeMetrics {
                approx_rmse_full: rms(&self.approx[0]),
                approx_rmse_after_discard: rms(&self.approx[1]),
                approx_rmse_after_growth: rms(&self.approx[2]),
                nodes_discarded: self.discarded.unwrap_or(0),
                nodes_added: nn.growth_progress(NetworkId::F).added,
                weight_norm_max: self.max_weight_norm,
            },
            self.trace.into_series(),
        ))
    }
}
