//! Normal equations of the identification least squares, accumulated per contiguous block
//! of samples, so that every candidate setting (ridge, spring terms) and every held-out
//! block is scored without touching the samples again.

use nalgebra::{DMatrix, DVector};

use crate::algorithms::regressor::{joint_torque_regressor, PARAMETERS_PER_BODY};
use crate::data::Data;
use crate::error::DynamicsError;
use crate::identification::joint_terms::{features, JOINT_FEATURES};
use crate::identification::samples::Samples;
use crate::model::Model;

/// Samples stacked per product (rows of `W`), to multiply in blocks.
const BATCH: usize = 128;

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
    pub fn zeros(p: usize) -> Self {
        Normal {
            gram: DMatrix::zeros(p, p),
            rhs: DVector::zeros(p),
            yy: 0.0,
            rows: 0,
        }
    }

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

/// Fills `row_block` (n x columns) with the regression rows of one sample.
pub(crate) fn sample_rows(
    model: &Model,
    data: &mut Data,
    samples: &Samples,
    k: usize,
    width: f64,
    out: &mut nalgebra::DMatrixViewMut<f64>,
) -> Result<(), DynamicsError> {
    let n = model.nq();
    let (q, qd, qdd, _) = samples.row(k);
    let y = joint_torque_regressor(model, data, q, qd, qdd)?;
    out.view_mut((0, 0), (n, PARAMETERS_PER_BODY * n))
        .copy_from(y);
    out.view_mut((0, PARAMETERS_PER_BODY * n), (n, JOINT_FEATURES * n))
        .fill(0.0);
    let mut f = [0.0; JOINT_FEATURES];
    for i in 0..n {
        features(q[i], qd[i], qdd[i], width, &mut f);
        for (c, v) in f.iter().enumerate() {
            out[(i, PARAMETERS_PER_BODY * n + JOINT_FEATURES * i + c)] = *v;
        }
    }
    Ok(())
}

/// The normal equations of `blocks` contiguous stretches of `samples` (the last takes the
/// remainder), each joint's rows multiplied by its weight.
pub(crate) fn accumulate(
    model: &Model,
    samples: &Samples,
    width: f64,
    blocks: usize,
    weights: &[f64],
) -> Result<Vec<Normal>, DynamicsError> {
    let n = model.nq();
    let p = columns(n);
    let len = samples.len();
    let mut data = Data::new(model);
    let mut w = DMatrix::zeros(BATCH * n, p);
    let mut y = DVector::zeros(BATCH * n);
    let mut out = Vec::with_capacity(blocks);
    for b in 0..blocks {
        let (start, end) = (b * len / blocks, (b + 1) * len / blocks);
        let mut normal = Normal::zeros(p);
        let mut k = start;
        while k < end {
            let m = (end - k).min(BATCH);
            for s in 0..m {
                sample_rows(
                    model,
                    &mut data,
                    samples,
                    k + s,
                    width,
                    &mut w.view_mut((s * n, 0), (n, p)),
                )?;
                y.rows_mut(s * n, n).copy_from_slice(samples.row(k + s).3);
                for (i, wi) in weights.iter().enumerate() {
                    w.row_mut(s * n + i).scale_mut(*wi);
                    y[s * n + i] *= wi;
                }
            }
            let wb = w.rows(0, m * n);
            let yb = y.rows(0, m * n);
            normal.gram.gemm_tr(1.0, &wb, &wb, 1.0);
            normal.rhs.gemv_tr(1.0, &wb, &yb, 1.0);
            normal.yy += yb.norm_squared();
            normal.rows += m * n;
            k += m;
        }
        out.push(normal);
    }
    Ok(out)
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
    let sol = a.cholesky()?.solve(&rhs);
    let mut x = prior.clone();
    for (r, &c) in idx.iter().enumerate() {
        x[c] = sol[r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The normal equations of one stretch as functions of the acceleration gain `a` (the
/// regressor is affine in the acceleration: `W(a) = W_0 + a W_a`, `W_0` the rows at zero
/// acceleration) and of a shift of each joint's torque against the motion (right-hand sides
/// per joint and candidate shift): every candidate gain and delay is scored without
/// touching the samples again.
#[derive(Clone, Debug)]
pub(crate) struct NormalParts {
    g00: DMatrix<f64>,
    g0a: DMatrix<f64>,
    gaa: DMatrix<f64>,
    /// Per joint: `W_0^T y_s` and `W_a^T y_s` of that joint's rows, one column per shift.
    r0: Vec<DMatrix<f64>>,
    ra: Vec<DMatrix<f64>>,
    /// `y_s^T y_s` per joint (rows) and shift (columns).
    yy: DMatrix<f64>,
    pub rows: usize,
}

impl NormalParts {
    fn zeros(p: usize, joints: usize, shifts: usize) -> Self {
        NormalParts {
            g00: DMatrix::zeros(p, p),
            g0a: DMatrix::zeros(p, p),
            gaa: DMatrix::zeros(p, p),
            r0: vec![DMatrix::zeros(p, shifts); joints],
            ra: vec![DMatrix::zeros(p, shifts); joints],
            yy: DMatrix::zeros(joints, shifts),
            rows: 0,
        }
    }

    pub fn add(&mut self, o: &NormalParts) {
        self.g00 += &o.g00;
        self.g0a += &o.g0a;
        self.gaa += &o.gaa;
        self.r0.iter_mut().zip(&o.r0).for_each(|(a, b)| *a += b);
        self.ra.iter_mut().zip(&o.ra).for_each(|(a, b)| *a += b);
        self.yy += &o.yy;
        self.rows += o.rows;
    }

    pub fn sum(parts: &[NormalParts]) -> NormalParts {
        let mut total = parts[0].clone();
        parts[1..].iter().for_each(|p| total.add(p));
        total
    }

    /// The normal equations with acceleration gain `gain` and joint `i`'s torque shifted by
    /// the `shifts[i]`-th candidate.
    pub fn at(&self, gain: f64, shifts: &[usize]) -> Normal {
        let cross = &self.g0a + self.g0a.transpose();
        let mut rhs = DVector::zeros(self.g00.nrows());
        let mut yy = 0.0;
        for (i, &s) in shifts.iter().enumerate() {
            rhs += self.r0[i].column(s) + self.ra[i].column(s) * gain;
            yy += self.yy[(i, s)];
        }
        Normal {
            gram: &self.g00 + cross * gain + &self.gaa * (gain * gain),
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

/// [`NormalParts`] of `blocks` contiguous stretches of `samples` (the last takes the
/// remainder), each joint's rows multiplied by its weight, one right-hand side per shift
/// (in samples: positive pairs each motion sample with a later torque sample).
pub(crate) fn accumulate_parts(
    model: &Model,
    samples: &Samples,
    width: f64,
    blocks: usize,
    weights: &[f64],
    shifts: &[f64],
) -> Result<Vec<NormalParts>, DynamicsError> {
    let n = model.nq();
    let p = columns(n);
    let s_count = shifts.len();
    let len = samples.len();
    let mut data = Data::new(model);
    let mut w0 = DMatrix::zeros(BATCH * n, p);
    let mut wa = DMatrix::zeros(BATCH * n, p);
    let mut scratch = DMatrix::zeros(n, p);
    let mut y = DMatrix::zeros(BATCH * n, s_count);
    let zeros = vec![0.0; n];
    let mut out = Vec::with_capacity(blocks);
    for b in 0..blocks {
        let (start, end) = (b * len / blocks, (b + 1) * len / blocks);
        let mut parts = NormalParts::zeros(p, n, s_count);
        let mut k = start;
        while k < end {
            let m = (end - k).min(BATCH);
            for s in 0..m {
                let (q, qd, qdd, _) = samples.row(k + s);
                rows_at(
                    model,
                    &mut data,
                    q,
                    qd,
                    &zeros,
                    width,
                    &mut w0.view_mut((s * n, 0), (n, p)),
                )?;
                rows_at(
                    model,
                    &mut data,
                    q,
                    &zeros,
                    qdd,
                    width,
                    &mut wa.view_mut((s * n, 0), (n, p)),
                )?;
                rows_at(
                    model,
                    &mut data,
                    q,
                    &zeros,
                    &zeros,
                    width,
                    &mut scratch.view_mut((0, 0), (n, p)),
                )?;
                let mut block = wa.view_mut((s * n, 0), (n, p));
                block -= &scratch;
                for i in 0..n {
                    for (c, shift) in shifts.iter().enumerate() {
                        y[(s * n + i, c)] = shifted_torque(samples, k + s, i, *shift) * weights[i];
                    }
                    w0.row_mut(s * n + i).scale_mut(weights[i]);
                    wa.row_mut(s * n + i).scale_mut(weights[i]);
                }
            }
            let (w0b, wab) = (w0.rows(0, m * n), wa.rows(0, m * n));
            parts.g00.gemm_tr(1.0, &w0b, &w0b, 1.0);
            parts.g0a.gemm_tr(1.0, &w0b, &wab, 1.0);
            parts.gaa.gemm_tr(1.0, &wab, &wab, 1.0);
            // Each joint's rows on their own: its torque may be shifted differently.
            for i in 0..n {
                for s in 0..m {
                    let r = s * n + i;
                    let (w0r, war) = (w0.row(r), wa.row(r));
                    for c in 0..s_count {
                        let yv = y[(r, c)];
                        if yv != 0.0 {
                            parts.r0[i].column_mut(c).axpy(yv, &w0r.transpose(), 1.0);
                            parts.ra[i].column_mut(c).axpy(yv, &war.transpose(), 1.0);
                        }
                        parts.yy[(i, c)] += yv * yv;
                    }
                }
            }
            parts.rows += m * n;
            k += m;
        }
        out.push(parts);
    }
    Ok(out)
}

/// The regression rows of one sample `(q, qd, qdd)` into `out` (n x columns).
fn rows_at(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    width: f64,
    out: &mut nalgebra::DMatrixViewMut<f64>,
) -> Result<(), DynamicsError> {
    let n = model.nq();
    let y = joint_torque_regressor(model, data, q, qd, qdd)?;
    out.view_mut((0, 0), (n, PARAMETERS_PER_BODY * n))
        .copy_from(y);
    out.view_mut((0, PARAMETERS_PER_BODY * n), (n, JOINT_FEATURES * n))
        .fill(0.0);
    let mut f = [0.0; JOINT_FEATURES];
    for i in 0..n {
        features(q[i], qd[i], qdd[i], width, &mut f);
        for (c, v) in f.iter().enumerate() {
            out[(i, PARAMETERS_PER_BODY * n + JOINT_FEATURES * i + c)] = *v;
        }
    }
    Ok(())
}
