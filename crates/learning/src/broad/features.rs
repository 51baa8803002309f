//! The pattern row `a(x) = [X_std | friction features | 1 | xi(X)]` (METHOD.md section 5,
//! plus the friction-shaped inputs of section 7), for one sample (prediction) or for a
//! block of samples (training, the Gram accumulation).

use super::config::FrictionFeatures;
use super::data::Standardiser;
use super::error::BroadError;
use super::kernels;
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use serde::{Deserialize, Serialize};

/// The enhancement nodes `xi_j(X) = exp(-||X - u_j||^2 / eta_j^2)` of METHOD.md section 5
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
    /// Centres transposed, dim x L (node index fastest), for the one-sample path.
    centres_t: Vec<f64>,
    /// ||u_j||^2.
    un: Vec<f64>,
    /// 1 / eta_j^2.
    inv_eta2: Vec<f64>,
    /// 1 / v_k for the friction scales.
    inv_scales: Vec<f64>,
}

impl FeatureMap {
    pub(crate) fn new(
        standardiser: Standardiser,
        friction: FrictionFeatures,
        nodes: NodeSet,
    ) -> Self {
        let d = nodes.dim;
        let l = nodes.len();
        let mut centres_t = vec![0.0; d * l];
        for j in 0..l {
            for k in 0..d {
                centres_t[k * l + j] = nodes.centres[j * d + k];
            }
        }
        let un = nodes
            .centres
            .chunks_exact(d.max(1))
            .map(|c| c.iter().map(|v| v * v).sum())
            .collect();
        let inv_eta2 = nodes.widths.iter().map(|w| 1.0 / (w * w)).collect();
        let inv_scales = friction.scales.iter().map(|v| 1.0 / v).collect();
        Self {
            standardiser,
            friction,
            nodes,
            centres_t,
            un,
            inv_eta2,
            inv_scales,
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
    /// The squared distances come from one GEMM per block,
    /// `||x - u||^2 = ||x||^2 + ||u||^2 - 2 x.u` (the -2 X U^T product written straight
    /// into the Gaussian rows), then the vectorised exp. `xn` is scratch of length >= b.
    pub(crate) fn fill_block(&self, x_rows: &[f64], at: &mut [f64], xn: &mut [f64], par: Par) {
        let d = self.d_in();
        let p = self.width();
        let l = self.n_nodes();
        let g0 = self.gauss_offset();
        let b = x_rows.len() / d;
        debug_assert!(at.len() >= p * b);
        for s in 0..b {
            xn[s] = self.fill_head(&x_rows[s * d..(s + 1) * d], &mut at[s * p..s * p + g0]);
        }
        if l == 0 {
            return;
        }
        {
            let at_mat = MatMut::from_column_major_slice_mut(&mut at[..p * b], p, b);
            let (top, bottom) = at_mat.split_at_row_mut(g0);
            let xs_t = top.as_ref().subrows(0, d);
            let u = MatRef::from_row_major_slice(&self.nodes.centres, l, d);
            matmul(bottom, Accum::Replace, u, xs_t, -2.0, par);
        }
        for s in 0..b {
            let col = &mut at[s * p + g0..(s + 1) * p];
            kernels::gauss_from_neg2dots(col, xn[s], &self.un, &self.inv_eta2);
        }
    }
}
