//! The dynamic-node events of docs/method.md section 4 on a [`NeuralController`]: discard
//! and grow, with the per-step relevance tracking and growth attempts.

use admittance_learning::rbf::{GaussianRbfLayer, GrowOutcome};

use super::controller::NeuralController;
use super::networks::FNet;
use super::nodes::{GrowthProgress, GrowthRequest, NetworkId};
use crate::error::ConfigError;

impl NeuralController {
    /// The network `id`, if this controller has it.
    pub fn network(&self, id: NetworkId) -> Option<&GaussianRbfLayer> {
        match (&self.f, id) {
            (FNet::Lumped { net, .. }, NetworkId::F) => Some(net),
            (FNet::Split { m, .. }, NetworkId::M) => Some(m),
            (FNet::Split { c, .. }, NetworkId::C) => Some(c),
            (FNet::Split { g, .. }, NetworkId::G) => Some(g),
            (_, NetworkId::Deadzone) => self.t.as_ref(),
            _ => None,
        }
    }

    /// Mutable access to network `id` (e.g. to load weights). Changing its input dimension
    /// or output count is impossible through the layer's API; everything else is allowed.
    pub fn network_mut(&mut self, id: NetworkId) -> Option<&mut GaussianRbfLayer> {
        match (&mut self.f, id) {
            (FNet::Lumped { net, .. }, NetworkId::F) => Some(net),
            (FNet::Split { m, .. }, NetworkId::M) => Some(m),
            (FNet::Split { c, .. }, NetworkId::C) => Some(c),
            (FNet::Split { g, .. }, NetworkId::G) => Some(g),
            (_, NetworkId::Deadzone) => self.t.as_mut(),
            _ => None,
        }
    }

    /// The networks this controller has, in [`NetworkId::ALL`] order.
    pub fn network_ids(&self) -> impl Iterator<Item = NetworkId> + '_ {
        NetworkId::ALL
            .into_iter()
            .filter(|id| self.network(*id).is_some())
    }

    /// Active node count of network `id` (0 when absent).
    pub fn node_count(&self, id: NetworkId) -> usize {
        self.network(id).map_or(0, |l| l.len())
    }

    /// Frobenius norm of the weights of network `id` (0 when absent).
    pub fn weight_norm(&self, id: NetworkId) -> f64 {
        self.network(id).map_or(0.0, |l| l.weight_norm())
    }

    /// **Discard** (docs/method.md section 4, eq. 29-31): removes from network `id` every node
    /// whose tracked activation stayed below `upsilon` over the trailing relevance window
    /// (paper: 0.05); returns how many were removed. Needs relevance tracking
    /// ([`NeuralControllerConfig::track_relevance`](crate::NeuralControllerConfig::track_relevance)); nodes tracked for less than a full
    /// window are kept. Does not allocate.
    pub fn discard(&mut self, id: NetworkId, upsilon: f64) -> usize {
        self.network_mut(id).map_or(0, |l| l.discard(upsilon))
    }

    /// [`discard`](Self::discard) on every f network (lumped, or M, C and G); the deadzone
    /// network is left alone. Returns the total removed.
    pub fn discard_f(&mut self, upsilon: f64) -> usize {
        [NetworkId::F, NetworkId::M, NetworkId::C, NetworkId::G]
            .into_iter()
            .map(|id| self.discard(id, upsilon))
            .sum()
    }

    /// **Grow** (docs/method.md section 4): arms a request to add `request.nodes` nodes to
    /// network `id` near the trajectory. From the next step on, every `interval_steps`
    /// steps the controller tries one addition at the network's current input (see
    /// [`GrowthRequest::params`]) until the count is reached or the network is full. A new
    /// request replaces a pending one. Does not allocate.
    pub fn request_growth(
        &mut self,
        id: NetworkId,
        request: GrowthRequest,
    ) -> Result<(), ConfigError> {
        if self.network(id).is_none() {
            return Err(ConfigError::new(
                "network",
                format!("this controller has no `{}` network", id.as_str()),
            ));
        }
        request
            .params
            .validate()
            .map_err(|e| ConfigError::new("growth.params", format!("{e}")))?;
        if request.interval_steps == 0 {
            return Err(ConfigError::new(
                "growth.interval_steps",
                "must be at least 1",
            ));
        }
        let state = &mut self.growth[id.index()];
        state.request = Some(request);
        state.since = request.interval_steps; // first attempt at the next step
        state.progress.pending = request.nodes;
        Ok(())
    }

    /// Progress of growth on network `id`.
    pub fn growth_progress(&self, id: NetworkId) -> GrowthProgress {
        self.growth[id.index()].progress
    }

    /// Cancels a pending growth request on network `id`.
    pub fn cancel_growth(&mut self, id: NetworkId) {
        let s = &mut self.growth[id.index()];
        s.request = None;
        s.progress.pending = 0;
    }

    pub(super) fn after_step(&mut self) {
        let track = self.track_relevance;
        for id in NetworkId::ALL {
            let state = self.growth[id.index()];
            let grow = state.progress.pending > 0 && state.request.is_some();
            if !track && !grow {
                continue;
            }
            let Some(layer) = self.network_mut(id) else {
                continue;
            };
            if track {
                let _ = layer.track_relevance();
            }
            if !grow {
                continue;
            }
            let request = state.request.expect("checked above");
            let mut state = state;
            state.since = state.since.saturating_add(1);
            if state.since >= request.interval_steps {
                match layer.maybe_grow_at_last_input(&request.params) {
                    Ok(GrowOutcome::Added { .. }) => {
                        state.progress.pending -= 1;
                        state.progress.added += 1;
                        state.since = 0;
                    }
                    Ok(GrowOutcome::AtCapacity { .. }) => {
                        state.progress.pending = 0;
                    }
                    Ok(_) => state.progress.declined += 1,
                    Err(_) => {}
                }
                if state.progress.pending == 0 {
                    state.request = None;
                }
            }
            self.growth[id.index()] = state;
        }
    }

    /// After a faulted law step: a network whose weights are no longer all finite (they
    /// cannot recover by themselves) is zeroed, so that learning restarts at the next step.
    pub(super) fn zero_non_finite_networks(&mut self) {
        for id in NetworkId::ALL {
            if let Some(layer) = self.network_mut(id) {
                if !layer.weights().iter().all(|w| w.is_finite()) {
                    layer.reset_weights();
                }
            }
        }
    }
}
