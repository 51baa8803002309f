//! Gaussian RBF layer of the adaptive neural controller (docs/method.md sections 3 and 4).
//!
//! A [`GaussianRbfLayer`] maps an input `Z` (dimension `d`) to `n` outputs
//!
//! ```text
//!     s_i(Z) = exp(-||Z - u_i||^2 / eta_i^2)          (eq. 9, docs/method.md section 3)
//!     f_hat(Z) = W^T S(Z)                             (eq. 10)
//! ```
//!
//! with `L` active nodes (centre `u_i`, width `eta_i`, weight row `W_i` of length `n`) out of a
//! capacity `L_max` fixed at construction. It implements, without allocating after
//! construction:
//!
//! * the sigma-modified update law `W' = Gamma (S(Z) e^T - sigma W)` (docs/method.md section 3,
//!   the corrected form of eq. 27), integrated over a control period by explicit Euler or by
//!   the exact zero-order-hold solution ([`Integrator`]);
//! * relevance tracking and **discard** of nodes whose activation stayed below a threshold
//!   `Upsilon` over a trailing window (docs/method.md section 4, eq. 29-31);
//! * **growth** of a node at the current input when the mean distance to its `m` nearest
//!   centres exceeds `Xi` (docs/method.md section 4, eq. 20-23; the new centre is placed at `Z`,
//!   or on the segment from the nearest centre to `Z`, see [`GrowthParams::step_fraction`]).
//!
//! # Design notes
//!
//! * **Relevance** (docs/method.md section 4): [`GaussianRbfLayer::track_relevance`] keeps, per
//!   node, the maximum activation over the current bucket of `W` tracked steps and over the
//!   previous complete bucket; the node's relevance is the larger of the two, i.e. its
//!   maximum activation over the last `W..2W` tracked steps. [`GaussianRbfLayer::discard`]
//!   removes a node iff it has been tracked for at least `W` steps and its relevance is
//!   below `Upsilon`.
//! * **Growth placement** (docs/method.md section 4, eq. 20): the new centre is placed at `Z`
//!   (default), or at `u_near + step_fraction (Z - u_near)` on the segment from the nearest
//!   centre; width = mean width of the `m` neighbours; weight row = 0.
//! * **Integration** (docs/method.md section 3): exact solution of the update law over a step
//!   with `S(Z)` and `e` held (default), or explicit Euler.
//! * **Cut-off**: activations below `min_activation` (default `1e-16`) are exactly zero.
//! * **Speed**: the distance kernel reads a block-major copy of the centres and handles
//!   32 nodes at a time; `exp` is a branch-free polynomial evaluated 16 lanes at a time
//!   (relative error below `1e-15` against `f64::exp`); outputs and weight updates are
//!   specialised for 1 to 8 outputs. The kernels are compiled for the baseline target and
//!   for AVX2 + FMA, chosen at run time. `evaluate` + `adapt` with 512 nodes, `d = 28`,
//!   `n = 7`, all nodes active, takes about 3.2 us on a 2.45 GHz AMD EPYC (see
//!   `benches/rbf_layer.rs`).
//!
//! Storage is flat and node-major: the centre of node `i` is
//! `centres()[i * d .. (i + 1) * d]`, its weight row `weights()[i * n .. (i + 1) * n]`.
//! Node indices are dense (`0..len()`); [`GaussianRbfLayer::discard`] compacts the storage
//! in place and preserves the relative order of the surviving nodes.
//!
//! # Example
//!
//! ```
//! use admittance_learning::rbf::{GaussianRbfLayer, Placement, RbfLayerConfig};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//!
//! let config = RbfLayerConfig {
//!     lower: vec![-1.0, -1.0],
//!     upper: vec![1.0, 1.0],
//!     placement: Placement::Lattice { points: vec![5, 5] },
//!     width: 0.5,
//!     capacity: 40,
//!     outputs: 1,
//!     ..RbfLayerConfig::default()
//! };
//! let mut layer = GaussianRbfLayer::from_config(&config)?;
//! let mut f_hat = [0.0];
//! for k in 0..5000 {
//!     let z = [(k as f64 * 1e-3).sin(), (k as f64 * 1e-3).cos()];
//!     layer.evaluate(&z, &mut f_hat)?;
//!     let e = [z[0] * z[1] - f_hat[0]]; // drive f_hat towards f(Z) = z0 z1
//!     layer.adapt(&e, 1e-3)?;
//!     layer.track_relevance()?;
//! }
//! // Nodes the input never came near (relevance < 0.05 over the last window) go.
//! let removed = layer.discard(0.05);
//! assert_eq!(layer.len() + removed, 25);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

mod config;
mod kernels;
mod layer;

#[cfg(test)]
mod tests;

pub use config::{
    lattice_centres, random_centres, GrowthParams, Integrator, Placement, RbfLayerConfig,
};
pub use layer::{GaussianRbfLayer, GrowOutcome, LayerOptions};

/// Errors reported by the per-step methods of [`GaussianRbfLayer`].
///
/// None of them leaves the layer in a corrupted state: a method that returns an error has
/// not modified the weights (docs/method.md section 3: adaptation is skipped, never fed with
/// non-finite data).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum RbfError {
    /// A slice argument has the wrong length.
    #[error("{what} has length {got}, expected {expected}")]
    DimensionMismatch {
        /// Which argument ("input Z", "error e", "output", "centre").
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Length received.
        got: usize,
    },
    /// The input `Z` contains a NaN or an infinity; the activations were invalidated.
    #[error("input Z is not finite")]
    NonFiniteInput,
    /// The error vector `e` (e2 in docs/method.md section 3) contains a NaN or an infinity;
    /// adaptation was skipped.
    #[error("error vector e is not finite")]
    NonFiniteError,
    /// [`GaussianRbfLayer::adapt`] or [`GaussianRbfLayer::output`] was called without valid
    /// activations (no successful [`GaussianRbfLayer::activate`] since construction or since
    /// the last non-finite input).
    #[error("no valid activations: evaluate a finite input first")]
    NoActivations,
    /// The integration step `dt` is negative or not finite.
    #[error("invalid time step {0}")]
    InvalidStep(f64),
    /// A width (eta) is not finite and positive, or so small that `1/eta^2` overflows.
    #[error("invalid width {0}")]
    InvalidWidth(f64),
    /// The layer is full (`len() == capacity()`).
    #[error("layer is at capacity ({0} nodes)")]
    AtCapacity(usize),
    /// A gain (Gamma or sigma) is negative or not finite.
    #[error("invalid gain {0}")]
    InvalidGain(f64),
}

/// Errors in a layer description ([`RbfLayerConfig`]) detected at construction.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RbfConfigError {
    /// Input dimension zero, or lower/upper bounds of different lengths.
    #[error("box has {lower} lower and {upper} upper bounds; need the same, non-zero count")]
    BoxDimension {
        /// Number of lower bounds.
        lower: usize,
        /// Number of upper bounds.
        upper: usize,
    },
    /// A bound is not finite or `lower > upper` in some dimension.
    #[error("invalid box in dimension {dim}: [{lower}, {upper}]")]
    InvalidBox {
        /// Dimension index.
        dim: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// The lattice has a number of points per dimension that does not match the box, or a
    /// zero count.
    #[error(
        "lattice needs one non-zero point count per dimension ({dim} dimensions), got {got:?}"
    )]
    LatticeShape {
        /// Input dimension.
        dim: usize,
        /// The point counts received.
        got: Vec<usize>,
    },
    /// The placement produces more nodes than the capacity.
    #[error("placement produces {nodes} nodes, capacity is {capacity}")]
    TooManyNodes {
        /// Nodes requested (saturated at `usize::MAX` on overflow).
        nodes: usize,
        /// Capacity.
        capacity: usize,
    },
    /// An explicit centre has the wrong dimension or is not finite.
    #[error(
        "explicit centre {index} is invalid (dimension {got}, expected {expected}, or not finite)"
    )]
    InvalidCentre {
        /// Index in the list.
        index: usize,
        /// Its length.
        got: usize,
        /// The box dimension.
        expected: usize,
    },
    /// Zero outputs or zero capacity.
    #[error("outputs and capacity must be positive (outputs {outputs}, capacity {capacity})")]
    EmptyShape {
        /// Output count n.
        outputs: usize,
        /// Capacity L_max.
        capacity: usize,
    },
    /// Width not finite and positive (or `1/eta^2` overflows).
    #[error("invalid width {0}")]
    InvalidWidth(f64),
    /// Gamma or sigma negative or not finite.
    #[error("invalid {name} = {value}")]
    InvalidGain {
        /// "gamma" or "sigma".
        name: &'static str,
        /// The value.
        value: f64,
    },
    /// Relevance window of zero steps, `max_neighbours` of zero, or a `min_activation`
    /// outside `[0, 1)`.
    #[error("invalid option {name}")]
    InvalidOption {
        /// Name of the option.
        name: &'static str,
    },
    /// Invalid growth parameters.
    #[error("invalid growth parameters: {0}")]
    InvalidGrowth(&'static str),
}
