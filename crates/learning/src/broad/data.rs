//! Data views and input standardisation (docs/method.md section 5: the input
//! X = [q, q', q''] is standardised with the mean and spread of the training data).

use super::error::BroadError;
use serde::{Deserialize, Serialize};

/// A borrowed data set: `n_samples` rows of `d_in` inputs and `d_out` targets, both
/// row-major (`inputs[i * d_in + k]` is input column `k` of sample `i`).
///
/// For the observer of docs/method.md section 5 a row is `X = [q, q', q'']` (d_in = 3n) and the
/// target is the measured free-motion torque `tau` (d_out = n). Construction checks the
/// shapes and that every value is finite and within [`MAX_ABS_DATA_VALUE`], so the fitting
/// code never sees NaN and its sums of squares never overflow.
#[derive(Clone, Copy, Debug)]
pub struct Dataset<'a> {
    inputs: &'a [f64],
    targets: &'a [f64],
    d_in: usize,
    d_out: usize,
    n_samples: usize,
}

impl<'a> Dataset<'a> {
    /// Wraps row-major `inputs` (N x d_in) and `targets` (N x d_out).
    ///
    /// Errors: zero widths, lengths that are not multiples of the widths, different row
    /// counts, no rows, a non-finite value ([`BroadError::NonFinite`]) or one beyond
    /// [`MAX_ABS_DATA_VALUE`] ([`BroadError::OutOfRange`]); both name the row and column.
    pub fn new(
        inputs: &'a [f64],
        targets: &'a [f64],
        d_in: usize,
        d_out: usize,
    ) -> Result<Self, BroadError> {
        if d_in == 0 {
            return Err(BroadError::Dimension {
                what: "input width d_in",
                expected: 1,
                got: 0,
            });
        }
        if d_out == 0 {
            return Err(BroadError::Dimension {
                what: "output width d_out",
                expected: 1,
                got: 0,
            });
        }
        if !inputs.len().is_multiple_of(d_in) {
            return Err(BroadError::Dimension {
                what: "input array length (multiple of d_in)",
                expected: (inputs.len() / d_in + 1) * d_in,
                got: inputs.len(),
            });
        }
        if !targets.len().is_multiple_of(d_out) {
            return Err(BroadError::Dimension {
                what: "target array length (multiple of d_out)",
                expected: (targets.len() / d_out + 1) * d_out,
                got: targets.len(),
            });
        }
        let n_samples = inputs.len() / d_in;
        if targets.len() / d_out != n_samples {
            return Err(BroadError::Dimension {
                what: "target rows (must equal input rows)",
                expected: n_samples,
                got: targets.len() / d_out,
            });
        }
        if n_samples == 0 {
            return Err(BroadError::Empty { what: "data set" });
        }
        check_data(inputs, d_in, "inputs")?;
        check_data(targets, d_out, "targets")?;
        Ok(Self {
            inputs,
            targets,
            d_in,
            d_out,
            n_samples,
        })
    }

    /// Refuses data whose every input column is constant (its range within 1e-12 of its
    /// magnitude, the [`Standardiser`]'s guard): a recording without motion.
    pub fn check_motion(&self, what: &'static str) -> Result<(), BroadError> {
        let d = self.d_in;
        let mut rows = self.inputs.chunks_exact(d);
        let Some(first) = rows.next() else {
            return Err(BroadError::Empty { what });
        };
        let (mut lo, mut hi) = (first.to_vec(), first.to_vec());
        for r in rows {
            for ((l, h), &x) in lo.iter_mut().zip(hi.iter_mut()).zip(r) {
                *l = l.min(x);
                *h = h.max(x);
            }
        }
        let moving = lo
            .iter()
            .zip(&hi)
            .any(|(&l, &h)| h - l > 1e-12 * l.abs().max(h.abs()).max(1.0));
        if moving {
            Ok(())
        } else {
            Err(BroadError::NoMotion { what })
        }
    }

    /// Number of rows N.
    pub fn n_samples(&self) -> usize {
        self.n_samples
    }
    /// Input width d_in.
    pub fn d_in(&self) -> usize {
        self.d_in
    }
    /// Output width d_out.
    pub fn d_out(&self) -> usize {
        self.d_out
    }
    /// Row-major inputs.
    pub fn inputs(&self) -> &'a [f64] {
        self.inputs
    }
    /// Row-major targets.
    pub fn targets(&self) -> &'a [f64] {
        self.targets
    }
    /// Input row `i`.
    pub fn input_row(&self, i: usize) -> &'a [f64] {
        &self.inputs[i * self.d_in..(i + 1) * self.d_in]
    }
    /// Inputs of rows `start..start + len`.
    pub(crate) fn input_rows(&self, start: usize, len: usize) -> &'a [f64] {
        &self.inputs[start * self.d_in..(start + len) * self.d_in]
    }
    /// Targets of rows `start..start + len`.
    pub(crate) fn target_rows(&self, start: usize, len: usize) -> &'a [f64] {
        &self.targets[start * self.d_out..(start + len) * self.d_out]
    }
    /// The rows `start..end` as a data set (already checked: no new checks).
    pub(crate) fn slice(&self, start: usize, end: usize) -> Dataset<'a> {
        Dataset {
            inputs: self.input_rows(start, end - start),
            targets: self.target_rows(start, end - start),
            n_samples: end - start,
            ..*self
        }
    }
}

/// Largest magnitude a data value may have: 10^12. No joint angle, velocity, acceleration
/// or torque in SI units comes near it; a value beyond it is a unit error or a corrupted
/// field, and its square, summed over the rows, would overflow the fit's sums (10^300
/// squared is infinite) and give a network of NaN.
pub const MAX_ABS_DATA_VALUE: f64 = 1e12;

/// Returns the first value that is not finite or beyond [`MAX_ABS_DATA_VALUE`] as an
/// error naming its row and column.
pub(crate) fn check_data(
    values: &[f64],
    width: usize,
    what: &'static str,
) -> Result<(), BroadError> {
    // Fast path (vectorised): `!(|v| <= limit)` also catches NaN.
    let mut ok = true;
    for chunk in values.chunks(4096) {
        let mut c = true;
        for &v in chunk {
            c &= v.abs() <= MAX_ABS_DATA_VALUE;
        }
        ok &= c;
    }
    if ok {
        return Ok(());
    }
    check_finite(values, width, what)?;
    // Finite here, so `>` is the complement of `<=`.
    match values.iter().position(|v| v.abs() > MAX_ABS_DATA_VALUE) {
        Some(idx) => Err(BroadError::OutOfRange {
            what,
            row: idx / width,
            column: idx % width,
            value: values[idx],
            limit: MAX_ABS_DATA_VALUE,
        }),
        None => Ok(()),
    }
}

/// Returns the first non-finite entry as an error naming its row and column.
pub(crate) fn check_finite(
    values: &[f64],
    width: usize,
    what: &'static str,
) -> Result<(), BroadError> {
    // Fast path: a sum of `v * 0` is NaN iff some value is NaN or infinite.
    let mut acc = 0.0f64;
    for chunk in values.chunks(4096) {
        let mut s = 0.0;
        for &v in chunk {
            s += v * 0.0;
        }
        acc += s;
    }
    if acc == 0.0 {
        return Ok(());
    }
    for (idx, &v) in values.iter().enumerate() {
        if !v.is_finite() {
            return Err(BroadError::NonFinite {
                what,
                row: idx / width,
                column: idx % width,
                value: v,
            });
        }
    }
    Ok(())
}

/// Per-column affine standardisation `x_std = (x - mean) / std` with the training
/// statistics (population standard deviation).
///
/// Guard: a column whose standard deviation is zero or below `1e-12 * max(1, |mean|)`
/// (a constant column, e.g. a joint that never moved) gets `std = 1`, so its standardised
/// value is `x - mean` (zero on the training data) instead of a division by zero.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Standardiser {
    /// Column means.
    pub mean: Vec<f64>,
    /// Column standard deviations after the guard (all > 0).
    pub std: Vec<f64>,
}

impl Standardiser {
    /// Computes the statistics of the inputs of `data` (two passes, in f64, for accuracy).
    pub fn from_data(data: &Dataset<'_>) -> Self {
        let d = data.d_in();
        let n = data.n_samples() as f64;
        let mut mean = vec![0.0; d];
        for row in data.inputs().chunks_exact(d) {
            for (m, &x) in mean.iter_mut().zip(row) {
                *m += x;
            }
        }
        for m in &mut mean {
            *m /= n;
        }
        let mut var = vec![0.0; d];
        for row in data.inputs().chunks_exact(d) {
            for ((v, &m), &x) in var.iter_mut().zip(&mean).zip(row) {
                let e = x - m;
                *v += e * e;
            }
        }
        let std = var
            .iter()
            .zip(&mean)
            .map(|(&v, &m)| {
                let s = (v / n).sqrt();
                if s > 1e-12 * m.abs().max(1.0) {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        Self { mean, std }
    }

    /// Input width.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Standardises `x` into `out` (both of length `dim()`).
    #[inline]
    pub fn apply(&self, x: &[f64], out: &mut [f64]) {
        for (((o, &x), &m), &s) in out.iter_mut().zip(x).zip(&self.mean).zip(&self.std) {
            *o = (x - m) / s;
        }
    }
}
