//! Blocked passes over a data set: the N x P pattern matrix A is never held whole.
//! Each pass forms the pattern a block of rows at a time and hands it to a consumer: the
//! Gram accumulation `G += A_b^T A_b`, `A^T Y += A_b^T Y_b` (docs/method.md section 5, the
//! normal equations of the ridge solution), the cross terms of a node growth, or
//! validation predictions.
//!
//! The products that dominate a fit, the Gram (with A^T Y) and the growth cross terms,
//! run on packed slabs with a register-tiled AVX2 + FMA kernel (`kernels/syrk.rs`) when
//! the CPU has it and each block is handled by one thread: the blocks are then formed
//! straight into the packed layout ([`for_each_slab`]). Otherwise the blocks are formed
//! column-major (P x b, one pattern row per column, [`for_each_block`]) for faer's
//! matmul.

use super::config::GramStrategy;
use super::data::Dataset;
use super::features::{push_max_activations, BlockScratch, FeatureMap, SlabScratch};
use super::kernels::syrk::{self, Store};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::{Accum, Mat, MatMut, MatRef, Par};

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
        let mut scratch = BlockScratch::default();
        let mut r = start;
        while r < end {
            let b = block_rows.min(end - r);
            fm.fill_block(
                data.input_rows(r, b),
                &mut at[..p * b],
                &mut scratch,
                Par::Seq,
            );
            let y_rm = data.target_rows(r, b);
            let block = Block {
                at: MatRef::from_column_major_slice(&at[..p * b], p, b),
                y: MatRef::from_row_major_slice(y_rm, b, d_out),
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
        GramStrategy::PerThread => on_ranges(n, block_rows, threads, &init, &run_range),
        GramStrategy::SharedGemm => {
            let mut state = init();
            let mut at = vec![0.0; p * block_rows];
            let par = Par::rayon(threads);
            let mut r = 0;
            while r < n {
                let b = block_rows.min(n - r);
                let per = b.div_ceil(threads);
                std::thread::scope(|scope| {
                    let mut at_rest = &mut at[..p * b];
                    let mut s0 = 0;
                    while s0 < b {
                        let bb = per.min(b - s0);
                        let (at_part, at_tail) = std::mem::take(&mut at_rest).split_at_mut(p * bb);
                        at_rest = at_tail;
                        let rows = data.input_rows(r + s0, bb);
                        scope.spawn(move || {
                            fm.fill_block(rows, at_part, &mut BlockScratch::default(), Par::Seq)
                        });
                        s0 += bb;
                    }
                });
                let y_rm = data.target_rows(r, b);
                let block = Block {
                    at: MatRef::from_column_major_slice(&at[..p * b], p, b),
                    y: MatRef::from_row_major_slice(y_rm, b, d_out),
                };
                consume(&mut state, block, par);
                r += b;
            }
            vec![state]
        }
    }
}

/// Cuts `0..n` into `threads` contiguous, block-aligned ranges (so that the blocks are
/// full) and runs `run_range` on each in its own thread, with its own state.
fn on_ranges<S: Send>(
    n: usize,
    block_rows: usize,
    threads: usize,
    init: &(impl Fn() -> S + Sync),
    run_range: &(impl Fn(usize, usize, &mut S) + Sync),
) -> Vec<S> {
    let n_blocks = n.div_ceil(block_rows);
    let per = n_blocks.div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .filter_map(|t| {
                let start = (t * per * block_rows).min(n);
                let end = ((t + 1) * per * block_rows).min(n);
                (start < end).then(|| {
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

/// The packed path's pass: runs `consume` on the `[pattern | targets]` slab (P + d_out
/// rows, see [`FeatureMap::fill_slab_observed`]) of every block of at most `slab_rows` samples
/// (capped at `syrk::KC`), the rows cut between `threads` workers as in the `PerThread`
/// strategy of [`for_each_block`], each with its own state (from `init`). Each block is
/// formed straight into the slab, never as a column-major block: that saves a 4 MB
/// buffer per worker (at P = 1043) beside the slab and the Gram in L3, and a copy.
fn for_each_slab<S: Send>(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    slab_rows: usize,
    threads: usize,
    init: impl Fn() -> S + Sync,
    consume: impl Fn(&mut S, &syrk::Slab, &[f64]) + Sync,
) -> Vec<S> {
    for_each_slab_observed(
        fm,
        data,
        slab_rows,
        threads,
        false,
        init,
        |s, slab, y, _| consume(s, slab, y),
    )
}

/// [`for_each_slab`], with the largest Gaussian activation of each row of the block
/// (`features::push_max_activations`, taken from the pattern while it is formed) handed to
/// `consume` when `maxima` (an empty slice otherwise).
fn for_each_slab_observed<S: Send>(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    slab_rows: usize,
    threads: usize,
    maxima: bool,
    init: impl Fn() -> S + Sync,
    consume: impl Fn(&mut S, &syrk::Slab, &[f64], &[f64]) + Sync,
) -> Vec<S> {
    let n = data.n_samples();
    let d_out = data.d_out();
    let slab_rows = slab_rows.clamp(1, syrk::KC);
    let threads = threads.max(1);
    let run_range = |start: usize, end: usize, state: &mut S| {
        let mut slab = syrk::Slab::new(fm.width() + d_out, slab_rows);
        let mut scratch = SlabScratch::default();
        let mut block_max = Vec::with_capacity(if maxima { slab_rows } else { 0 });
        let mut r = start;
        while r < end {
            let b = slab_rows.min(end - r);
            let y_rm = data.target_rows(r, b);
            block_max.clear();
            fm.fill_slab_observed(
                data.input_rows(r, b),
                y_rm,
                d_out,
                &mut slab,
                &mut scratch,
                |chunk| {
                    if maxima {
                        push_max_activations(fm, chunk, &mut block_max);
                    }
                },
            );
            consume(state, &slab, y_rm, &block_max);
            r += b;
        }
    };
    if threads == 1 || n < 2 * slab_rows {
        let mut s = init();
        run_range(0, n, &mut s);
        return vec![s];
    }
    on_ranges(n, slab_rows, threads, &init, &run_range)
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

/// Whether the blocks of a pass go through the packed SIMD kernel: the CPU has AVX2 +
/// FMA and each block is consumed by one thread (the `SharedGemm` strategy parallelises
/// inside faer's matmul instead). Such passes run on [`for_each_slab`], blocks of at most
/// `syrk::KC` rows formed straight into their packed slabs. `allow` false forces faer
/// (tests).
fn simd_rows(
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
    allow: bool,
) -> Option<usize> {
    let one_thread_per_block = threads <= 1 || strategy == GramStrategy::PerThread;
    (allow && syrk::simd_available() && one_thread_per_block).then(|| block_rows.clamp(1, syrk::KC))
}

/// One worker's share of [`accumulate_gram`].
struct GramPart {
    /// Column-major, lower triangle. Packed path: the Gram of `[A | Y]`, (P + d_out)
    /// square, whose last d_out rows hold `Y^T A`; faer path: G alone, P x P.
    g: Vec<f64>,
    /// A^T Y (faer path).
    aty: Mat<f64>,
    y_sum: Vec<f64>,
    y_sq: Vec<f64>,
}

/// G = A^T A (lower triangle, symmetric rank-k updates), A^T Y and the target sums:
/// the normal equations of docs/method.md section 5, accumulated block by block.
pub(crate) fn accumulate_gram(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
) -> GramAcc {
    gram_pass(fm, data, block_rows, threads, strategy, true)
}

fn gram_pass(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
    allow_simd: bool,
) -> GramAcc {
    let p = fm.width();
    let d_out = data.d_out();
    let simd = simd_rows(block_rows, threads, strategy, allow_simd);
    // Packed path: Y rides along as d_out extra rows, so that one symmetric product
    // gives A^T A and A^T Y (its last rows) at the kernel's speed.
    let n = if simd.is_some() { p + d_out } else { p };
    let init = || GramPart {
        g: vec![0.0; n * n],
        aty: Mat::zeros(p, d_out),
        y_sum: vec![0.0; d_out],
        y_sq: vec![0.0; d_out],
    };
    let parts = match simd {
        Some(rows) => for_each_slab(fm, data, rows, threads, init, |acc, slab, y_rm| {
            syrk::gemm_nt(&mut acc.g, n, slab, slab, Store::AddLower);
            let y = MatRef::from_row_major_slice(y_rm, y_rm.len() / d_out.max(1), d_out);
            add_y_stats(y, &mut acc.y_sum, &mut acc.y_sq);
        }),
        None => for_each_block(
            fm,
            data,
            block_rows,
            threads,
            strategy,
            init,
            |acc, block, par| {
                tri_matmul(
                    MatMut::from_column_major_slice_mut(&mut acc.g, n, n)
                        .subrows_mut(0, p)
                        .subcols_mut(0, p),
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
        ),
    };
    // Summed into the first worker's share (one Gram-sized buffer less at the peak).
    let mut parts = parts.into_iter();
    let Some(mut sum) = parts.next() else {
        return GramAcc::zeros(p, d_out);
    };
    for part in parts {
        let pairs = [
            (&mut sum.g, &part.g),
            (&mut sum.y_sum, &part.y_sum),
            (&mut sum.y_sq, &part.y_sq),
        ];
        for (total, add) in pairs {
            for (a, b) in total.iter_mut().zip(add) {
                *a += b;
            }
        }
        sum.aty += &part.aty;
    }
    let g = MatRef::from_column_major_slice(&sum.g, n, n);
    GramAcc {
        g: g.submatrix(0, 0, p, p).to_owned(),
        aty: if n > p {
            g.submatrix(p, 0, d_out, p).transpose().to_owned()
        } else {
            sum.aty
        },
        y_sum: sum.y_sum,
        y_sq: sum.y_sq,
    }
}

/// Cross terms for `k` new nodes appended at the end of `fm` (pattern width P' = P + k):
/// the last k rows of the grown Gram, `A_new^T [A_old | A_new]` (k x P'), and
/// `A_new^T Y` (k x d_out). The old features are recomputed per block (the pattern matrix
/// is not stored) but only the k new rows of the Gram are multiplied: 2 N P' k flops
/// instead of N P'^2 for a full retrain. Accumulated transposed, `[A | Y]^T A_new`
/// ((P' + d_out) x k, Y as extra rows on the packed path), the packed kernel's layout.
///
/// With `maxima`, also the largest Gaussian activation of every row of `data` under the
/// grown node set (in no particular order), for the coverage threshold
/// (`coverage::threshold_of_maxima`), taken from the pattern this pass forms anyway
/// instead of a second pass; empty otherwise.
pub(crate) fn accumulate_new_rows(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    k: usize,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
    maxima: bool,
) -> NewRows {
    new_rows_pass(fm, data, k, block_rows, threads, strategy, true, maxima)
}

/// What [`accumulate_new_rows`] returns.
pub(crate) struct NewRows {
    /// `A_new^T [A_old | A_new]`, k x P'.
    pub rows: Mat<f64>,
    /// `A_new^T Y`, k x d_out.
    pub aty: Mat<f64>,
    /// Largest activation of each row (when asked for).
    pub maxima: Vec<f64>,
}

/// One worker's share of [`new_rows_pass`]: the transposed cross terms, `A_new^T Y`
/// (faer path) and the row maxima.
type NewRowsPart = (Vec<f64>, Mat<f64>, Vec<f64>);

#[allow(clippy::too_many_arguments)]
fn new_rows_pass(
    fm: &FeatureMap,
    data: &Dataset<'_>,
    k: usize,
    block_rows: usize,
    threads: usize,
    strategy: GramStrategy,
    allow_simd: bool,
    maxima: bool,
) -> NewRows {
    let p = fm.width();
    let p_old = p - k;
    let d_out = data.d_out();
    let simd = simd_rows(block_rows, threads, strategy, allow_simd);
    let n = if simd.is_some() { p + d_out } else { p };
    let init = || -> NewRowsPart { (vec![0.0; n * k], Mat::<f64>::zeros(k, d_out), Vec::new()) };
    let parts: Vec<NewRowsPart> = match simd {
        Some(rows) => for_each_slab_observed(
            fm,
            data,
            rows,
            threads,
            maxima,
            || (init(), syrk::Slab::new(k, rows.clamp(1, syrk::KC))),
            |((cross, _, max), new), all, _, block_max| {
                new.copy_rows(all, p_old);
                syrk::gemm_nt(cross, n, all, new, Store::Add);
                max.extend_from_slice(block_max);
            },
        )
        .into_iter()
        .map(|(part, _)| part)
        .collect(),
        None => for_each_block(
            fm,
            data,
            block_rows,
            threads,
            strategy,
            init,
            |(cross, aty, max), block, par| {
                let new_t = block.at.subrows(p_old, k);
                matmul(
                    MatMut::from_column_major_slice_mut(cross, n, k),
                    Accum::Add,
                    block.at,
                    new_t.transpose(),
                    1.0,
                    par,
                );
                matmul(aty.as_mut(), Accum::Add, new_t, block.y, 1.0, par);
                if maxima {
                    let g0 = fm.gauss_offset();
                    for s in 0..block.at.ncols() {
                        let col = block.at.col(s);
                        max.push((g0..p).fold(0.0f64, |m, i| m.max(col[i])));
                    }
                }
            },
        ),
    };
    let mut rows = Mat::<f64>::zeros(k, p);
    let mut aty = Mat::<f64>::zeros(k, d_out);
    let mut all_max = Vec::with_capacity(if maxima { data.n_samples() } else { 0 });
    for (cross, a, max) in &parts {
        all_max.extend_from_slice(max);
        let c = MatRef::from_column_major_slice(cross, n, k);
        rows += c.subrows(0, p).transpose();
        if n > p {
            aty += c.subrows(p, d_out).transpose();
        } else {
            aty += a;
        }
    }
    NewRows {
        rows,
        aty,
        maxima: all_max,
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::broad::config::FrictionFeatures;
    use crate::broad::data::Standardiser;
    use crate::broad::features::NodeSet;

    /// Deterministic pseudo-random values in [-1, 1).
    fn values(n: usize, seed: u64) -> Vec<f64> {
        crate::broad::kernels::test_values(n, seed)
            .into_iter()
            .map(|v| 2.0 * v)
            .collect()
    }

    /// A feature map with `l` nodes on 3 inputs (one with friction features) and the
    /// pattern matrix of `data` formed in one block, column-major P x N.
    fn setup(data: &Dataset<'_>, l: usize, seed: u64) -> (FeatureMap, Vec<f64>) {
        let nodes = NodeSet {
            dim: 3,
            centres: values(3 * l, seed),
            widths: values(l, seed + 1).iter().map(|v| 0.8 + 0.5 * v).collect(),
        };
        let friction = FrictionFeatures {
            columns: vec![1],
            scales: vec![0.1, 0.5],
        };
        let fm = FeatureMap::new(Standardiser::from_data(data), friction, nodes);
        let (n, p) = (data.n_samples(), fm.width());
        let mut at = vec![0.0; p * n];
        fm.fill_block(
            data.inputs(),
            &mut at,
            &mut BlockScratch::default(),
            Par::Seq,
        );
        (fm, at)
    }

    /// `|got - expected| <= 1e-12 * scale` entrywise.
    fn assert_close(got: MatRef<'_, f64>, expected: &Mat<f64>, scale: &Mat<f64>, what: &str) {
        for j in 0..got.ncols() {
            for i in 0..got.nrows() {
                let err = (got[(i, j)] - expected[(i, j)]).abs();
                assert!(
                    err <= 1e-12 * scale[(i, j)] + 1e-300,
                    "{what}: ({i}, {j}) = {} vs {} (error {err:e})",
                    got[(i, j)],
                    expected[(i, j)]
                );
            }
        }
    }

    /// The packed kernel and the faer path give the naive `A^T A` (lower triangle),
    /// `A^T Y` and the growth cross terms, for block sizes that do not divide N and for
    /// 1 and 2 threads.
    #[test]
    fn packed_and_faer_passes_match_naive_products() {
        let (n, d_out, l, k_new) = (611, 2, 45, 7);
        let x = values(n * 3, 11);
        let y = values(n * d_out, 12);
        let data = Dataset::new(&x, &y, 3, d_out).unwrap();
        let (fm, at) = setup(&data, l, 13);
        let p = fm.width();
        let a = |s: usize, i: usize| at[s * p + i];
        let (mut g, mut g_scale) = (Mat::<f64>::zeros(p, p), Mat::<f64>::zeros(p, p));
        for j in 0..p {
            for i in j..p {
                for s in 0..n {
                    g[(i, j)] += a(s, i) * a(s, j);
                    g_scale[(i, j)] += (a(s, i) * a(s, j)).abs();
                }
            }
        }
        let (mut aty, mut aty_scale) = (Mat::<f64>::zeros(p, d_out), Mat::<f64>::zeros(p, d_out));
        for o in 0..d_out {
            for i in 0..p {
                for s in 0..n {
                    aty[(i, o)] += a(s, i) * y[s * d_out + o];
                    aty_scale[(i, o)] += (a(s, i) * y[s * d_out + o]).abs();
                }
            }
        }
        // Row p - k + r of the symmetric G, from its lower triangle.
        let sym = |m: &Mat<f64>, r: usize, i: usize| {
            let row = p - k_new + r;
            m[(row.max(i), row.min(i))]
        };
        let rows = Mat::<f64>::from_fn(k_new, p, |r, i| sym(&g, r, i));
        let rows_scale = Mat::<f64>::from_fn(k_new, p, |r, i| sym(&g_scale, r, i));
        let rows_aty = aty.as_ref().subrows(p - k_new, k_new).to_owned();
        let rows_aty_scale = aty_scale.as_ref().subrows(p - k_new, k_new).to_owned();
        for allow_simd in [true, false] {
            for (block, threads) in [(1, 1), (7, 1), (256, 1), (300, 2), (2048, 2)] {
                let what = format!("simd {allow_simd} block {block} threads {threads}");
                let acc = gram_pass(
                    &fm,
                    &data,
                    block,
                    threads,
                    GramStrategy::PerThread,
                    allow_simd,
                );
                let lower =
                    Mat::<f64>::from_fn(p, p, |i, j| if i >= j { acc.g[(i, j)] } else { 0.0 });
                assert_close(lower.as_ref(), &g, &g_scale, &format!("{what} G"));
                assert_close(acc.aty.as_ref(), &aty, &aty_scale, &format!("{what} A^T Y"));
                let new = new_rows_pass(
                    &fm,
                    &data,
                    k_new,
                    block,
                    threads,
                    GramStrategy::PerThread,
                    allow_simd,
                    true,
                );
                let (r, ra) = (&new.rows, &new.aty);
                // The row maxima: every row once, each the largest activation of its
                // pattern row.
                let mut got = new.maxima.clone();
                let mut want: Vec<f64> = (0..n)
                    .map(|s| (p - l..p).fold(0.0f64, |m, i| m.max(a(s, i))))
                    .collect();
                got.sort_by(f64::total_cmp);
                want.sort_by(f64::total_cmp);
                assert_eq!(got.len(), n, "{what} row maxima");
                for (g, w) in got.iter().zip(&want) {
                    assert!((g - w).abs() <= 1e-12 * w, "{what} row maxima: {g} vs {w}");
                }
                assert_close(
                    r.as_ref(),
                    &rows,
                    &rows_scale,
                    &format!("{what} cross terms"),
                );
                assert_close(
                    ra.as_ref(),
                    &rows_aty,
                    &rows_aty_scale,
                    &format!("{what} new A^T Y"),
                );
            }
        }
    }
}
