//! Normal equations of the identification least squares, accumulated per contiguous block
//! of samples and per joint, so that every candidate setting (joint weights, delay, ridge,
//! spring terms) and every held-out block is scored without touching the samples again.

use nalgebra::{DMatrix, DVector};

use crate::algorithms::regressor::{joint_torque_regressor, PARAMETERS_PER_BODY};
use crate::data::Data;
use crate::error::DynamicsError;
use crate::identification::cholesky::cholesky;
use crate::identification::joint_terms::{
    coulomb_features, features, COULOMB_FEATURES, JOINT_FEATURES,
};
use crate::identification::samples::Samples;
use crate::model::Model;

/// Samples stacked per product (rows of `W`), to multiply in blocks.
const BATCH: usize = 128;
/// Rows and columns of the blocks the Gram matrix is accumulated in.
const GRAM_BLOCK: usize = 32;

/// `W^T W`, `W^T y`, `y^T y` and the row count of one stretch of samples, for the columns
/// `[10 n inertial | JOINT_FEATURES per joint]`.
#[derive(Clone, Debug)]
pub(crate) struct Normal {
    pub gram: DMatrix<f64>,
    pub rhs: DVector<f64>,
    pub yy: f64,
    pub rows: usize,
}

impl Normal {
    pub fn sub(&mut self, o: &Normal) {
        self.gram -= &o.gram;
        self.rhs -= &o.rhs;
        self.yy -= o.yy;
        self.rows -= o.rows;
    }

    /// Sum of squared residuals of `x` on these rows.
    pub fn squared_error(&self, x: &DVector<f64>) -> f64 {
        (self.yy - 2.0 * x.dot(&self.rhs) + x.dot(&(&self.gram * x))).max(0.0)
    }
}

/// Number of columns for an arm of `n` joints.
pub(crate) fn columns(n: usize) -> usize {
    (PARAMETERS_PER_BODY + JOINT_FEATURES) * n
}

/// The ridge weight of a column: `ridge` for the inertial parameters (pulled toward the
/// URDF), a negligible one for the joint terms (no prior knowledge to pull toward).
pub(crate) fn ridge_weight(column: usize, columns: usize, ridge: f64) -> f64 {
    let inertial = columns / (PARAMETERS_PER_BODY + JOINT_FEATURES) * PARAMETERS_PER_BODY;
    if column < inertial {
        ridge
    } else {
        1e-9
    }
}

/// Each column's scale in the ridge penalty: its mean square on these rows, floored at
/// 1e-4 of the median over the active columns, so that a column the motion barely excites
/// is held at the prior instead of taking absurd values.
pub(crate) fn column_scales(normal: &Normal, active: &[bool]) -> Vec<f64> {
    let mut diag: Vec<f64> = (0..active.len())
        .filter(|&c| active[c])
        .map(|c| normal.gram[(c, c)])
        .collect();
    diag.sort_by(f64::total_cmp);
    let median = diag.get(diag.len() / 2).copied().unwrap_or(0.0);
    (0..active.len())
        .map(|c| normal.gram[(c, c)].max(1e-4 * median).max(1e-300))
        .collect()
}

/// The ridge-regularised normal equations reduced to the `active` columns: `(A, c, idx)`
/// with `A = G + D`, `c = b + D prior - G_inactive prior_inactive`, `D` the ridge weight
/// times each column's scale (`ridge_weight`, `column_scales`); inactive columns are held
/// at the prior.
pub(crate) fn reduced_system(
    normal: &Normal,
    active: &[bool],
    prior: &DVector<f64>,
    ridge: f64,
) -> (DMatrix<f64>, DVector<f64>, Vec<usize>) {
    let idx: Vec<usize> = (0..active.len()).filter(|&c| active[c]).collect();
    let scales = column_scales(normal, active);
    let m = idx.len();
    let mut a = DMatrix::from_fn(m, m, |r, c| normal.gram[(idx[r], idx[c])]);
    let mut rhs = DVector::from_fn(m, |r, _| normal.rhs[idx[r]]);
    for (r, &cr) in idx.iter().enumerate() {
        for c in 0..active.len() {
            if !active[c] && prior[c] != 0.0 {
                rhs[r] -= normal.gram[(cr, c)] * prior[c];
            }
        }
        let d = ridge_weight(cr, active.len(), ridge) * scales[cr];
        a[(r, r)] += d;
        rhs[r] += d * prior[cr];
    }
    (a, rhs, idx)
}

/// Ridge solution on the `active` columns, pulled toward `prior` ([`reduced_system`]);
/// inactive columns stay at the prior.
pub(crate) fn solve(
    normal: &Normal,
    active: &[bool],
    prior: &DVector<f64>,
    ridge: f64,
) -> Option<DVector<f64>> {
    let (a, rhs, idx) = reduced_system(normal, active, prior, ridge);
    let sol = cholesky(a)?.solve(&rhs);
    let mut x = prior.clone();
    for (r, &c) in idx.iter().enumerate() {
        x[c] = sol[r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Per joint, the unweighted sums of one stretch of samples over the columns that joint's
/// rows can touch (`JointSums::columns`): the Gram matrix of its rows, their products with
/// its torque at every candidate shift, and the torque's squares. Joint weights, shifts and
/// the Coulomb width are applied afterwards, so one pass over the samples serves every
/// choice: each joint's rows carry the two Coulomb features at every candidate width (the
/// first width in the joint's own block, the others after it).
#[derive(Clone, Debug)]
pub(crate) struct JointSums {
    gram: Vec<DMatrix<f64>>,
    /// Per joint: one column per shift.
    rhs: Vec<DMatrix<f64>>,
    /// Per joint (rows) and shift (columns).
    yy: DMatrix<f64>,
    samples: usize,
    /// Number of candidate Coulomb widths.
    widths: usize,
}

impl JointSums {
    /// The columns joint `i`'s rows can be non-zero in, of an arm of `n` joints: the
    /// bodies from `i` to the tip (a body loads only the joints between it and the base)
    /// and the joint's own terms.
    fn columns(i: usize, n: usize) -> impl Iterator<Item = usize> {
        let inertial = PARAMETERS_PER_BODY * n;
        (PARAMETERS_PER_BODY * i..inertial)
            .chain(inertial + JOINT_FEATURES * i..inertial + JOINT_FEATURES * (i + 1))
    }

    /// Rows of joint `i`'s sums: its columns and the Coulomb features of the widths after
    /// the first.
    fn local_count(i: usize, n: usize, widths: usize) -> usize {
        Self::columns(i, n).count() + COULOMB_FEATURES.len() * (widths - 1)
    }

    /// Where each of joint `i`'s columns (`JointSums::columns` order) is among its sums'
    /// rows, with the Coulomb features of candidate width `width`.
    fn local_rows(i: usize, n: usize, width: usize) -> Vec<usize> {
        let own = Self::columns(i, n).count();
        let first_feature = own - JOINT_FEATURES;
        (0..own)
            .map(|r| {
                match COULOMB_FEATURES
                    .iter()
                    .position(|&f| r == first_feature + f)
                {
                    Some(k) if width > 0 => own + COULOMB_FEATURES.len() * (width - 1) + k,
                    _ => r,
                }
            })
            .collect()
    }

    fn zeros(n: usize, shifts: usize, widths: usize) -> Self {
        let rows = |i: usize| Self::local_count(i, n, widths);
        JointSums {
            gram: (0..n).map(|i| DMatrix::zeros(rows(i), rows(i))).collect(),
            rhs: (0..n).map(|i| DMatrix::zeros(rows(i), shifts)).collect(),
            yy: DMatrix::zeros(n, shifts),
            samples: 0,
            widths,
        }
    }

    /// Number of candidate Coulomb widths the sums carry.
    pub fn widths(&self) -> usize {
        self.widths
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.gram.len()
    }

    pub fn sum(parts: &[JointSums]) -> JointSums {
        let mut total = parts[0].clone();
        for p in &parts[1..] {
            total
                .gram
                .iter_mut()
                .zip(&p.gram)
                .for_each(|(a, b)| *a += b);
            total.rhs.iter_mut().zip(&p.rhs).for_each(|(a, b)| *a += b);
            total.yy += &p.yy;
            total.samples += p.samples;
        }
        total
    }

    /// The normal equations' parts with joint `i`'s rows (and torque) times `weights[i]`,
    /// at the `width`-th candidate Coulomb width.
    pub fn weighted(&self, weights: &[f64], width: usize) -> NormalParts {
        let n = self.gram.len();
        let p = columns(n);
        let shifts = self.yy.ncols();
        let mut parts = NormalParts {
            gram: DMatrix::zeros(p, p),
            rhs: vec![DMatrix::zeros(p, shifts); n],
            yy: DMatrix::zeros(n, shifts),
            rows: self.samples * n,
        };
        for (i, w) in weights.iter().enumerate() {
            let w2 = w * w;
            let cols: Vec<usize> = Self::columns(i, n).collect();
            let local = Self::local_rows(i, n, width);
            for (&a, &ca) in local.iter().zip(&cols) {
                for (&b, &cb) in local.iter().zip(&cols) {
                    parts.gram[(ca, cb)] += w2 * self.gram[i][(a, b)];
                }
                for c in 0..shifts {
                    parts.rhs[i][(ca, c)] = w2 * self.rhs[i][(a, c)];
                }
            }
            for c in 0..shifts {
                parts.yy[(i, c)] = w2 * self.yy[(i, c)];
            }
        }
        parts
    }

    /// Each joint's rms residual of the solution `x` (unweighted, torques unshifted) at the
    /// `width`-th candidate Coulomb width.
    pub fn rms_errors(&self, x: &DVector<f64>, width: usize) -> Vec<f64> {
        let n = self.gram.len();
        (0..n)
            .map(|i| {
                let mut sub = DVector::zeros(self.gram[i].nrows());
                for (&r, c) in Self::local_rows(i, n, width)
                    .iter()
                    .zip(Self::columns(i, n))
                {
                    sub[r] = x[c];
                }
                let sse = self.yy[(i, 0)] - 2.0 * sub.dot(&self.rhs[i].column(0))
                    + sub.dot(&(&self.gram[i] * &sub));
                (sse.max(0.0) / self.samples.max(1) as f64).sqrt()
            })
            .collect()
    }
}

/// The normal equations of one stretch, weighted, as functions of a shift of each joint's
/// torque against the motion (right-hand sides per joint and candidate shift): every
/// candidate delay is scored without touching the samples again.
#[derive(Clone, Debug)]
pub(crate) struct NormalParts {
    gram: DMatrix<f64>,
    /// Per joint: `W^T y_s` of that joint's rows, one column per shift.
    rhs: Vec<DMatrix<f64>>,
    /// `y_s^T y_s` per joint (rows) and shift (columns).
    yy: DMatrix<f64>,
    pub rows: usize,
}

impl NormalParts {
    pub fn sum(parts: &[NormalParts]) -> NormalParts {
        let mut total = parts[0].clone();
        for p in &parts[1..] {
            total.gram += &p.gram;
            total.rhs.iter_mut().zip(&p.rhs).for_each(|(a, b)| *a += b);
            total.yy += &p.yy;
            total.rows += p.rows;
        }
        total
    }

    /// The normal equations with joint `i`'s torque shifted by the `shifts[i]`-th candidate.
    pub fn at(&self, shifts: &[usize]) -> Normal {
        let mut rhs = DVector::zeros(self.gram.nrows());
        let mut yy = 0.0;
        for (i, &s) in shifts.iter().enumerate() {
            rhs += self.rhs[i].column(s);
            yy += self.yy[(i, s)];
        }
        Normal {
            gram: self.gram.clone(),
            rhs,
            yy,
            rows: self.rows,
        }
    }
}
/// The torque of joint `i` at fractional sample `k + shift` (linear interpolation, held at
/// the recording's ends).
pub(crate) fn shifted_torque(samples: &Samples, k: usize, i: usize, shift: f64) -> f64 {
    let n = samples.dof;
    let last = samples.len() - 1;
    let at = (k as f64 + shift).clamp(0.0, last as f64);
    let k0 = at.floor() as usize;
    let k1 = (k0 + 1).min(last);
    let w = at - k0 as f64;
    samples.tau[k0 * n + i] * (1.0 - w) + samples.tau[k1 * n + i] * w
}

/// [`JointSums`] of the samples `start..end` of `samples`, one right-hand side per shift
/// (in samples: positive pairs each motion sample with a later torque sample, read across
/// the stretch's ends) and the Coulomb features at every candidate width of `widths`
/// (rad/s). One regressor per sample; each joint's rows multiplied only over the columns
/// they can touch. `spring_ranges` (per joint, or empty) are where the training motion was:
/// beyond them the spring features continue linearly, as the fitted springs do.
pub(crate) fn accumulate(
    model: &Model,
    samples: &Samples,
    widths: &[f64],
    (start, end): (usize, usize),
    shifts: &[f64],
    spring_ranges: &[Option<[f64; 2]>],
) -> Result<JointSums, DynamicsError> {
    let n = model.nq();
    let s_count = shifts.len();
    let mut data = Data::new(model);
    let cols: Vec<Vec<usize>> = (0..n).map(|i| JointSums::columns(i, n).collect()).collect();
    // Per joint, a batch of its rows (one column per sample) and of its torques.
    let mut rows: Vec<DMatrix<f64>> = (0..n)
        .map(|i| DMatrix::zeros(JointSums::local_count(i, n, widths.len()), BATCH))
        .collect();
    let mut torques = vec![DMatrix::zeros(BATCH, s_count); n];
    let mut f = [0.0; JOINT_FEATURES];
    let inertial = PARAMETERS_PER_BODY * n;
    let mut sums = JointSums::zeros(n, s_count, widths.len());
    let split_shifts: Vec<(i64, f64)> = shifts
        .iter()
        .map(|s| (s.floor() as i64, s - s.floor()))
        .collect();
    let last = samples.len() as i64 - 1;
    let mut k = start;
    while k < end {
        let m = (end - k).min(BATCH);
        for s in 0..m {
            let (q, qd, qdd, _) = samples.row(k + s);
            let y = joint_torque_regressor(model, &mut data, q, qd, qdd)?;
            for i in 0..n {
                let range = spring_ranges.get(i).copied().flatten();
                features(q[i], qd[i], qdd[i], widths[0], range, &mut f);
                let mut column = rows[i].column_mut(s);
                for (r, &c) in cols[i].iter().enumerate() {
                    column[r] = if c < inertial {
                        y[(i, c)]
                    } else {
                        f[c - inertial - JOINT_FEATURES * i]
                    };
                }
                for (w, &width) in widths.iter().enumerate().skip(1) {
                    let [a, b] = coulomb_features(qd[i], width);
                    let r = cols[i].len() + COULOMB_FEATURES.len() * (w - 1);
                    column[r] = a;
                    column[r + 1] = b;
                }
                for (c, &(whole, fraction)) in split_shifts.iter().enumerate() {
                    // Inside the recording `k + shift` splits into the same whole sample and
                    // fraction at every k: `shifted_torque`'s value without its floor.
                    let k0 = (k + s) as i64 + whole;
                    torques[i][(s, c)] = if k0 >= 0 && k0 < last {
                        let k0 = k0 as usize;
                        samples.tau[k0 * n + i] * (1.0 - fraction)
                            + samples.tau[(k0 + 1) * n + i] * fraction
                    } else {
                        shifted_torque(samples, k + s, i, shifts[c])
                    };
                }
            }
        }
        for i in 0..n {
            let batch = rows[i].columns(0, m);
            let transposed = batch.transpose();
            let y = torques[i].rows(0, m);
            // The Gram matrix is symmetric: only its blocks on and below the diagonal are
            // multiplied (the upper triangle is copied once, at the end).
            let count = batch.nrows();
            for r0 in (0..count).step_by(GRAM_BLOCK) {
                let rl = GRAM_BLOCK.min(count - r0);
                for c0 in (0..=r0).step_by(GRAM_BLOCK) {
                    let cl = GRAM_BLOCK.min(count - c0);
                    sums.gram[i].view_mut((r0, c0), (rl, cl)).gemm(
                        1.0,
                        &batch.rows(r0, rl),
                        &transposed.columns(c0, cl),
                        1.0,
                    );
                }
            }
            sums.rhs[i].gemm(1.0, &batch, &y, 1.0);
            for c in 0..s_count {
                sums.yy[(i, c)] += y.column(c).norm_squared();
            }
        }
        sums.samples += m;
        k += m;
    }
    for gram in sums.gram.iter_mut() {
        gram.fill_upper_triangle_with_lower_triangle();
    }
    Ok(sums)
}
