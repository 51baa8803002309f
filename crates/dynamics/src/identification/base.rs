//! Base parameters: which combinations of the inertial parameters the joint torques
//! determine. A regressor column that is a combination of earlier columns on every motion
//! carries no information of its own; the rest are the *independent* columns, and the base
//! parameters are `pi_b = pi_independent + beta pi_dependent`.

use nalgebra::{DMatrix, DVector};

use crate::algorithms::regressor::{joint_torque_regressor, PARAMETERS_PER_BODY};
use crate::data::Data;
use crate::error::DynamicsError;
use crate::model::Model;

/// Relative size below which a column's part outside the span of the earlier columns
/// counts as zero.
const RANK_TOLERANCE: f64 = 1e-8;

/// The base parameters of an arm, found numerically from its regressor.
#[derive(Clone, Debug)]
pub struct BaseParameters {
    independent: Vec<usize>,
    dependent: Vec<usize>,
    /// `Y_dependent = Y_independent beta` (rank x dependent).
    beta: DMatrix<f64>,
}

impl BaseParameters {
    /// From the regressor stacked over `samples` pseudo-random states within the joint
    /// limits (position: the limits or +-pi; velocity: the limit or 2 rad/s; acceleration:
    /// +-5), drawn from `seed`.
    pub fn new(model: &Model, samples: usize, seed: u64) -> Result<Self, DynamicsError> {
        let n = model.nq();
        if samples == 0 || n == 0 {
            return Err(DynamicsError::InvalidArgument(
                "base parameters need at least one sample and one joint".into(),
            ));
        }
        let mut rng = SplitMix(seed);
        let mut data = Data::new(model);
        let mut stacked = DMatrix::zeros(samples * n, PARAMETERS_PER_BODY * n);
        let (mut q, mut v, mut a) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for s in 0..samples {
            for (i, joint) in model.joints.iter().enumerate() {
                let l = &joint.limits;
                let (lo, hi) = if l.lower.is_finite() && l.upper.is_finite() {
                    (l.lower, l.upper)
                } else {
                    (-std::f64::consts::PI, std::f64::consts::PI)
                };
                let vmax = if l.velocity.is_finite() {
                    l.velocity.min(2.0)
                } else {
                    2.0
                };
                q[i] = lo + (hi - lo) * rng.unit();
                v[i] = vmax * (2.0 * rng.unit() - 1.0);
                a[i] = 5.0 * (2.0 * rng.unit() - 1.0);
            }
            let y = joint_torque_regressor(model, &mut data, &q, &v, &a)?;
            stacked.view_mut((s * n, 0), (n, y.ncols())).copy_from(y);
        }
        Ok(Self::from_regressor(&stacked))
    }

    /// From a stacked regressor (rows: samples times joints): columns are kept in order
    /// when their part outside the span of the columns kept before them is more than
    /// 1e-8 of their norm (Gram-Schmidt, twice for accuracy).
    pub fn from_regressor(stacked: &DMatrix<f64>) -> Self {
        let largest = (0..stacked.ncols())
            .map(|c| stacked.column(c).norm())
            .fold(0.0, f64::max);
        let mut basis: Vec<DVector<f64>> = Vec::new();
        let (mut independent, mut dependent) = (Vec::new(), Vec::new());
        for c in 0..stacked.ncols() {
            let col = stacked.column(c).into_owned();
            let norm = col.norm();
            let mut rest = col;
            for _ in 0..2 {
                for b in &basis {
                    let d = b.dot(&rest);
                    rest.axpy(-d, b, 1.0);
                }
            }
            let r = rest.norm();
            if norm > 1e-12 * largest && r > RANK_TOLERANCE * norm {
                basis.push(rest / r);
                independent.push(c);
            } else {
                dependent.push(c);
            }
        }
        let yi = select_columns(stacked, &independent);
        let yd = select_columns(stacked, &dependent);
        let beta = if dependent.is_empty() {
            DMatrix::zeros(independent.len(), 0)
        } else {
            let gram = yi.transpose() * &yi;
            let rhs = yi.transpose() * yd;
            gram.cholesky()
                .map(|c| c.solve(&rhs))
                .unwrap_or_else(|| DMatrix::zeros(independent.len(), dependent.len()))
        };
        BaseParameters {
            independent,
            dependent,
            beta,
        }
    }

    /// Number of base parameters (the regressor's numerical rank).
    pub fn rank(&self) -> usize {
        self.independent.len()
    }

    /// Indices (into the 10 n parameters) of the independent columns.
    pub fn independent(&self) -> &[usize] {
        &self.independent
    }

    /// Indices of the columns that are combinations of the independent ones.
    pub fn dependent(&self) -> &[usize] {
        &self.dependent
    }

    /// The base parameter values of a full parameter vector: `pi_b = pi_i + beta pi_d`.
    pub fn base_values(&self, parameters: &[f64]) -> DVector<f64> {
        let pi_i = DVector::from_iterator(
            self.independent.len(),
            self.independent.iter().map(|&c| parameters[c]),
        );
        let pi_d = DVector::from_iterator(
            self.dependent.len(),
            self.dependent.iter().map(|&c| parameters[c]),
        );
        pi_i + &self.beta * pi_d
    }

    /// Condition number (largest over smallest singular value) of a stacked regressor's
    /// independent columns, each scaled to unit norm: how well a motion excites the base
    /// parameters (lower is better; infinite when a base parameter is not excited).
    pub fn condition_number(&self, stacked: &DMatrix<f64>) -> f64 {
        let mut yb = select_columns(stacked, &self.independent);
        for mut c in yb.column_iter_mut() {
            let norm = c.norm();
            if norm > 0.0 {
                c /= norm;
            }
        }
        let sv = yb.singular_values();
        let (max, min) = sv
            .iter()
            .fold((0.0f64, f64::INFINITY), |(a, b), &s| (a.max(s), b.min(s)));
        if min > 0.0 {
            max / min
        } else {
            f64::INFINITY
        }
    }
}

fn select_columns(m: &DMatrix<f64>, cols: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), cols.len(), |r, c| m[(r, cols[c])])
}

/// A small deterministic generator (SplitMix64) for sampling states: no dependency, the
/// same numbers on every platform.
pub(crate) struct SplitMix(pub(crate) u64);

impl SplitMix {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}
