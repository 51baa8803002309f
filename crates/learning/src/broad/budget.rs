//! Memory and work of a fit or a growth, estimated before any work starts and checked
//! against documented, overridable limits ([`Budget`]), so that a request that cannot fit
//! is refused with the figure it would need instead of aborting in an allocation or
//! running for hours.
//!
//! The estimates follow the code's own arrays (module documentation of `broad`): with
//! P = d_in + F + 1 + L pattern columns, Q = P + d_out, N training and V validation rows,
//! T worker threads and G candidate ridge parameters,
//!
//! * memory: the data arrays, `(N + V) (d_in + d_out)` values (the caller holds them), plus
//!   the largest of the phases: the per-thread Gram matrices `T Q^2`, their sum with the
//!   extracted Gram `Q^2 + P^2`, and the Gram with its Cholesky factor and the file image
//!   while saving, `3 P^2` values (growth: `4 P'^2` with the grown width P'); plus the
//!   centres and the subsample. 8 bytes per value. Byte counts use `checked_mul`: a count
//!   that does not fit 64 bits is refused as such.
//! * work (floating-point operations): k-means++ seeding `3 L m d_in` (m: subsample rows),
//!   widths `3 L^2 d_in`, features `N L (2 d_in + 20)`, the Gram `N Q^2`, one Cholesky
//!   factorisation `P^3 / 3` per candidate plus one, the validation pass
//!   `V P (2 d_in + 20 + 2 G d_out)`.

use super::config::BroadConfig;
use super::error::BroadError;
use super::limits::{format_bytes, Budget};
use super::model::BroadModel;
use serde::{Deserialize, Serialize};

/// The size of a fit or a growth, the input of [`check_budget`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FitSize {
    /// Training rows N.
    pub rows: usize,
    /// Validation rows V.
    pub validation_rows: usize,
    /// Input width d_in.
    pub inputs: usize,
    /// Output width d_out.
    pub targets: usize,
    /// Friction feature columns F.
    pub friction_columns: usize,
    /// Enhancement nodes L after the operation.
    pub nodes: usize,
    /// For a growth: the nodes added (the model had `nodes - added`); 0 for a fit.
    pub added: usize,
    /// Rows of the centre subsample (clamped to N).
    pub centre_subsample: usize,
    /// Candidate ridge parameters G.
    pub lambdas: usize,
    /// Stretches K of the blocked cross-validation (0 without: a validation set or a
    /// single lambda); K Gram matrices are held and K factorisations made per candidate.
    pub folds: usize,
    /// Worker threads T.
    pub threads: usize,
}

impl FitSize {
    /// The size of [`fit`](super::fit) with `config` on `rows` training and
    /// `validation_rows` validation rows of `inputs` inputs and `targets` outputs.
    pub fn fit(
        rows: usize,
        validation_rows: usize,
        inputs: usize,
        targets: usize,
        config: &BroadConfig,
    ) -> Self {
        Self {
            rows,
            validation_rows,
            inputs,
            targets,
            friction_columns: config.friction.count(),
            nodes: config.nodes,
            added: 0,
            centre_subsample: config.centre_subsample,
            lambdas: config.lambda_grid.len(),
            folds: if validation_rows == 0 && config.lambda_grid.len() > 1 {
                config.cv_folds
            } else {
                0
            },
            threads: config.thread_count(),
        }
    }

    /// The size of growing `model` by `added` nodes on `rows` training and
    /// `validation_rows` evaluation rows ([`BroadModel::grow`]).
    pub fn growth(
        model: &BroadModel,
        rows: usize,
        validation_rows: usize,
        added: usize,
        config: &BroadConfig,
    ) -> Self {
        Self {
            rows,
            validation_rows,
            inputs: model.d_in(),
            targets: model.d_out(),
            friction_columns: model.friction().count(),
            nodes: model.n_nodes().saturating_add(added),
            added,
            centre_subsample: config.centre_subsample,
            lambdas: 1,
            folds: 0,
            threads: config.thread_count(),
        }
    }
}

/// What [`check_budget`] estimated.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Pattern width P (after the operation).
    pub pattern_width: usize,
    /// Estimated peak memory, bytes (data arrays included).
    pub memory_bytes: u64,
    /// Estimated work, floating-point operations.
    pub flop: f64,
}

impl std::fmt::Display for Estimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "about {} of memory and {:.1e} floating-point operations",
            format_bytes(Some(self.memory_bytes)),
            self.flop
        )
    }
}

/// Checked arithmetic on value counts; `None` when a count overflows 64 bits.
fn memory_values(s: &FitSize, p: u64) -> Option<u64> {
    let u = |v: usize| v as u64;
    let q = p.checked_add(u(s.targets))?;
    let p2 = p.checked_mul(p)?;
    let q2 = q.checked_mul(q)?;
    let rows = u(s.rows).checked_add(u(s.validation_rows))?;
    let data = rows.checked_mul(u(s.inputs).checked_add(u(s.targets))?)?;
    let per_thread = u(s.threads.max(1)).checked_mul(q2)?;
    let summed = q2.checked_add(p2)?;
    // Held P x P matrices: Gram, factor and solve copies; the stretches' Grams and the
    // Gram without one stretch under cross-validation.
    let held = if s.added > 0 { 4 } else { 3u64 }
        .checked_add(u(s.folds).checked_add(u(s.folds.min(1)))?)?
        .checked_mul(p2)?;
    let gram_phase = per_thread.max(summed).max(held);
    let m = u(s.centre_subsample.min(s.rows));
    let centres = m
        .checked_add(u(s.nodes).checked_mul(2)?)?
        .checked_mul(u(s.inputs))?;
    let solutions = u(s.lambdas).checked_mul(p)?.checked_mul(u(s.targets))?;
    data.checked_add(gram_phase)?
        .checked_add(centres)?
        .checked_add(solutions)
}

fn work_flop(s: &FitSize, p: f64) -> f64 {
    let f = |v: usize| v as f64;
    let (n, v, d, o) = (f(s.rows), f(s.validation_rows), f(s.inputs), f(s.targets));
    let l = f(s.nodes);
    let q = p + o;
    let m = f(s.centre_subsample.min(s.rows));
    let feature = 2.0 * d + 20.0;
    if s.added == 0 {
        let centres = 3.0 * l * m * d + 3.0 * l * l * d;
        let gram = n * (l * feature + q * q);
        let solves = f(s.lambdas) * f(s.folds.max(1)) + 1.0;
        let solve = solves * p * p * p / 3.0;
        let validation = v * p * (feature + 2.0 * f(s.lambdas) * o);
        centres + gram + solve + validation
    } else {
        let k = f(s.added);
        let p_old = p - k;
        let centres = 3.0 * l * m * d + 3.0 * k * l * d;
        // Loading the file refactors the old Gram; the pass recomputes every feature but
        // multiplies only the k new rows; the factor is extended by a k-row block.
        let load = p_old * p_old * p_old / 3.0;
        let cross = n * (l * feature + 2.0 * q * k);
        let extend = p_old * p_old * k + k * k * k / 3.0 + 2.0 * p * p * o;
        let evaluate = v * p * (feature + 2.0 * o);
        centres + load + cross + extend + evaluate
    }
}

/// Estimates the peak memory and the work of a fit or growth of `size` and refuses it
/// when it cannot be done:
///
/// * no rows, or more enhancement nodes than training rows
///   ([`BroadError::TooManyNodes`]: the centres are drawn from the training rows, and the
///   system would be underdetermined);
/// * a pattern width or a byte count that does not fit 64 bits, or an estimated memory
///   above `budget.max_memory_bytes` ([`BroadError::MemoryBudget`]);
/// * estimated work above `budget.max_flop` ([`BroadError::WorkBudget`]).
///
/// Cheap (no allocation proportional to the problem): call it before loading or
/// simulating anything large. [`fit`](super::fit) and [`BroadModel::grow`] call it with
/// `config.budget`.
pub fn check_budget(size: &FitSize, budget: &Budget) -> Result<Estimate, BroadError> {
    if size.rows == 0 {
        return Err(BroadError::Empty {
            what: "training data",
        });
    }
    if size.nodes > size.rows {
        return Err(BroadError::TooManyNodes {
            nodes: size.nodes,
            rows: size.rows,
        });
    }
    let p = (size.inputs as u64)
        .checked_add(size.friction_columns as u64)
        .and_then(|v| v.checked_add(1))
        .and_then(|v| v.checked_add(size.nodes as u64));
    let values = p.and_then(|p| memory_values(size, p));
    let bytes = values.and_then(|v| v.checked_mul(8));
    let (Some(p), Some(bytes)) = (p, bytes) else {
        return Err(BroadError::MemoryBudget {
            needed_bytes: None,
            limit_bytes: budget.max_memory_bytes,
            nodes: size.nodes,
        });
    };
    if bytes > budget.max_memory_bytes {
        return Err(BroadError::MemoryBudget {
            needed_bytes: Some(bytes),
            limit_bytes: budget.max_memory_bytes,
            nodes: size.nodes,
        });
    }
    let flop = work_flop(size, p as f64);
    if flop.is_nan() || flop > budget.max_flop {
        return Err(BroadError::WorkBudget {
            needed_flop: flop,
            limit_flop: budget.max_flop,
        });
    }
    Ok(Estimate {
        pattern_width: p as usize,
        memory_bytes: bytes,
        flop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn size(rows: usize, nodes: usize) -> FitSize {
        FitSize::fit(rows, rows / 4, 21, 7, &BroadConfig::for_arm(7)).with_nodes_for_test(nodes)
    }

    impl FitSize {
        fn with_nodes_for_test(mut self, nodes: usize) -> Self {
            self.nodes = nodes;
            self.threads = 2;
            self
        }
    }

    #[test]
    fn the_issue_cases_are_refused_with_the_figure() {
        let budget = Budget::default();
        // `--nodes 1000000000` on 8000 rows: more nodes than rows.
        match check_budget(&size(8000, 1_000_000_000), &budget) {
            Err(BroadError::TooManyNodes {
                nodes: 1_000_000_000,
                rows: 8000,
            }) => {}
            other => panic!("{other:?}"),
        }
        // 10^8 nodes on enough rows: 2.4e17 bytes for the Gram and its factor.
        match check_budget(&size(200_000_000, 100_000_000), &budget) {
            Err(
                e @ BroadError::MemoryBudget {
                    needed_bytes: Some(b),
                    ..
                },
            ) => {
                assert!(b > 3 * 8 * 100_000_000u64 * 100_000_000, "{b}");
                assert!(e.to_string().contains("GB"), "{e}");
            }
            other => panic!("{other:?}"),
        }
        // 2^32 nodes (a scenario's `nodes = 4294967296`): the byte count overflows.
        let huge = 1usize << 32;
        match check_budget(&size(usize::MAX / 2, huge), &budget) {
            Err(
                e @ BroadError::MemoryBudget {
                    needed_bytes: None, ..
                },
            ) => assert!(e.to_string().contains("overflows"), "{e}"),
            other => panic!("{other:?}"),
        }
        // Nothing overflows even at the extremes.
        for nodes in [0, 1, usize::MAX / 2, usize::MAX] {
            let _ = check_budget(&size(usize::MAX, nodes), &budget);
        }
        // `--nodes 200000` on 8000 rows.
        assert!(matches!(
            check_budget(&size(8000, 200_000), &budget),
            Err(BroadError::TooManyNodes { .. })
        ));
    }

    #[test]
    fn the_paper_fit_is_within_the_default_budget() {
        let e = check_budget(&size(450_000, 1000), &Budget::default()).unwrap();
        assert_eq!(e.pattern_width, 21 + 21 + 1 + 1000);
        // Data 450,000 x 1.25 x 28 values and about 3 P^2 values.
        assert!(
            e.memory_bytes > 100_000_000 && e.memory_bytes < 200_000_000,
            "{e:?}"
        );
        assert!(e.flop > 4e11 && e.flop < 8e11, "{e:?}");
        // A work limit below it refuses it.
        let tight = Budget {
            max_flop: 1e11,
            ..Budget::default()
        };
        assert!(matches!(
            check_budget(&size(450_000, 1000), &tight),
            Err(BroadError::WorkBudget { .. })
        ));
        assert!(matches!(
            check_budget(&size(0, 0), &Budget::unlimited()),
            Err(BroadError::Empty { .. })
        ));
    }

    #[test]
    fn bytes_are_formatted_readably() {
        assert_eq!(format_bytes(Some(168_000_000_000)), "168.0 GB");
        assert_eq!(format_bytes(Some(9_400_000)), "9 MB");
        assert!(format_bytes(None).contains("overflows"));
    }
}
