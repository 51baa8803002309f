//! Configuration of the broad network fit (docs/method.md sections 5 and 7).

use super::error::BroadError;
use super::limits::Budget;
use serde::{Deserialize, Serialize};

/// Friction-shaped extra inputs, appended to the linear part of the pattern row
/// (docs/method.md section 7).
///
/// For every chosen input column `c` (the joint velocities q') and every scale `v_k`
/// the pattern row gets `tanh(x_c / v_k)`, computed on the **raw** (unstandardised)
/// value, so `v_k` is in the column's physical unit (rad/s).
///
/// Why: the plant's Coulomb friction `Fc tanh(q' / v_s)` (docs/method.md section 1) is nearly a
/// step at q' = 0 (v_s about 0.01 rad/s). Gaussian enhancement nodes on the standardised
/// [q, q', q''] are smooth on the scale of their widths (about one standard deviation of
/// q'), so they round the step off, and the observer reached only NRMSE ~0.47 on the
/// quick simulation of docs/method.md section 7. With a few `tanh(q'/v)` columns the ridge fit
/// represents the step (any mix of the scales) linearly, which brought it to ~0.14.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionFeatures {
    /// Input columns (0-based) that get the features, e.g. `n..2n` for X = [q, q', q''].
    pub columns: Vec<usize>,
    /// Scales `v_k` (> 0, finite), in the unit of those columns.
    pub scales: Vec<f64>,
}

/// Gaussian nodes of an observer's network unless told otherwise (the paper's 1000): the
/// one default of the CLI, the scenarios, Python and the co-simulation.
pub const DEFAULT_NODES: usize = 1000;

/// Scales `v` (rad/s) of the friction-shaped inputs `tanh(qdot / v)` unless told otherwise.
pub const DEFAULT_FRICTION_SCALES: [f64; 3] = [0.01, 0.05, 0.2];

impl FrictionFeatures {
    /// The friction-shaped inputs of an observer's network for `n_joints` joints: on the
    /// velocity block of X = [q, q', q''] when `enabled`, with `scales` (default
    /// [`DEFAULT_FRICTION_SCALES`]); none otherwise. The one rule of every front end.
    pub fn for_observer(n_joints: usize, enabled: bool, scales: Option<Vec<f64>>) -> Self {
        if !enabled {
            return Self::none();
        }
        Self {
            columns: (n_joints..2 * n_joints).collect(),
            scales: scales.unwrap_or_else(|| DEFAULT_FRICTION_SCALES.to_vec()),
        }
    }

    /// No friction features.
    pub fn none() -> Self {
        Self {
            columns: Vec::new(),
            scales: Vec::new(),
        }
    }

    /// Features on the velocity block of X = [q, q', q''] for `n_joints` joints
    /// (columns `n..2n`) with the [`DEFAULT_FRICTION_SCALES`].
    pub fn joint_velocities(n_joints: usize) -> Self {
        Self::for_observer(n_joints, true, None)
    }

    /// Number of extra pattern columns: `columns.len() * scales.len()`.
    pub fn count(&self) -> usize {
        self.columns.len() * self.scales.len()
    }

    pub(crate) fn validate(&self, d_in: usize) -> Result<(), BroadError> {
        if let Some(&c) = self.columns.iter().find(|&&c| c >= d_in) {
            return Err(BroadError::Config(format!(
                "friction feature column {c} is outside the {d_in} input columns"
            )));
        }
        if let Some(&v) = self.scales.iter().find(|&&v| !(v.is_finite() && v > 0.0)) {
            return Err(BroadError::Config(format!(
                "friction feature scale {v} must be finite and > 0"
            )));
        }
        if !self.columns.is_empty() && self.scales.is_empty() {
            return Err(BroadError::Config(
                "friction feature columns given but no scales".into(),
            ));
        }
        Ok(())
    }
}

/// Rule that sets the width `eta_j` of each enhancement node `exp(-||X - u_j||^2 / eta_j^2)`
/// (docs/method.md section 5: widths from a rule based on distances). Distances are in the
/// standardised input space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum WidthRule {
    /// `eta_j = scale * (mean distance from u_j to its k nearest other centres)`.
    /// Adapts to the local density of the centres: nodes in sparse regions of the data
    /// get wide Gaussians, nodes in dense regions narrow ones, so neighbouring
    /// Gaussians overlap everywhere by about the same amount. A width that comes out 0
    /// (duplicate centres) is replaced by the median of the non-zero widths. Default
    /// k = 8, scale = 2 (see the module documentation for how it was chosen).
    Knn {
        /// Number of neighbours (clamped to L - 1).
        k: usize,
        /// Multiplier.
        scale: f64,
    },
    /// `eta_j = scale * median over centres of the nearest-neighbour distance` (one global width).
    GlobalMedian {
        /// Multiplier.
        scale: f64,
    },
    /// The same width for all nodes.
    Fixed(f64),
}

/// How the per-block Gram update `G += A_b^T A_b` is parallelised over the cores.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum GramStrategy {
    /// Each worker thread owns a private Gram matrix and processes its own share of the
    /// row blocks (features and a sequential symmetric rank-k update of the lower
    /// triangle); the private matrices are summed at the end. No synchronisation.
    PerThread,
    /// Features of a block are formed by all threads, then one symmetric rank-k update
    /// parallelised inside faer's GEMM (rayon).
    SharedGemm,
}

/// Configuration of [`fit`](super::fit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BroadConfig {
    /// Number of enhancement (Gaussian) nodes L. The paper uses 1000.
    pub nodes: usize,
    /// Friction-shaped extra inputs (docs/method.md section 7).
    pub friction: FrictionFeatures,
    /// Size of the random subsample of training rows that k-means++ seeding draws the
    /// centres from (clamped to N). Default 20,000 (20 candidates per node at L = 1000).
    pub centre_subsample: usize,
    /// Seed of the ChaCha8 generator used for the subsample and the seeding.
    pub seed: u64,
    /// Width heuristic.
    pub widths: WidthRule,
    /// Candidate ridge parameters, relative: the absolute lambda is `lambda_rel * N`
    /// (N training rows), i.e. the fit minimises `(1/N)||A W - Y||^2 + lambda_rel ||W'||^2`
    /// where W' is W without the bias row. Several values need a validation set.
    pub lambda_grid: Vec<f64>,
    /// Contiguous stretches K of the blocked cross-validation that chooses lambda when no
    /// validation set is given (default 5; see `cv.rs`); 0: no cross-validation, a grid
    /// of several values then needs a validation set.
    #[serde(default = "default_cv_folds")]
    pub cv_folds: usize,
    /// Set to zero every output whose error on motion the fit did not see (the validation
    /// set, or the cross-validation's pooled error) is not at least
    /// [`REQUIRED_GAIN`](super::REQUIRED_GAIN) (2 %) below the error of predicting zero. For
    /// a residual on a nominal model (the hybrid's network) zero is the nominal model
    /// itself: a joint where the network does not pay on unseen motion keeps the model
    /// alone. Off by default (the paper's network has no such fallback).
    #[serde(default)]
    pub zero_unhelpful_outputs: bool,
    /// Set every output to zero: the caller has no recording of other motion to judge the
    /// outputs on (blocked cross-validation over one recording, or its tail, holds motion
    /// the fit has seen: issue 30). For a residual on a nominal model the network then
    /// adds nothing and the nominal model stands alone. Off by default.
    #[serde(default)]
    pub zero_all_outputs: bool,
    /// Rows per block when accumulating the Gram matrix (never the whole N x P pattern);
    /// capped at 256 on the packed AVX2 path, where larger blocks would leave the cache.
    pub block_rows: usize,
    /// Worker threads (0: all available cores).
    pub threads: usize,
    /// Parallelisation of the Gram update.
    pub gram_strategy: GramStrategy,
    /// Memory and work limits checked before a fit or growth starts
    /// ([`check_budget`](super::check_budget)). Not a setting of the result: it is not
    /// serialised.
    #[serde(skip)]
    pub budget: Budget,
}

impl Default for BroadConfig {
    fn default() -> Self {
        Self {
            nodes: DEFAULT_NODES,
            friction: FrictionFeatures::none(),
            centre_subsample: 20_000,
            seed: 0x5eed_b7ad,
            widths: WidthRule::Knn { k: 8, scale: 2.0 },
            lambda_grid: vec![1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2],
            cv_folds: default_cv_folds(),
            zero_unhelpful_outputs: false,
            zero_all_outputs: false,
            block_rows: 2048,
            threads: 0,
            gram_strategy: GramStrategy::PerThread,
            budget: Budget::default(),
        }
    }
}

fn default_cv_folds() -> usize {
    5
}

impl BroadConfig {
    /// Default configuration for an arm with `n_joints` joints (inputs [q, q', q''],
    /// friction features on the velocities).
    pub fn for_arm(n_joints: usize) -> Self {
        Self {
            friction: FrictionFeatures::joint_velocities(n_joints),
            ..Self::default()
        }
    }

    pub(crate) fn validate(&self, d_in: usize) -> Result<(), BroadError> {
        self.friction.validate(d_in)?;
        if self.nodes == 0 {
            return Err(BroadError::Config(
                "nodes must be a positive integer (Gaussian enhancement nodes)".into(),
            ));
        }
        if self.block_rows == 0 {
            return Err(BroadError::Config("block_rows must be > 0".into()));
        }
        if self.cv_folds == 1 {
            return Err(BroadError::Config(
                "cv_folds must be 0 (none) or at least 2".into(),
            ));
        }
        if self.lambda_grid.is_empty() {
            return Err(BroadError::Config("lambda_grid is empty".into()));
        }
        if let Some(&l) = self
            .lambda_grid
            .iter()
            .find(|&&l| !(l.is_finite() && l > 0.0))
        {
            return Err(BroadError::Config(format!(
                "lambda {l} must be finite and > 0"
            )));
        }
        match self.widths {
            WidthRule::Knn { k, scale } => {
                if k == 0 || !(scale.is_finite() && scale > 0.0) {
                    return Err(BroadError::Config(format!(
                        "Knn width rule needs k > 0 and scale > 0, got k = {k}, scale = {scale}"
                    )));
                }
            }
            WidthRule::GlobalMedian { scale } => {
                if !(scale.is_finite() && scale > 0.0) {
                    return Err(BroadError::Config(format!(
                        "width scale {scale} must be > 0"
                    )));
                }
            }
            WidthRule::Fixed(w) => {
                if !(w.is_finite() && w > 0.0) {
                    return Err(BroadError::Config(format!("fixed width {w} must be > 0")));
                }
            }
        }
        Ok(())
    }

    pub(crate) fn thread_count(&self) -> usize {
        if self.threads > 0 {
            self.threads
        } else {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        }
    }
}
