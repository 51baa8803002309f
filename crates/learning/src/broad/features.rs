//! The pattern row `a(x) = [X_std | friction features | 1 | xi(X)]` (docs/method.md section 5,
//! plus the friction-shaped inputs of section 7), for one sample (prediction) or for a
//! block of samples (training, the Gram accumulation).

use super::config::FrictionFeatures;
use super::data::Standardiser;
use super::error::BroadError;
use super::kernels;
use super::kernels::syrk::{self, Slab, Store};
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use serde::{Deserialize, Serialize};

/// The enhancement nodes `xi_j(X) = exp(-||X - u_j||^2 / eta_j^2)` of docs/method.md section 5
/// (eq. 9 form): centres `u_j` in **standardised** input units (row-major, L x d_in) and
/// widths `eta_j > 0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodeSet {
    /// Input width d_in.
    pub dim: usize,
    /// Centres, row-major L x dim, standardised input units.
    pub centres: Vec<f64>,
    /// Widths eta_j, length L.
    pub widths: Vec<f64>,
}

impl NodeSet {
    /// Number of nodes L.
    pub fn len(&self) -> usize {
        self.widths.len()
    }
    /// True when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.widths.is_empty()
    }
    /// Checks shapes, finiteness and positive widths.
    pub fn validate(&self, d_in: usize) -> Result<(), BroadError> {
        if self.dim != d_in {
            return Err(BroadError::Dimension {
                what: "node centre width",
                expected: d_in,
                got: self.dim,
            });
        }
        if self.centres.len() != self.widths.len() * self.dim {
            return Err(BroadError::Dimension {
                what: "node centres length (L * d_in)",
                expected: self.widths.len() * self.dim,
                got: self.centres.len(),
            });
        }
        super::data::check_finite(&self.centres, self.dim.max(1), "node centres")?;
        if let Some((j, &w)) = self
            .widths
            .iter()
            .enumerate()
            .find(|(_, &w)| !(w.is_finite() && w > 0.0))
        {
            return Err(BroadError::Config(format!(
                "node {j} has width {w}; widths must be finite and > 0"
            )));
        }
        Ok(())
    }
    /// Appends the nodes of `other`.
    pub fn extend(&mut self, other: &NodeSet) {
        self.centres.extend_from_slice(&other.centres);
        self.widths.extend_from_slice(&other.widths);
    }
}

/// Everything needed to map a raw input row to its pattern row, with derived quantities
/// precomputed for speed.
#[derive(Clone, Debug)]
pub(crate) struct FeatureMap {
    pub(crate) standardiser: Standardiser,
    pub(crate) friction: FrictionFeatures,
    pub(crate) nodes: NodeSet,
    /// Centres block-major (`kernels::block_major_index`), for the one-sample path.
    centres_t: Vec<f64>,
    /// ||u_j||^2.
    un: Vec<f64>,
    /// 1 / eta_j^2.
    inv_eta2: Vec<f64>,
    /// 1 / v_k for the friction scales.
    inv_scales: Vec<f64>,
    /// `-2 u_j` packed for the SIMD distance product (None without AVX2 + FMA).
    centres_packed: Option<Slab>,
}

/// Per-worker scratch of [`FeatureMap::fill_block`].
#[derive(Debug, Default)]
pub(crate) struct BlockScratch {
    /// ||x_std||^2 per sample.
    xn: Vec<f64>,
    /// The block's standardised inputs, packed (SIMD path).
    xs: Option<Slab>,
}

/// Per-worker scratch of [`FeatureMap::fill_slab_observed`].
#[derive(Debug, Default)]
pub(crate) struct SlabScratch {
    block: BlockScratch,
    /// One chunk of pattern columns, column-major.
    chunk: Vec<f64>,
}

impl FeatureMap {
    pub(crate) fn new(
        standardiser: Standardiser,
        friction: FrictionFeatures,
        nodes: NodeSet,
    ) -> Self {
        let d = nodes.dim;
        let l = nodes.len();
        let centres_t = kernels::block_major(&nodes.centres, d, l);
        let un = nodes
            .centres
            .chunks_exact(d.max(1))
            .map(|c| c.iter().map(|v| v * v).sum())
            .collect();
        let inv_eta2 = nodes.widths.iter().map(|w| 1.0 / (w * w)).collect();
        let inv_scales = friction.scales.iter().map(|v| 1.0 / v).collect();
        let centres_packed = (syrk::simd_available() && l > 0 && d > 0).then(|| {
            let mut u = Slab::new(l, d);
            u.pack_rows(&nodes.centres, d, d, -2.0);
            u
        });
        Self {
            standardiser,
            friction,
            nodes,
            centres_t,
            un,
            inv_eta2,
            inv_scales,
            centres_packed,
        }
    }

    pub(crate) fn d_in(&self) -> usize {
        self.standardiser.dim()
    }
    pub(crate) fn n_nodes(&self) -> usize {
        self.nodes.len()
    }
    /// Number of friction columns F.
    pub(crate) fn n_friction(&self) -> usize {
        self.friction.count()
    }
    /// Index of the bias column: d_in + F.
    pub(crate) fn bias_index(&self) -> usize {
        self.d_in() + self.n_friction()
    }
    /// Index of the first Gaussian column: d_in + F + 1.
    pub(crate) fn gauss_offset(&self) -> usize {
        self.bias_index() + 1
    }
    /// Pattern width P = d_in + F + 1 + L.
    pub(crate) fn width(&self) -> usize {
        self.gauss_offset() + self.n_nodes()
    }

    /// Linear part, friction features and bias of one raw input row; returns ||x_std||^2.
    #[inline]
    fn fill_head(&self, x: &[f64], a: &mut [f64]) -> f64 {
        let d = self.d_in();
        self.standardiser.apply(x, &mut a[..d]);
        let xn = a[..d].iter().map(|v| v * v).sum();
        let mut idx = d;
        for &c in &self.friction.columns {
            let v = x[c];
            for &is in &self.inv_scales {
                a[idx] = (v * is).tanh();
                idx += 1;
            }
        }
        a[idx] = 1.0;
        xn
    }

    /// Pattern row of one raw input `x` into `a` (length P), direct distances (no
    /// cancellation), no allocation. `dist` is scratch of length >= L.
    pub(crate) fn fill_row(&self, x: &[f64], a: &mut [f64]) {
        let g0 = self.gauss_offset();
        let l = self.n_nodes();
        let d = self.d_in();
        self.fill_head(x, a);
        let (head, gauss) = a.split_at_mut(g0);
        let gauss = &mut gauss[..l];
        kernels::sqdist(&head[..d], &self.centres_t, gauss);
        kernels::gauss_from_sqdist(gauss, &self.inv_eta2);
    }

    /// Pattern block for `b` raw input rows `x_rows` (row-major b x d_in) into `at`
    /// (column-major P x b: column s is the pattern row of sample s).
    ///
    /// The squared distances come from one matrix product per block,
    /// `||x - u||^2 = ||x||^2 + ||u||^2 - 2 x.u` (the -2 U X^T product written straight
    /// into the Gaussian rows: the packed SIMD kernel, or faer without AVX2 + FMA), then
    /// the vectorised exp.
    pub(crate) fn fill_block(
        &self,
        x_rows: &[f64],
        at: &mut [f64],
        scratch: &mut BlockScratch,
        par: Par,
    ) {
        let d = self.d_in();
        let p = self.width();
        let l = self.n_nodes();
        let g0 = self.gauss_offset();
        let b = x_rows.len() / d;
        debug_assert!(at.len() >= p * b);
        if b == 0 {
            return;
        }
        let at = &mut at[..p * b];
        if scratch.xn.len() < b {
            scratch.xn.resize(b, 0.0);
        }
        let xn = &mut scratch.xn[..b];
        for s in 0..b {
            xn[s] = self.fill_head(&x_rows[s * d..(s + 1) * d], &mut at[s * p..s * p + g0]);
        }
        if l == 0 {
            return;
        }
        match &self.centres_packed {
            Some(u) => {
                // Chunks of 24 samples, so that their distances (24 columns, about
                // 200 KB at L = 1000) are still in L2 when the exp reads them. X_std is
                // the first d rows of each column.
                const CHUNK: usize = 24;
                let xs = scratch.xs.get_or_insert_with(|| Slab::new(CHUNK, d));
                if xs.capacity() < d {
                    *xs = Slab::new(CHUNK, d);
                }
                let mut s0 = 0;
                while s0 < b {
                    let c = CHUNK.min(b - s0);
                    let part = &mut at[s0 * p..(s0 + c) * p];
                    xs.set_rows(c);
                    xs.pack_rows(part, p, d, 1.0);
                    syrk::gemm_nt(&mut part[g0..], p, u, xs, Store::Overwrite);
                    self.gauss_columns(part, &xn[s0..s0 + c]);
                    s0 += c;
                }
            }
            None => {
                let at_mat = MatMut::from_column_major_slice_mut(at, p, b);
                let (top, bottom) = at_mat.split_at_row_mut(g0);
                let xs_t = top.as_ref().subrows(0, d);
                let u = MatRef::from_row_major_slice(&self.nodes.centres, l, d);
                matmul(bottom, Accum::Replace, u, xs_t, -2.0, par);
                self.gauss_columns(at, xn);
            }
        }
    }

    /// Pattern rows of the raw inputs `x_rows` (row-major b x d_in, b at most the slab's
    /// capacity) with the row-major targets `y_rows` (b x d_out) under them, straight
    /// into a packed slab of P + d_out rows: formed 24 samples at a time in `chunk`
    /// (about 200 KB at P = 1043, so it stays in L2 until it is packed), never as a
    /// whole block. The values are those of [`fill_block`](Self::fill_block).
    ///
    /// Each chunk of pattern columns (column-major, P x c, in sample order) is handed to
    /// `observe` while it is in cache.
    pub(crate) fn fill_slab_observed(
        &self,
        x_rows: &[f64],
        y_rows: &[f64],
        d_out: usize,
        slab: &mut Slab,
        scratch: &mut SlabScratch,
        mut observe: impl FnMut(&[f64]),
    ) {
        const CHUNK: usize = 24;
        let d = self.d_in();
        let p = self.width();
        let b = x_rows.len() / d.max(1);
        slab.set_len(b);
        if scratch.chunk.len() < p * CHUNK {
            scratch.chunk.resize(p * CHUNK, 0.0);
        }
        let mut s0 = 0;
        while s0 < b {
            let c = CHUNK.min(b - s0);
            let chunk = &mut scratch.chunk[..p * c];
            self.fill_block(
                &x_rows[s0 * d..(s0 + c) * d],
                chunk,
                &mut scratch.block,
                Par::Seq,
            );
            observe(chunk);
            slab.write_chunk(chunk, p, s0, c, &y_rows[s0 * d_out..], d_out);
            s0 += c;
        }
    }

    /// Gaussian rows of the columns of `at` (column-major P x xn.len()) from the `-2 x.u`
    /// they hold and `xn = ||x||^2`.
    fn gauss_columns(&self, at: &mut [f64], xn: &[f64]) {
        let p = self.width();
        let g0 = self.gauss_offset();
        for (col, &x2) in at.chunks_exact_mut(p).zip(xn) {
            kernels::gauss_from_neg2dots(&mut col[g0..], x2, &self.un, &self.inv_eta2);
        }
    }
}

/// Appends to `out` the largest Gaussian activation of each pattern column of `at`
/// (column-major, `fm.width()` rows), as `coverage.rs` measures one
/// pattern, kept in eight running maxima so that the loop vectorises (a single `fold` is one
/// serial chain of compares); the maximum of the activations (never NaN) does not depend on the order.
pub(crate) fn push_max_activations(fm: &FeatureMap, at: &[f64], out: &mut Vec<f64>) {
    const W: usize = 8;
    let p = fm.width();
    let g0 = fm.gauss_offset();
    out.extend(at.chunks_exact(p.max(1)).map(|column| {
        let gauss = &column[g0..];
        let mut acc = [0.0f64; W];
        let mut blocks = gauss.chunks_exact(W);
        for b in &mut blocks {
            for l in 0..W {
                acc[l] = if b[l] > acc[l] { b[l] } else { acc[l] };
            }
        }
        let tail = blocks.remainder().iter().fold(0.0f64, |m, &v| m.max(v));
        acc.iter().fold(tail, |m, &v| m.max(v))
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A feature map on `d` inputs with `l` deterministic nodes, inputs standardised with
    /// `mean` and `std` on every column, and friction features on `columns` x `scales`.
    fn test_map(
        d: usize,
        l: usize,
        (mean, std): (f64, f64),
        columns: Vec<usize>,
        scales: Vec<f64>,
    ) -> FeatureMap {
        let nodes = NodeSet {
            dim: d,
            centres: (0..l * d).map(|i| (i as f64 * 0.377).cos()).collect(),
            widths: (0..l).map(|j| 0.7 + 0.05 * j as f64).collect(),
        };
        let standardiser = Standardiser {
            mean: vec![mean; d],
            std: vec![std; d],
        };
        FeatureMap::new(standardiser, FrictionFeatures { columns, scales }, nodes)
    }

    /// The packed distance product (AVX2 + FMA machines) and faer's give the same block,
    /// and both the per-sample pattern rows of `fill_row` (direct distances).
    #[test]
    fn fill_block_paths_agree_with_fill_row() {
        let (n, d, l) = (37, 5, 29);
        let x: Vec<f64> = (0..n * d).map(|i| (i as f64 * 0.731).sin() * 2.0).collect();
        let fm = test_map(d, l, (0.1, 1.3), vec![0, 3], vec![0.5]);
        let mut fm_faer = fm.clone();
        fm_faer.centres_packed = None;
        let p = fm.width();
        let mut rows = vec![0.0; p * n];
        for s in 0..n {
            fm.fill_row(&x[s * d..(s + 1) * d], &mut rows[s * p..(s + 1) * p]);
        }
        for map in [&fm, &fm_faer] {
            // Uneven blocks, scratch reused between them.
            let mut scratch = BlockScratch::default();
            let mut s0 = 0;
            for b in [1, 11, 25] {
                let mut at = vec![f64::NAN; p * b];
                map.fill_block(&x[s0 * d..(s0 + b) * d], &mut at, &mut scratch, Par::Seq);
                for (i, (&got, &e)) in at.iter().zip(&rows[s0 * p..]).enumerate() {
                    assert!(
                        (got - e).abs() <= 1e-12 * e.abs().max(1e-3),
                        "packed {}: sample {}, column {}: {got} vs {e}",
                        map.centres_packed.is_some(),
                        s0 + i / p,
                        i % p
                    );
                }
                s0 += b;
            }
        }
    }

    /// `fill_slab_observed` (24-sample chunks written into the slab) holds exactly the block that
    /// `fill_block` forms, packed with its targets, for block sizes around the chunk.
    #[test]
    fn fill_slab_equals_the_packed_block() {
        let (d, l, d_out) = (4, 37, 3);
        let fm = test_map(d, l, (0.2, 0.9), vec![1, 2], vec![0.3, 2.0]);
        let p = fm.width();
        let mut scratch = SlabScratch::default();
        let mut slab = Slab::new(p + d_out, 80);
        for b in [1usize, 23, 24, 25, 49, 80] {
            let x: Vec<f64> = (0..b * d).map(|i| (i as f64 * 0.613).sin() * 1.7).collect();
            let y: Vec<f64> = (0..b * d_out).map(|i| (i as f64 * 0.29).cos()).collect();
            fm.fill_slab_observed(&x, &y, d_out, &mut slab, &mut scratch, |_| {});
            let mut at = vec![0.0; p * b];
            fm.fill_block(&x, &mut at, &mut BlockScratch::default(), Par::Seq);
            let mut packed = Slab::new(p + d_out, 80);
            packed.pack_with_targets(&at, p, 0, b, &y, d_out);
            let (got, want) = (slab.data_for_tests(), packed.data_for_tests());
            assert_eq!(got.len(), want.len(), "b {b}");
            for (i, (g, w)) in got.iter().zip(want).enumerate() {
                assert_eq!(g.to_bits(), w.to_bits(), "b {b}: packed value {i}");
            }
        }
    }
}
