//! Blocked cross-validation of the ridge parameter (issue #22, "honest validation"):
//! without a separate validation recording, lambda is chosen by K contiguous stretches of
//! the training rows, each scored by a fit on the other K - 1 stretches, never by the
//! tail of the same motion.
//!
//! The Gram terms are additive over rows: one blocked pass per stretch gives
//! `G_k = A_k^T A_k`, `A_k^T Y_k` and the target sums; the total is their sum. For every
//! candidate lambda and every stretch k the fit on the others solves
//! `(G - G_k + lambda_k D) W_k = A^T Y - A_k^T Y_k` (`lambda_k = lambda_rel (N - N_k)`)
//! and its error on stretch k comes from the stretch's own Gram terms (as
//! `solve.rs`'s `sse_from_gram`),
//! `||Y_k - A_k W_k||^2 = Y_k^T Y_k - 2 W_k^T A_k^T Y_k + W_k^T G_k W_k`, without a second
//! pass over the data. Cost: K passes that together equal one, and K factorisations per
//! candidate.

use super::config::GramStrategy;
use super::data::Dataset;
use super::error::BroadError;
use super::features::FeatureMap;
use super::gram::{accumulate_gram, GramAcc};
use super::model::nrmse;
use super::solve::{factor, solve};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// The contiguous stretches `[start, end)` of `n` rows cut into `folds` nearly equal
/// parts (the first `n % folds` one row longer).
pub(crate) fn fold_bounds(n: usize, folds: usize) -> Vec<(usize, usize)> {
    let (base, extra) = (n / folds, n % folds);
    let mut start = 0;
    (0..folds)
        .map(|k| {
            let end = start + base + usize::from(k < extra);
            let b = (start, end);
            start = end;
            b
        })
        .collect()
}

/// Per-stretch Gram terms and their sum.
pub(crate) struct FoldGrams {
    /// One accumulation per stretch, in row order.
    pub folds: Vec<GramAcc>,
    /// Rows per stretch.
    pub rows: Vec<usize>,
    /// The sum over the stretches: the Gram terms of all rows.
    pub total: GramAcc,
}

/// Adds `b` to `a` (lower triangle of G, A^T Y, target sums).
fn add_into(a: &mut GramAcc, b: &GramAcc, sign: f64) {
    let p = a.g.nrows();
    for j in 0..p {
        for i in j..p {
            a.g[(i, j)] += sign * b.g[(i, j)];
        }
    }
    for j in 0..a.aty.ncols() {
        for i in 0..p {
            a.aty[(i, j)] += sign * b.aty[(i, j)];
        }
    }
    for (x, y) in a.y_sum.iter_mut().zip(&b.y_sum) {
        *x += sign * y;
    }
    for (x, y) in a.y_sq.iter_mut().zip(&b.y_sq) {
        *x += sign * y;
    }
}

/// Checks that `n` rows make `folds` stretches of at least 2 rows each.
pub(crate) fn check_folds(n: usize, folds: usize) -> Result<(), BroadError> {
    if folds < 2 || n < 2 * folds {
        return Err(BroadError::Config(format!(
            "blocked cross-validation needs at least 2 folds of 2 rows each: \
             {folds} folds of {n} rows"
        )));
    }
    Ok(())
}

/// One blocked Gram pass per stretch, and their sum.
pub(crate) fn accumulate_folds(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    folds: usize,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
) -> FoldGrams {
    let bounds = fold_bounds(data.n_samples(), folds);
    let parts: Vec<GramAcc> = bounds
        .iter()
        .map(|&(s, e)| accumulate_gram(fm, &data.slice(s, e), block_rows, threads, strategy))
        .collect();
    let mut total = parts[0].clone();
    for part in &parts[1..] {
        add_into(&mut total, part, 1.0);
    }
    FoldGrams {
        folds: parts,
        rows: bounds.iter().map(|(s, e)| e - s).collect(),
        total,
    }
}

/// Per-output cross-validated NRMSE of every relative lambda in `grid`: the stretches'
/// squared errors summed, over all N rows, divided by the standard deviation of all the
/// training targets (RMSE where it is 0). `None` for a candidate whose system was not
/// positive definite on some stretch.
pub(crate) fn cross_validate(
    fg: &FoldGrams,
    grid: &[f64],
    bias: usize,
    par: Par,
) -> Vec<Option<Vec<f64>>> {
    let d_out = fg.total.aty.ncols();
    let n: usize = fg.rows.iter().sum();
    let mut sse: Vec<Option<Vec<f64>>> = vec![Some(vec![0.0; d_out]); grid.len()];
    for (fold, &rows) in fg.folds.iter().zip(&fg.rows) {
        let mut rest = fg.total.clone();
        add_into(&mut rest, fold, -1.0);
        let g_full = symmetric(fold.g.as_ref());
        for (c, &rel) in grid.iter().enumerate() {
            let Some(sum) = sse[c].as_mut() else {
                continue;
            };
            let Some(l) = factor(rest.g.as_ref(), rel * (n - rows) as f64, bias, par) else {
                sse[c] = None;
                continue;
            };
            let w: Mat<f64> = solve(l.as_ref(), rest.aty.as_ref(), par);
            let e = held_out_sse(&g_full, fold, w.as_ref(), par);
            sum.iter_mut().zip(&e).for_each(|(s, v)| *s += v);
        }
    }
    let std = acc_std(&fg.total, n);
    sse.into_iter()
        .map(|s| s.map(|s| nrmse(&s, n, &std)))
        .collect()
}

/// The symmetric matrix whose lower triangle is `lower`'s.
fn symmetric(lower: MatRef<'_, f64>) -> Mat<f64> {
    Mat::from_fn(lower.nrows(), lower.ncols(), |i, j| {
        lower[(i.max(j), i.min(j))]
    })
}

/// Per-output squared error of the weights `w` on a stretch from its Gram terms,
/// `y^T y - 2 w^T A^T y + w^T G w` (`g_full`: the stretch's G, both triangles), as
/// [`sse_from_gram`] but with one matrix product for `G W`.
fn held_out_sse(g_full: &Mat<f64>, fold: &GramAcc, w: MatRef<'_, f64>, par: Par) -> Vec<f64> {
    let mut gw = Mat::<f64>::zeros(w.nrows(), w.ncols());
    matmul(gw.as_mut(), Accum::Replace, g_full.as_ref(), w, 1.0, par);
    (0..w.ncols())
        .map(|o| {
            let (mut wgw, mut way) = (0.0, 0.0);
            for j in 0..w.nrows() {
                wgw += w[(j, o)] * gw[(j, o)];
                way += w[(j, o)] * fold.aty[(j, o)];
            }
            (fold.y_sq[o] - 2.0 * way + wgw).max(0.0)
        })
        .collect()
}

/// Standard deviation of each target from the accumulated sums.
pub(crate) fn acc_std(acc: &GramAcc, n: usize) -> Vec<f64> {
    let n = n as f64;
    acc.y_sum
        .iter()
        .zip(&acc.y_sq)
        .map(|(&s, &q)| {
            let m = s / n;
            (q / n - m * m).max(0.0).sqrt()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::broad::config::FrictionFeatures;
    use crate::broad::data::Standardiser;
    use crate::broad::features::NodeSet;

    #[test]
    fn fold_bounds_cover_the_rows_in_order() {
        assert_eq!(fold_bounds(7, 3), vec![(0, 3), (3, 5), (5, 7)]);
        assert_eq!(fold_bounds(10, 5).last(), Some(&(8, 10)));
        assert!(check_folds(9, 5).is_err());
        assert!(check_folds(10, 5).is_ok());
        assert!(check_folds(10, 1).is_err());
    }

    /// Each stretch is scored by a fit that never saw it: the cross-validated NRMSE
    /// equals fits on the other rows (their own Gram pass) predicting the stretch.
    #[test]
    fn each_stretch_is_scored_by_a_fit_on_the_others() {
        let n = 600;
        let vals = crate::broad::kernels::test_values(n * 5, 7);
        let (x, y) = vals.split_at(n * 3);
        let data = Dataset::new(x, y, 3, 2).unwrap();
        let nodes = NodeSet {
            dim: 3,
            centres: crate::broad::kernels::test_values(3 * 30, 8),
            widths: vec![0.5; 30],
        };
        let fm = FeatureMap::new(
            Standardiser::from_data(&data),
            FrictionFeatures::none(),
            nodes,
        );
        let grid = [1e-8, 1e-4, 1e-1];
        let bias = fm.bias_index();
        let fg = accumulate_folds(&fm, &data, 4, 64, 1, GramStrategy::PerThread);
        let got = cross_validate(&fg, &grid, bias, Par::Seq);
        for (c, &rel) in grid.iter().enumerate() {
            let mut sse = [0.0; 2];
            for (s, e) in fold_bounds(n, 4) {
                let xr: Vec<f64> = [&x[..3 * s], &x[3 * e..]].concat();
                let yr: Vec<f64> = [&y[..2 * s], &y[2 * e..]].concat();
                let rest = Dataset::new(&xr, &yr, 3, 2).unwrap();
                let acc = accumulate_gram(&fm, &rest, 64, 1, GramStrategy::PerThread);
                let lambda = rel * rest.n_samples() as f64;
                let l = factor(acc.g.as_ref(), lambda, bias, Par::Seq).unwrap();
                let w = solve(l.as_ref(), acc.aty.as_ref(), Par::Seq);
                let part = crate::broad::gram::prediction_sse(
                    &fm,
                    &data.slice(s, e),
                    w.as_ref(),
                    64,
                    1,
                    GramStrategy::PerThread,
                );
                sse[0] += part[0];
                sse[1] += part[1];
            }
            let expect = nrmse(&sse, n, &acc_std(&fg.total, n));
            let got = got[c].as_ref().unwrap();
            for o in 0..2 {
                assert!(
                    (got[o] - expect[o]).abs() <= 1e-7 * expect[o],
                    "lambda {rel}, output {o}: {} vs {}",
                    got[o],
                    expect[o]
                );
            }
        }
    }

    /// The per-stretch Gram terms sum to the Gram terms of one pass over all rows.
    #[test]
    fn stretch_grams_sum_to_the_full_gram() {
        let n = 1003;
        let vals = crate::broad::kernels::test_values(n * 5, 3);
        let (x, y) = vals.split_at(n * 3);
        let data = Dataset::new(x, y, 3, 2).unwrap();
        let nodes = NodeSet {
            dim: 3,
            centres: crate::broad::kernels::test_values(3 * 20, 4),
            widths: vec![0.7; 20],
        };
        let fm = FeatureMap::new(
            Standardiser::from_data(&data),
            FrictionFeatures::none(),
            nodes,
        );
        for threads in [1, 2] {
            let full = accumulate_gram(&fm, &data, 256, threads, GramStrategy::PerThread);
            let fg = accumulate_folds(&fm, &data, 5, 256, threads, GramStrategy::PerThread);
            assert_eq!(fg.rows.iter().sum::<usize>(), n);
            let p = fm.width();
            for j in 0..p {
                for i in j..p {
                    let (a, b) = (fg.total.g[(i, j)], full.g[(i, j)]);
                    assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "G({i},{j})");
                }
                for o in 0..2 {
                    let (a, b) = (fg.total.aty[(j, o)], full.aty[(j, o)]);
                    assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "A^T Y({j},{o})");
                }
            }
            for o in 0..2 {
                assert!((fg.total.y_sq[o] - full.y_sq[o]).abs() <= 1e-12 * full.y_sq[o]);
                assert!((fg.total.y_sum[o] - full.y_sum[o]).abs() <= 1e-9);
            }
        }
    }
}
