//! The Gaussian RBF layer: storage, evaluation, adaptation, relevance, discard, growth.

mod adaptation;
mod structure;

use super::config::{GrowthParams, Integrator, RbfLayerConfig};
use super::kernels::{self, centre_slot, gaussian, padded, sq_dist, Isa, Nodes, MAX_EXPONENT};
use super::{RbfConfigError, RbfError};

/// Run-time options of a layer that do not describe its initial centres (see
/// [`RbfLayerConfig`] for their meaning; the defaults are the same as there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerOptions {
    /// Adaptation gain `Gamma = Theta^-1` (docs/method.md section 3).
    pub gamma: f64,
    /// Sigma-modification `sigma` (docs/method.md section 3).
    pub sigma: f64,
    /// Weight integrator.
    pub integrator: Integrator,
    /// Width given to a node grown in an empty layer.
    pub default_width: f64,
    /// Relevance window `W` in tracked steps (docs/method.md section 4).
    pub relevance_window: usize,
    /// Activations below this are computed as zero (node skipped).
    pub min_activation: f64,
    /// Largest `m` for growth (fixed scratch size).
    pub max_neighbours: usize,
    /// Growth parameters carried with the layer, if any.
    pub growth: Option<GrowthParams>,
}

impl Default for LayerOptions {
    /// Experiment-C gains (Gamma = 1/0.03, sigma = 0.035), exact-decay integration, width 1,
    /// window 1000 steps, cut-off 1e-16, up to 16 neighbours, no growth parameters.
    fn default() -> Self {
        let c = RbfLayerConfig::default();
        LayerOptions {
            gamma: c.gamma,
            sigma: c.sigma,
            integrator: c.integrator,
            default_width: c.width,
            relevance_window: c.relevance_window,
            min_activation: c.min_activation,
            max_neighbours: c.max_neighbours,
            growth: None,
        }
    }
}

impl LayerOptions {
    fn validate(&self) -> Result<(), RbfConfigError> {
        if !(self.gamma.is_finite() && self.gamma >= 0.0) {
            return Err(RbfConfigError::InvalidGain {
                name: "gamma",
                value: self.gamma,
            });
        }
        if !(self.sigma.is_finite() && self.sigma >= 0.0) {
            return Err(RbfConfigError::InvalidGain {
                name: "sigma",
                value: self.sigma,
            });
        }
        if inverse_width_sq(self.default_width).is_none() {
            return Err(RbfConfigError::InvalidWidth(self.default_width));
        }
        if self.relevance_window == 0 {
            return Err(RbfConfigError::InvalidOption {
                name: "relevance_window",
            });
        }
        if !(self.min_activation >= 0.0 && self.min_activation < 1.0) {
            return Err(RbfConfigError::InvalidOption {
                name: "min_activation",
            });
        }
        if self.max_neighbours == 0 {
            return Err(RbfConfigError::InvalidOption {
                name: "max_neighbours",
            });
        }
        if let Some(g) = &self.growth {
            g.validate()?;
        }
        Ok(())
    }
}

/// `1 / eta^2` when it is finite and positive.
fn inverse_width_sq(width: f64) -> Option<f64> {
    let inv = 1.0 / (width * width);
    (width.is_finite() && width > 0.0 && inv.is_finite() && inv > 0.0).then_some(inv)
}

/// Result of [`GaussianRbfLayer::maybe_grow`] (docs/method.md section 4, eq. 20-22).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GrowOutcome {
    /// A node was added at `index` (always the last index, `len() - 1`).
    Added {
        /// Index of the new node.
        index: usize,
        /// Mean distance from `Z` to its `m` nearest centres before the addition (eq. 21).
        mean_distance: f64,
    },
    /// `mean_distance <= Xi`: the input is covered, nothing added.
    Covered {
        /// Mean distance from `Z` to its `m` nearest centres.
        mean_distance: f64,
    },
    /// Growth was due but the layer is full.
    AtCapacity {
        /// Mean distance from `Z` to its `m` nearest centres.
        mean_distance: f64,
    },
    /// Growth was due but the candidate centre lies closer than the minimum spacing to an
    /// existing centre.
    TooClose {
        /// Mean distance from `Z` to its `m` nearest centres.
        mean_distance: f64,
        /// Distance from the candidate centre to the closest existing centre.
        nearest: f64,
    },
}

impl GrowOutcome {
    /// Whether a node was added.
    pub fn added(&self) -> bool {
        matches!(self, GrowOutcome::Added { .. })
    }
}

/// A Gaussian RBF layer with preallocated capacity and dynamic nodes (docs/method.md sections 3-4).
///
/// * evaluation: `s_i(Z) = exp(-||Z - u_i||^2 / eta_i^2)` (eq. 9), `f_hat = W^T S(Z)`
///   ([`activate`](Self::activate), [`output`](Self::output), [`evaluate`](Self::evaluate),
///   and the state-free [`predict`](Self::predict));
/// * adaptation: `W' = Gamma (S(Z) e^T - sigma W)` ([`adapt`](Self::adapt));
/// * dynamic nodes: [`track_relevance`](Self::track_relevance),
///   [`discard`](Self::discard), [`maybe_grow`](Self::maybe_grow),
///   [`add_node`](Self::add_node).
///
/// All storage (`capacity` nodes) is allocated by the constructor; no method allocates
/// afterwards, and no method panics, whatever its arguments: bad lengths and non-finite
/// values are reported as [`RbfError`] and leave the weights untouched.
///
/// Activations below `min_activation` (default `1e-16`) are computed as exactly zero without
/// evaluating `exp`; this is the only deviation from eq. 9, far below the rounding error of
/// any node in range.
#[derive(Debug, Clone)]
pub struct GaussianRbfLayer {
    dim: usize,
    outputs: usize,
    capacity: usize,
    len: usize,
    gamma: f64,
    sigma: f64,
    integrator: Integrator,
    default_width: f64,
    min_activation: f64,
    /// Largest scaled squared distance `||Z - u||^2 / eta^2` evaluated.
    exponent_cutoff: f64,
    window: usize,
    /// Steps tracked in the current relevance bucket.
    window_fill: usize,
    growth: Option<GrowthParams>,
    /// `capacity * dim`, node-major (the public layout).
    centres: Vec<f64>,
    /// The same centres block-major (`kernels::centre_slot`, `dim * padded(capacity)`
    /// values), for the distance kernel.
    centres_t: Vec<f64>,
    widths: Vec<f64>,
    inv_width_sq: Vec<f64>,
    /// `capacity * outputs`, node-major (row `i` is `W_i`).
    weights: Vec<f64>,
    /// `S(Z)` at the last input (`stride` values, the first `len` meaningful).
    activations: Vec<f64>,
    /// `||Z - u_i||^2` at the last input (`stride` values).
    dist_sq: Vec<f64>,
    /// Distances for `maybe_grow` at an arbitrary input (`stride` values).
    scratch_sq: Vec<f64>,
    relevance_current: Vec<f64>,
    relevance_previous: Vec<f64>,
    /// Value of `tracked_steps` when the node was added (or relevance was reset).
    born_at: Vec<u64>,
    /// Relevance steps tracked since construction.
    tracked_steps: u64,
    last_input: Vec<f64>,
    /// `activations`, `dist_sq` and `last_input` describe a finite input.
    activations_valid: bool,
    nn_dist_sq: Vec<f64>,
    nn_index: Vec<usize>,
    /// Kernel instruction set, detected at construction.
    isa: Isa,
}

impl GaussianRbfLayer {
    /// Builds the layer described by `config` (docs/method.md section 3: centres on a lattice,
    /// sampled in a box, or listed), with zero weights.
    pub fn from_config(config: &RbfLayerConfig) -> Result<Self, RbfConfigError> {
        let centres = config.centres()?;
        let options = LayerOptions {
            gamma: config.gamma,
            sigma: config.sigma,
            integrator: config.integrator,
            default_width: config.width,
            relevance_window: config.relevance_window,
            min_activation: config.min_activation,
            max_neighbours: config.max_neighbours,
            growth: config.growth,
        };
        Self::with_centres(
            config.input_dim(),
            config.outputs,
            config.capacity,
            &centres,
            config.width,
            options,
        )
    }

    /// An empty layer (no nodes) with room for `capacity` nodes of input dimension `dim` and
    /// `outputs` outputs; nodes come from [`add_node`](Self::add_node) or
    /// [`maybe_grow`](Self::maybe_grow) (docs/method.md section 4).
    pub fn empty(
        dim: usize,
        outputs: usize,
        capacity: usize,
        options: LayerOptions,
    ) -> Result<Self, RbfConfigError> {
        Self::with_centres(dim, outputs, capacity, &[], options.default_width, options)
    }

    /// A layer with the given initial centres (flat, node-major, `k * dim` values), all of
    /// width `width` (eta of eq. 9) and zero weight (docs/method.md section 3).
    pub fn with_centres(
        dim: usize,
        outputs: usize,
        capacity: usize,
        centres: &[f64],
        width: f64,
        options: LayerOptions,
    ) -> Result<Self, RbfConfigError> {
        if dim == 0 {
            return Err(RbfConfigError::BoxDimension { lower: 0, upper: 0 });
        }
        if outputs == 0 || capacity == 0 {
            return Err(RbfConfigError::EmptyShape { outputs, capacity });
        }
        options.validate()?;
        let inv = inverse_width_sq(width).ok_or(RbfConfigError::InvalidWidth(width))?;
        if !centres.len().is_multiple_of(dim) {
            return Err(RbfConfigError::InvalidCentre {
                index: centres.len() / dim,
                got: centres.len() % dim,
                expected: dim,
            });
        }
        if let Some(pos) = centres.iter().position(|x| !x.is_finite()) {
            return Err(RbfConfigError::InvalidCentre {
                index: pos / dim,
                got: dim,
                expected: dim,
            });
        }
        let nodes = centres.len() / dim;
        if nodes > capacity {
            return Err(RbfConfigError::TooManyNodes { nodes, capacity });
        }
        // Refuse absurd sizes instead of aborting on allocation (2^32 values per buffer).
        const MAX_VALUES: usize = 1 << 32;
        let stride = padded(capacity.min(MAX_VALUES));
        let total = |k: usize| {
            stride
                .checked_mul(k)
                .filter(|&t| t <= MAX_VALUES)
                .ok_or(RbfConfigError::TooManyNodes {
                    nodes: capacity,
                    capacity: MAX_VALUES / k,
                })
        };
        let mut c = vec![0.0; total(dim)?];
        c[..centres.len()].copy_from_slice(centres);
        let mut centres_t = vec![0.0; total(dim)?];
        for (i, u) in centres.chunks_exact(dim).enumerate() {
            for (k, &x) in u.iter().enumerate() {
                centres_t[centre_slot(dim, k, i)] = x;
            }
        }
        let weights = vec![0.0; total(outputs)?];
        let mut widths = vec![options.default_width; capacity];
        widths[..nodes].fill(width);
        let mut inv_width_sq = vec![0.0; stride];
        inv_width_sq[..nodes].fill(inv);
        let m = options.max_neighbours;
        Ok(GaussianRbfLayer {
            dim,
            outputs,
            capacity,
            len: nodes,
            gamma: options.gamma,
            sigma: options.sigma,
            integrator: options.integrator,
            default_width: options.default_width,
            min_activation: options.min_activation,
            exponent_cutoff: exponent_cutoff(options.min_activation),
            window: options.relevance_window,
            window_fill: 0,
            growth: options.growth,
            centres: c,
            centres_t,
            widths,
            inv_width_sq,
            weights,
            activations: vec![0.0; stride],
            dist_sq: vec![0.0; stride],
            scratch_sq: vec![0.0; stride],
            relevance_current: vec![0.0; capacity],
            relevance_previous: vec![0.0; capacity],
            born_at: vec![0; capacity],
            tracked_steps: 0,
            last_input: vec![0.0; dim],
            activations_valid: false,
            nn_dist_sq: vec![0.0; m],
            nn_index: vec![0; m],
            isa: Isa::detect(),
        })
    }

    // ------------------------------------------------------------------------------------
    // Accessors
    // ------------------------------------------------------------------------------------

    /// Input dimension `d`.
    pub fn input_dim(&self) -> usize {
        self.dim
    }

    /// Number of outputs `n`.
    pub fn outputs(&self) -> usize {
        self.outputs
    }

    /// Number of active nodes `L`.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the layer has no active node.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Capacity `L_max` (docs/method.md section 4: the bound that keeps the node count finite).
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Centres `u_i` (eq. 9) of the active nodes, flat and node-major (`len() * input_dim()`
    /// values).
    pub fn centres(&self) -> &[f64] {
        &self.centres[..self.len * self.dim]
    }

    /// Centre `u_i` of node `i`, if `i < len()`.
    pub fn centre(&self, i: usize) -> Option<&[f64]> {
        (i < self.len).then(|| &self.centres[i * self.dim..(i + 1) * self.dim])
    }

    /// Widths `eta_i` of the active nodes (eq. 9).
    pub fn widths(&self) -> &[f64] {
        &self.widths[..self.len]
    }

    /// Weights `W` (L x n, docs/method.md section 0/3) of the active nodes, flat and node-major
    /// (`len() * outputs()` values; row `i` is `W_i`, the weights from node `i` to the `n`
    /// outputs).
    pub fn weights(&self) -> &[f64] {
        &self.weights[..self.len * self.outputs]
    }

    /// Mutable weights (same layout as [`weights`](Self::weights)), e.g. to load learned
    /// weights.
    pub fn weights_mut(&mut self) -> &mut [f64] {
        &mut self.weights[..self.len * self.outputs]
    }

    /// Weight row `W_i` of node `i`, if `i < len()`.
    pub fn weight_row(&self, i: usize) -> Option<&[f64]> {
        (i < self.len).then(|| &self.weights[i * self.outputs..(i + 1) * self.outputs])
    }

    /// Frobenius norm `||W||_F` of the active weights (the quantity that sigma-modification
    /// keeps bounded, docs/method.md section 3).
    pub fn weight_norm(&self) -> f64 {
        self.weights().iter().map(|w| w * w).sum::<f64>().sqrt()
    }

    /// Activations `S(Z)` at the last input passed to [`activate`](Self::activate) /
    /// [`evaluate`](Self::evaluate), for the active nodes (all zero before the first one).
    pub fn activations(&self) -> &[f64] {
        &self.activations[..self.len]
    }

    /// Whether [`activations`](Self::activations) describe a valid (finite) input.
    pub fn has_activations(&self) -> bool {
        self.activations_valid
    }

    /// The last finite input evaluated, if any.
    pub fn last_input(&self) -> Option<&[f64]> {
        self.activations_valid.then_some(&self.last_input[..])
    }

    /// Tracked relevance of node `i` (docs/method.md section 4): the largest activation over the
    /// trailing window, see [`track_relevance`](Self::track_relevance).
    pub fn relevance(&self, i: usize) -> Option<f64> {
        (i < self.len).then(|| self.relevance_current[i].max(self.relevance_previous[i]))
    }

    /// Number of relevance steps tracked since node `i` was added (saturating).
    pub fn observed_steps(&self, i: usize) -> Option<u64> {
        (i < self.len).then(|| self.tracked_steps - self.born_at[i])
    }

    /// Relevance window `W` in tracked steps.
    pub fn relevance_window(&self) -> usize {
        self.window
    }

    /// Adaptation gain `Gamma`.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Sigma-modification `sigma`.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The weight integrator.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// Activation cut-off (`min_activation`).
    pub fn min_activation(&self) -> f64 {
        self.min_activation
    }

    /// Growth parameters carried from the configuration, if any.
    pub fn growth_params(&self) -> Option<&GrowthParams> {
        self.growth.as_ref()
    }

    /// Largest `m` accepted by [`maybe_grow`](Self::maybe_grow).
    pub fn max_neighbours(&self) -> usize {
        self.nn_index.len()
    }

    /// Sets `Gamma` and `sigma` (docs/method.md section 3). Both must be finite and `>= 0`.
    pub fn set_gains(&mut self, gamma: f64, sigma: f64) -> Result<(), RbfError> {
        for g in [gamma, sigma] {
            if !(g.is_finite() && g >= 0.0) {
                return Err(RbfError::InvalidGain(g));
            }
        }
        self.gamma = gamma;
        self.sigma = sigma;
        Ok(())
    }

    /// Selects the weight integrator.
    pub fn set_integrator(&mut self, integrator: Integrator) {
        self.integrator = integrator;
    }

    /// Sets every active weight to zero.
    pub fn reset_weights(&mut self) {
        let end = self.len * self.outputs;
        self.weights[..end].fill(0.0);
    }

    /// Forgets the tracked relevance: every node starts a fresh window, as if just added.
    pub fn reset_relevance(&mut self) {
        self.relevance_current[..self.len].fill(0.0);
        self.relevance_previous[..self.len].fill(0.0);
        self.born_at[..self.len].fill(self.tracked_steps);
        self.window_fill = 0;
    }

    // ------------------------------------------------------------------------------------
    // Evaluation (eq. 9, 10)
    // ------------------------------------------------------------------------------------

    fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), RbfError> {
        if expected == got {
            Ok(())
        } else {
            Err(RbfError::DimensionMismatch {
                what,
                expected,
                got,
            })
        }
    }

    fn check_input(&self, z: &[f64]) -> Result<(), RbfError> {
        Self::check_len("input Z", self.dim, z.len())?;
        if z.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(RbfError::NonFiniteInput)
        }
    }

    /// Computes and stores `S(Z)` (eq. 9, docs/method.md section 3) for the active nodes.
    ///
    /// On a wrong length or a non-finite `Z` it returns an error and invalidates the stored
    /// activations, so that a following [`adapt`](Self::adapt) is refused rather than
    /// applied with stale data.
    pub fn activate(&mut self, z: &[f64]) -> Result<(), RbfError> {
        if let Err(e) = self.check_input(z) {
            self.activations_valid = false;
            return Err(e);
        }
        self.last_input.copy_from_slice(z);
        let nodes = Nodes {
            centres_t: &self.centres_t,
            len: self.len,
            inv_width_sq: &self.inv_width_sq,
            cutoff: self.exponent_cutoff,
        };
        kernels::activate(self.isa, z, nodes, &mut self.dist_sq, &mut self.activations);
        self.activations_valid = true;
        Ok(())
    }

    /// Writes `f_hat = W^T S(Z)` (eq. 10) at the stored activations into `out` (length `n`).
    pub fn output(&self, out: &mut [f64]) -> Result<(), RbfError> {
        Self::check_len("output", self.outputs, out.len())?;
        if !self.activations_valid {
            return Err(RbfError::NoActivations);
        }
        out.fill(0.0);
        let len = self.len;
        kernels::accumulate(
            self.isa,
            &self.activations[..len],
            &self.weights[..len * self.outputs],
            out,
        );
        Ok(())
    }

    /// [`activate`](Self::activate) at `z`, then [`output`](Self::output) into `out`.
    /// On error `out` is left unchanged.
    pub fn evaluate(&mut self, z: &[f64], out: &mut [f64]) -> Result<(), RbfError> {
        Self::check_len("output", self.outputs, out.len())?;
        self.activate(z)?;
        self.output(out)
    }

    /// `f_hat(z) = W^T S(z)` at an arbitrary input without touching the stored activations,
    /// relevance or weights (for measuring the approximation error, docs/method.md section 6 C).
    pub fn predict(&self, z: &[f64], out: &mut [f64]) -> Result<(), RbfError> {
        Self::check_len("output", self.outputs, out.len())?;
        self.check_input(z)?;
        out.fill(0.0);
        kernels::predict(self.isa, z, self.nodes(), self.weights(), out);
        Ok(())
    }

    fn nodes(&self) -> Nodes<'_> {
        Nodes {
            centres_t: &self.centres_t,
            len: self.len,
            inv_width_sq: &self.inv_width_sq,
            cutoff: self.exponent_cutoff,
        }
    }

    /// Activation `s_i(z)` (eq. 9) of every active node at an arbitrary input, written to
    /// `out[..len()]` (`out` must hold at least `len()` values); state untouched.
    pub fn activations_at(&self, z: &[f64], out: &mut [f64]) -> Result<(), RbfError> {
        self.check_input(z)?;
        if out.len() < self.len {
            return Err(RbfError::DimensionMismatch {
                what: "activation buffer",
                expected: self.len,
                got: out.len(),
            });
        }
        let d = self.dim;
        let centres = self.centres[..self.len * d].chunks_exact(d);
        for ((c, s), &iw) in centres
            .zip(out.iter_mut())
            .zip(&self.inv_width_sq[..self.len])
        {
            *s = gaussian(sq_dist(z, c) * iw, self.exponent_cutoff);
        }
        Ok(())
    }
}

#[cfg(test)]
impl GaussianRbfLayer {
    /// Selects the kernel build (tests compare the baseline and AVX2 builds).
    pub(crate) fn force_isa(&mut self, isa: Isa) {
        self.isa = isa;
    }

    pub(crate) fn step_coefficients_for_test(&self, dt: f64) -> (f64, f64) {
        self.step_coefficients(dt)
    }
}

/// `-ln(min_activation)`, capped at [`MAX_EXPONENT`].
fn exponent_cutoff(min_activation: f64) -> f64 {
    if min_activation > 0.0 {
        (-min_activation.ln()).min(MAX_EXPONENT)
    } else {
        MAX_EXPONENT
    }
}
