//! Blocked passes over a data set: the N x P pattern matrix A is never held whole.
//! Each pass forms the pattern block of `block_rows` rows at a time (column-major P x b,
//! one pattern row per column) and hands it to a consumer: the Gram accumulation
//! `G += A_b^T A_b`, `A^T Y += A_b^T Y_b` (METHOD.md section 5, the normal equations of
//! the ridge solution), the cross terms of a node growth, or validation predictions.

use super::config::GramStrategy;
use super::data::Dataset;
use super::features::FeatureMap;
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::{Accum, Mat, MatRef, Par};

/// One pattern block handed to a consumer.
pub(crate) struct Block<'a> {
    /// Pattern, P x b column-major (A_b^T).
    pub at: MatRef<'a, f64>,
    /// Targets of the block, b x d_out (row-major view).
    pub y: MatRef<'a, f64>,
}

/// Runs `consume` on every block of `data`, with `threads` workers.
///
/// `PerThread`: the rows are cut into `threads` contiguous ranges; each worker forms its
/// blocks and calls `consume` on its own state (from `init`) with `Par::Seq`.
/// `SharedGemm`: one state; every block's features are formed by all workers (columns
/// split between them), then `consume` runs once with `Par::rayon(threads)`.
/// Returns the states (one per worker, or one).
pub(crate) fn for_each_block<S: Send>(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
    init: impl Fn() -> S + Sync,
    consume: impl Fn(&mut S, Block<'_>, Par) + Sync,
) -> Vec<S> {
    let n = data.n_samples();
    let p = fm.width();
    let d_out = data.d_out();
    let threads = threads.max(1);
    let block_rows = block_rows.max(1);
    let run_range = |start: usize, end: usize, state: &mut S| {
        let cap = block_rows.min(end - start);
        let mut at = vec![0.0; p * cap];
        let mut xn = vec![0.0; cap];
        let mut r = start;
        while r < end {
            let b = block_rows.min(end - r);
            fm.fill_block(data.input_rows(r, b), &mut at[..p * b], &mut xn, Par::Seq);
            let block = Block {
                at: MatRef::from_column_major_slice(&at[..p * b], p, b),
                y: MatRef::from_row_major_slice(data.target_rows(r, b), b, d_out),
            };
            consume(state, block, Par::Seq);
            r += b;
        }
    };
    if threads == 1 || n < 2 * block_rows {
        let mut s = init();
        if n > 0 {
            run_range(0, n, &mut s);
        }
        return vec![s];
    }
    match strategy {
        GramStrategy::PerThread => {
            // Contiguous ranges, block-aligned so the blocks are full.
            let n_blocks = n.div_ceil(block_rows);
            let per = n_blocks.div_ceil(threads);
            std::thread::scope(|scope| {
                let handles: Vec<_> = (0..threads)
                    .filter_map(|t| {
                        let start = (t * per * block_rows).min(n);
                        let end = ((t + 1) * per * block_rows).min(n);
                        (start < end).then(|| {
                            let run_range = &run_range;
                            let init = &init;
                            scope.spawn(move || {
                                let mut s = init();
                                run_range(start, end, &mut s);
                                s
                            })
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("broad worker panicked"))
                    .collect()
            })
        }
        GramStrategy::SharedGemm => {
            let mut state = init();
            let mut at = vec![0.0; p * block_rows];
            let mut xn = vec![0.0; block_rows];
            let par = Par::rayon(threads);
            let mut r = 0;
            while r < n {
                let b = block_rows.min(n - r);
                let per = b.div_ceil(threads);
                std::thread::scope(|scope| {
                    let mut at_rest = &mut at[..p * b];
                    let mut xn_rest = &mut xn[..b];
                    let mut s0 = 0;
                    while s0 < b {
                        let bb = per.min(b - s0);
                        let (at_part, at_tail) = std::mem::take(&mut at_rest).split_at_mut(p * bb);
                        let (xn_part, xn_tail) = std::mem::take(&mut xn_rest).split_at_mut(bb);
                        at_rest = at_tail;
                        xn_rest = xn_tail;
                        let rows = data.input_rows(r + s0, bb);
                        scope.spawn(move || fm.fill_block(rows, at_part, xn_part, Par::Seq));
                        s0 += bb;
                    }
                });
                let block = Block {
                    at: MatRef::from_column_major_slice(&at[..p * b], p, b),
                    y: MatRef::from_row_major_slice(data.target_rows(r, b), b, d_out),
                };
                consume(&mut state, block, par);
                r += b;
            }
            vec![state]
        }
    }
}

/// Accumulated normal-equation terms of a data set.
#[derive(Clone, Debug)]
pub(crate) struct GramAcc {
    /// G = A^T A, P x P; only the lower triangle is meaningful.
    pub g: Mat<f64>,
    /// A^T Y, P x d_out.
    pub aty: Mat<f64>,
    /// Column sums of Y.
    pub y_sum: Vec<f64>,
    /// Column sums of Y^2.
    pub y_sq: Vec<f64>,
}

impl GramAcc {
    fn zeros(p: usize, d_out: usize) -> Self {
        Self {
            g: Mat::zeros(p, p),
            aty: Mat::zeros(p, d_out),
            y_sum: vec![0.0; d_out],
            y_sq: vec![0.0; d_out],
        }
    }
    fn add(&mut self, other: &GramAcc) {
        self.g += &other.g;
        self.aty += &other.aty;
        for (a, b) in self.y_sum.iter_mut().zip(&other.y_sum) {
            *a += b;
        }
        for (a, b) in self.y_sq.iter_mut().zip(&other.y_sq) {
            *a += b;
        }
    }
}

fn add_y_stats(y: MatRef<'_, f64>, y_sum: &mut [f64], y_sq: &mut [f64]) {
    for i in 0..y.nrows() {
        for o in 0..y.ncols() {
            let v = y[(i, o)];
            y_sum[o] += v;
            y_sq[o] += v * v;
        }
    }
}

/// G = A^T A (lower triangle, symmetric rank-k updates), A^T Y and the target sums.
pub(crate) fn accumulate_gram(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
) -> GramAcc {
    let p = fm.width();
    let d_out = data.d_out();
    let parts = for_each_block(
        fm,
        data,
        block_rows,
        threads,
        strategy,
        || GramAcc::zeros(p, d_out),
        |acc, block, par| {
            tri_matmul(
                acc.g.as_mut(),
                BlockStructure::TriangularLower,
                Accum::Add,
                block.at,
                BlockStructure::Rectangular,
                block.at.transpose(),
                BlockStructure::Rectangular,
                1.0,
                par,
            );
            matmul(acc.aty.as_mut(), Accum::Add, block.at, block.y, 1.0, par);
            add_y_stats(block.y, &mut acc.y_sum, &mut acc.y_sq);
        },
    );
    let mut it = parts.into_iter();
    let mut total = it.next().unwrap_or_else(|| GramAcc::zeros(p, d_out));
    for part in it {
        total.add(&part);
    }
    total
}

/// Cross terms for `k` new nodes appended at the end of `fm` (pattern width P' = P + k):
/// the last k rows of the grown Gram, `A_new^T [A_old | A_new]` (k x P'), and
/// `A_new^T Y` (k x d_out). The old features are recomputed per block (the pattern matrix
/// is not stored) but only the k new rows of the Gram are multiplied: 2 N P' k flops
/// instead of N P'^2 for a full retrain.
pub(crate) fn accumulate_new_rows(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    k: usize,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
) -> (Mat<f64>, Mat<f64>) {
    let p = fm.width();
    let p_old = p - k;
    let d_out = data.d_out();
    let parts = for_each_block(
        fm,
        data,
        block_rows,
        threads,
        strategy,
        || (Mat::<f64>::zeros(k, p), Mat::<f64>::zeros(k, d_out)),
        |(rows, aty), block, par| {
            let new_t = block.at.subrows(p_old, k);
            matmul(
                rows.as_mut(),
                Accum::Add,
                new_t,
                block.at.transpose(),
                1.0,
                par,
            );
            matmul(aty.as_mut(), Accum::Add, new_t, block.y, 1.0, par);
        },
    );
    let mut it = parts.into_iter();
    let (mut rows, mut aty) = it
        .next()
        .unwrap_or_else(|| (Mat::zeros(k, p), Mat::zeros(k, d_out)));
    for (r, a) in it {
        rows += &r;
        aty += &a;
    }
    (rows, aty)
}

/// Sums of squared prediction errors on `data` for several weight matrices at once:
/// `w_all` is P x (m * d_out) (m candidate weight matrices side by side); returns
/// `sse[c * d_out + o]` for candidate c and output o.
pub(crate) fn prediction_sse(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    w_all: MatRef<'_, f64>,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
) -> Vec<f64> {
    let d_out = data.d_out();
    let cols = w_all.ncols();
    let m = cols / d_out;
    let parts = for_each_block(
        fm,
        data,
        block_rows,
        threads,
        strategy,
        || (vec![0.0; cols], Mat::<f64>::zeros(cols, block_rows)),
        |(sse, pred), block, par| {
            let b = block.at.ncols();
            let mut pv = pred.as_mut().subcols_mut(0, b);
            matmul(
                pv.as_mut(),
                Accum::Replace,
                w_all.transpose(),
                block.at,
                1.0,
                par,
            );
            for c in 0..m {
                for o in 0..d_out {
                    let row = c * d_out + o;
                    let mut s = 0.0;
                    for i in 0..b {
                        let e = pv[(row, i)] - block.y[(i, o)];
                        s += e * e;
                    }
                    sse[row] += s;
                }
            }
        },
    );
    let mut total = vec![0.0; cols];
    for (s, _) in parts {
        for (t, v) in total.iter_mut().zip(s) {
            *t += v;
        }
    }
    total
}
