//! Incremental growth of a fitted network by k enhancement nodes without retraining
//! (docs/method.md section 5, eq. 14-16 in their exact ridge form).

use super::budget::{check_budget, FitSize};
use super::centres::{compute_widths, kmeanspp, rng_from_seed, subsample_standardised};
use super::config::BroadConfig;
use super::coverage::threshold_of_maxima;
use super::data::{Dataset, Standardiser};
use super::error::BroadError;
use super::features::{FeatureMap, NodeSet};
use super::gram::{accumulate_new_rows, NewRows};
use super::model::{check_finite_result, par_for, train_nrmse, BroadModel, GrowthState};
use super::provenance::{CentreSettings, GrowthRecord};
use super::solve::{extend_factor, solve};
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What [`BroadModel::grow`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrowthReport {
    /// Nodes added k.
    pub nodes_added: usize,
    /// Nodes after growth.
    pub nodes: usize,
    /// Seconds choosing the new centres and widths.
    pub centres_s: f64,
    /// Seconds for the cross terms (one pass over the data).
    pub cross_terms_s: f64,
    /// Seconds for the Cholesky extension and the new solve.
    pub solve_s: f64,
    /// Everything.
    pub total_s: f64,
    /// Per-output training NRMSE after growth (from the Gram terms).
    pub train_nrmse: Vec<f64>,
}

/// Which nodes [`BroadModel::grow`] adds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum GrowthSpec {
    /// These nodes (centres in standardised units).
    Nodes(NodeSet),
    /// `count` nodes by continuing the k-means++ seeding with the existing centres as
    /// already chosen: new centres land where the data is far from every current centre,
    /// the region docs/method.md section 4 grows into. Drawn from a fresh subsample of
    /// `config.centre_subsample` rows with a ChaCha8 generator seeded by `seed`; widths by
    /// `config.widths` with all centres as neighbours (old widths unchanged).
    KMeansPlusPlus {
        /// Number of nodes k.
        count: usize,
        /// Seed.
        seed: u64,
    },
}

impl BroadModel {
    /// Incremental growth by k enhancement nodes without retraining (docs/method.md section 5,
    /// eq. 14-16 in its exact ridge form): one pass over the training data computes only
    /// the k new rows of the Gram, `A_new^T [A_old | A_new]`, and `A_new^T Y`; the stored
    /// Cholesky factor is extended by the Schur-complement block
    /// (`L21 = G21 L11^-T`, `L22 = chol(G22 + lambda I - L21 L21^T)`) and W re-solved.
    /// The result equals a full retrain on the grown node set with the same lambda
    /// (to rounding). `train` must be the training data of the fit (checked by row count,
    /// input means and target sums). `config` supplies `block_rows`, `threads`,
    /// `gram_strategy`, `centre_subsample` and `widths`.
    pub fn grow(
        &mut self,
        train: &Dataset<'_>,
        spec: &GrowthSpec,
        config: &BroadConfig,
    ) -> Result<GrowthReport, BroadError> {
        let t0 = Instant::now();
        config.validate(self.d_in())?;
        let d = self.d_in();
        if train.d_in() != d {
            return Err(BroadError::Dimension {
                what: "growth data input width",
                expected: d,
                got: train.d_in(),
            });
        }
        if train.d_out() != self.d_out {
            return Err(BroadError::Dimension {
                what: "growth data output width",
                expected: self.d_out,
                got: train.d_out(),
            });
        }
        let state = self.state.as_ref().ok_or(BroadError::NoGrowthState)?;
        self.check_training_data(train, state)?;
        let added = match spec {
            GrowthSpec::Nodes(ns) => ns.len(),
            GrowthSpec::KMeansPlusPlus { count, .. } => *count,
        };
        let size = FitSize::growth(self, train.n_samples(), 0, added, config);
        check_budget(&size, &config.budget)?;
        let threads = config.thread_count();
        let par = par_for(threads);

        let new_nodes = self.new_nodes(train, spec, config)?;
        let k = new_nodes.len();
        let centres_s = t0.elapsed().as_secs_f64();
        if k == 0 {
            let train_e = train_nrmse(
                state,
                MatRef::from_row_major_slice(&self.w, self.pattern_width(), self.d_out),
            );
            return Ok(GrowthReport {
                nodes_added: 0,
                nodes: self.n_nodes(),
                centres_s,
                cross_terms_s: 0.0,
                solve_s: 0.0,
                total_s: t0.elapsed().as_secs_f64(),
                train_nrmse: train_e,
            });
        }
        let mut all_nodes = self.fm.nodes.clone();
        all_nodes.extend(&new_nodes);
        let fm = FeatureMap::new(
            self.fm.standardiser.clone(),
            self.fm.friction.clone(),
            all_nodes,
        );

        let t = Instant::now();
        let with_coverage = self.coverage_threshold.is_some();
        let NewRows {
            rows,
            aty: aty_new,
            maxima: mut row_maxima,
        } = accumulate_new_rows(
            &fm,
            train,
            k,
            config.block_rows,
            threads,
            config.gram_strategy,
            with_coverage,
        );
        let cross_terms_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let p_old = self.pattern_width();
        let p = p_old + k;
        let chol = extend_factor(state.chol.as_ref(), rows.as_ref(), self.lambda, par).ok_or(
            BroadError::NotPositiveDefinite {
                tried: vec![self.lambda],
            },
        )?;
        let mut gram = Mat::<f64>::zeros(p, p);
        gram.as_mut()
            .submatrix_mut(0, 0, p_old, p_old)
            .copy_from(&state.gram);
        gram.as_mut().submatrix_mut(p_old, 0, k, p).copy_from(&rows);
        let mut aty = Mat::<f64>::zeros(p, self.d_out);
        aty.as_mut()
            .submatrix_mut(0, 0, p_old, self.d_out)
            .copy_from(&state.aty);
        aty.as_mut()
            .submatrix_mut(p_old, 0, k, self.d_out)
            .copy_from(&aty_new);
        let w = solve(chol.as_ref(), aty.as_ref(), par);
        let new_state = GrowthState {
            gram,
            aty,
            chol,
            n_samples: state.n_samples,
            y_sum: state.y_sum.clone(),
            y_sq: state.y_sq.clone(),
        };
        let train_e = train_nrmse(&new_state, w.as_ref());
        let solve_s = t.elapsed().as_secs_f64();
        check_finite_result(w.as_ref(), &[], &train_e)?;

        self.provenance.growth.push(GrowthRecord {
            nodes_added: k,
            centres: match spec {
                GrowthSpec::Nodes(_) => None,
                GrowthSpec::KMeansPlusPlus { seed, .. } => Some(CentreSettings {
                    centre_subsample: config.centre_subsample,
                    seed: *seed,
                    widths: config.widths.clone(),
                }),
            },
        });
        self.fm = fm;
        if with_coverage {
            // From the grown pattern rows of the pass above (the retrain's threshold, up to
            // the rounding of the distance product).
            self.coverage_threshold = threshold_of_maxima(&mut row_maxima);
        }
        self.state = Some(new_state);
        self.set_weights(w.as_ref());
        Ok(GrowthReport {
            nodes_added: k,
            nodes: self.n_nodes(),
            centres_s,
            cross_terms_s,
            solve_s,
            total_s: t0.elapsed().as_secs_f64(),
            train_nrmse: train_e,
        })
    }

    fn check_training_data(
        &self,
        train: &Dataset<'_>,
        state: &GrowthState,
    ) -> Result<(), BroadError> {
        if train.n_samples() != state.n_samples {
            return Err(BroadError::GrowthDataMismatch(format!(
                "{} rows, the model was trained on {}",
                train.n_samples(),
                state.n_samples
            )));
        }
        let now = Standardiser::from_data(train);
        for (k, ((a, b), s)) in now
            .mean
            .iter()
            .zip(&self.fm.standardiser.mean)
            .zip(&self.fm.standardiser.std)
            .enumerate()
        {
            if (a - b).abs() > 1e-9 * (s + b.abs()) {
                return Err(BroadError::GrowthDataMismatch(format!(
                    "mean of input column {k} is {a}, training mean was {b}"
                )));
            }
        }
        let d_out = self.d_out;
        let mut y_sum = vec![0.0; d_out];
        for r in train.targets().chunks_exact(d_out) {
            for (s, v) in y_sum.iter_mut().zip(r) {
                *s += v;
            }
        }
        for (o, (a, b)) in y_sum.iter().zip(&state.y_sum).enumerate() {
            let scale = (state.y_sq[o] * state.n_samples as f64).sqrt();
            if (a - b).abs() > 1e-9 * scale.max(1e-300) {
                return Err(BroadError::GrowthDataMismatch(format!(
                    "sum of target column {o} is {a}, training sum was {b}"
                )));
            }
        }
        Ok(())
    }

    /// The nodes a growth adds: the given ones, or k-means++ seeding continued from the
    /// existing centres on a fresh subsample, widths by `config.widths`.
    fn new_nodes(
        &self,
        train: &Dataset<'_>,
        spec: &GrowthSpec,
        config: &BroadConfig,
    ) -> Result<NodeSet, BroadError> {
        let d = self.d_in();
        Ok(match spec {
            GrowthSpec::Nodes(ns) => {
                ns.validate(d)?;
                ns.clone()
            }
            GrowthSpec::KMeansPlusPlus { count, seed } => {
                let mut rng = rng_from_seed(*seed);
                let (pts_t, m) = subsample_standardised(
                    train,
                    &self.fm.standardiser,
                    config.centre_subsample,
                    &mut rng,
                );
                let centres = kmeanspp(&pts_t, m, d, &self.fm.nodes.centres, *count, &mut rng);
                let mut all = self.fm.nodes.centres.clone();
                all.extend_from_slice(&centres);
                let widths = compute_widths(
                    &all,
                    d,
                    self.n_nodes(),
                    &self.fm.nodes.widths,
                    &config.widths,
                );
                NodeSet {
                    dim: d,
                    centres,
                    widths,
                }
            }
        })
    }
}
