//! Flat ("broad") RBF network of the force-sensorless observer (docs/method.md section 5,
//! paper eq. 14-19).
//!
//! The network learns the free-motion torque `tau_free(q, q', q'')` from free-motion data
//! (docs/method.md section 5); in contact, `tau_ext_hat = f_hat(q, q', q'') - tau` (eq. 19).
//! It is generic over the input width d_in (21 for X = [q, q', q''] of a 7-joint arm) and
//! the output width d_out (7).
//!
//! * Pattern row `a(x) = [X_std | friction features | 1 | xi(X)]`, width
//!   P = d_in + F + 1 + L: standardised inputs ([`Standardiser`]), optional
//!   `tanh(q'/v_k)` columns ([`FrictionFeatures`], docs/method.md section 7), a bias, and L
//!   Gaussian enhancement nodes `xi_j(X) = exp(-||X - u_j||^2 / eta_j^2)` ([`NodeSet`]).
//! * Centres by k-means++ seeding on a random subsample, widths by a k-nearest-centre
//!   heuristic ([`WidthRule`]); see *Design decisions* below.
//! * Ridge solution `W = (A^T A + lambda D)^-1 A^T Y` with the bias not regularised (D is
//!   the identity except a 0 for the bias column), from the Gram matrix accumulated in row
//!   blocks (the N x P pattern matrix is never held), Cholesky solve, lambda chosen on a
//!   validation set from a grid without recomputing the Gram ([`fit`]).
//! * Incremental growth by k nodes ([`BroadModel::grow`]): only the new Gram rows are
//!   computed, the Cholesky factor is extended by a Schur-complement block. The paper's
//!   Greville pseudo-inverse form is [`greville_add_columns`] (small problems).
//! * Allocation-free one-sample prediction ([`BroadModel::predict_into`]), and the
//!   coverage of an input by the training data with the prediction faded to zero outside
//!   it ([`BroadModel::coverage`], [`BroadModel::predict_faded_into`], `coverage.rs`).
//! * Versioned, checksummed, atomically written model files ([`BroadModel::save`],
//!   [`BroadModel::load`]) that know the arm they were trained for and every setting that
//!   made them ([`Provenance`], [`BroadModel::check_arm`]), written only to a new name or
//!   over a model file ([`check_model_destination`]).
//! * Fits refused before they start when they cannot fit in memory or time
//!   ([`check_budget`], [`Budget`]) and refused after when their result is not finite.
//!
//! # Design decisions
//!
//! * **Centres**: k-means++ seeding (D^2 sampling) on a uniform random subsample of
//!   `centre_subsample` standardised training rows (default 20,000), ChaCha8 seeded by
//!   `seed`, deterministic, no Lloyd iterations: the seeding spreads the centres over the
//!   whole visited region (corners of the joint box included) while following the data
//!   density; the subsample keeps it at tens of milliseconds (see `centres.rs`).
//! * **Widths**: `eta_j = scale * mean distance from u_j to its k nearest other centres`
//!   (default k = 8, scale = 2), in standardised units: local density adaptive, so that
//!   neighbouring Gaussians overlap about equally everywhere. Scale 2 was the best of
//!   {0.5, 1, 2, 3, 4} on a 3-input test function and on the 21-input synthetic arm data
//!   of `examples/broad_train_timing.rs` (validation NRMSE 0.30 with scale 2 or 4 against
//!   0.34 with scale 1 at N = 450,000, L = 1000).
//! * **Bias**: not regularised (D has a 0 at the bias column): the intercept carries the
//!   mean torque, which has no reason to be small. The paper's `(lambda I + A^T A)^-1`
//!   regularises everything; with an unregularised bias the training residuals have
//!   exactly zero mean. The system stays positive definite for lambda > 0.
//! * **Lambda**: a grid of relative values (`lambda = lambda_rel * N`, default
//!   1e-10 .. 1e-2); one Gram accumulation, one Cholesky solve per candidate, one blocked
//!   pass over the validation set predicting with all candidates at once; the candidate
//!   with the smallest mean (over outputs) validation NRMSE wins. Without a validation
//!   set, blocked cross-validation over `cv_folds` contiguous stretches of the training
//!   rows (default 5, `cv.rs`): each stretch scored by a fit on the others, from
//!   per-stretch Gram terms (never the tail of the same motion, issue #22).
//! * **Gram**: row blocks of `block_rows` rows (default 2048; at most 256 on the packed
//!   path below, so that a block stays in cache); each worker thread forms the block's
//!   pattern (the Gaussian distances by one product, `||x||^2 + ||u||^2 - 2 X U^T`, then
//!   a vectorised exp accurate to 1 ulp, flushed to 0 below 1.7e-154) and adds it to a
//!   private Gram by a symmetric rank-k update of the lower triangle, with the targets
//!   packed as extra rows so that the same update yields `A^T Y`. With AVX2 + FMA the
//!   products run on packed slabs with a register-tiled 8 x 6 kernel (`kernels/syrk.rs`,
//!   about 90 % of the FMA peak on one core); otherwise on faer's triangular matmul. The
//!   private Grams are summed ([`GramStrategy::PerThread`], default;
//!   [`GramStrategy::SharedGemm`] instead parallelises inside one faer GEMM; slower in
//!   every measurement here). The rows are split statically between the threads, so a fit
//!   is bitwise reproducible for a given thread count. Memory: one (P + d_out)^2 Gram and
//!   one P x block pattern per thread (about 9 MB and 2 MB at P = 1043), never the N x P
//!   pattern matrix.

mod budget;
mod centres;
mod config;
mod coverage;
mod cv;
mod data;
mod destination;
mod error;
mod features;
mod fit;
mod gram;
mod greville;
mod growth;
mod io;
mod kernels;
mod limits;
mod model;
mod provenance;
mod repeats;
mod solve;
mod stamp;

pub use budget::{check_budget, Estimate, FitSize};
pub use config::{
    BroadConfig, FrictionFeatures, GramStrategy, WidthRule, DEFAULT_FRICTION_SCALES, DEFAULT_NODES,
};
pub use coverage::COVERAGE_QUANTILE;
pub use data::{Dataset, Standardiser, MAX_ABS_DATA_VALUE};
pub use destination::check_model_destination;
pub use error::BroadError;
pub use features::NodeSet;
pub use fit::{fit, fit_with_nodes, FitReport, LambdaScore, PhaseTimes, REQUIRED_GAIN};
pub use greville::{greville_add_columns, pseudo_inverse, PinvState};
pub use growth::{GrowthReport, GrowthSpec};
pub use io::{fnv1a64, FORMAT_NAME, FORMAT_VERSION};
pub use kernels::exp_nonpositive_slice;
pub use limits::{format_bytes, Budget, DEFAULT_MAX_FLOP, DEFAULT_MAX_MEMORY_BYTES};
pub use model::{BroadModel, Workspace};
pub use provenance::{
    ArmCheck, ArmIdentity, CentreSettings, DataSettings, FitSettings, GrowthRecord, Provenance,
    TrainingTarget, ValidationSplit,
};
pub use repeats::repeat_period;
