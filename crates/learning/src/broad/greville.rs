//! The paper's pseudo-inverse (Greville) form of incremental growth, docs/method.md section 5
//! (eq. 14-16 with the typo of eq. 15 fixed). It needs the whole pattern matrix A and its
//! pseudo-inverse in memory (N x P each), so it is meant for small problems, as a
//! reference for the exact ridge route of [`BroadModel::grow`](super::BroadModel::grow),
//! and it is unregularised: W = A^+ Y.
//!
//! For each new column a (one enhancement node):
//!
//! ```text
//! d = A^+ a,   c = a - A d,
//! b^T = c^+ = c^T / (c^T c)                  if c != 0
//! b^T = (1 + d^T d)^-1 d^T A^+               if c == 0
//! A_p^+ = [A^+ - d b^T ; b^T],   W_p = [W - d b^T Y ; b^T Y]
//! ```
//!
//! k columns are added one after the other (each step is the rank-one Greville update).

use super::error::BroadError;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// A, A^+ and W = A^+ Y after a Greville update.
#[derive(Clone, Debug)]
pub struct PinvState {
    /// The grown pattern matrix A_p = [A | a_1 .. a_k], N x (P + k).
    pub a: Mat<f64>,
    /// Its pseudo-inverse A_p^+, (P + k) x N.
    pub a_pinv: Mat<f64>,
    /// The weights A_p^+ Y, (P + k) x d_out.
    pub w: Mat<f64>,
}

/// Moore-Penrose pseudo-inverse by SVD, singular values below
/// `rcond * sigma_max` treated as zero.
pub fn pseudo_inverse(a: MatRef<'_, f64>, rcond: f64) -> Result<Mat<f64>, BroadError> {
    let (n, p) = (a.nrows(), a.ncols());
    if n == 0 || p == 0 {
        return Ok(Mat::zeros(p, n));
    }
    if let Some(v) = (0..p)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .map(|ij| a[ij])
        .find(|v| !v.is_finite())
    {
        return Err(BroadError::Greville(format!(
            "non-finite entry {v} in the matrix"
        )));
    }
    let svd = a
        .thin_svd()
        .map_err(|e| BroadError::Greville(format!("SVD did not converge: {e:?}")))?;
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0f64, f64::max);
    let u = svd.U();
    let v = svd.V();
    // A^+ = V S^+ U^T.
    let mut vs = v.to_owned();
    for j in 0..s.nrows() {
        let inv = if s[j] > rcond * smax && s[j] > 0.0 {
            1.0 / s[j]
        } else {
            0.0
        };
        for i in 0..vs.nrows() {
            vs[(i, j)] *= inv;
        }
    }
    let mut out = Mat::<f64>::zeros(p, n);
    matmul(
        out.as_mut(),
        Accum::Replace,
        vs.as_ref(),
        u.transpose(),
        1.0,
        Par::Seq,
    );
    Ok(out)
}

/// Adds the columns of `new_cols` (N x k) to A one at a time with the Greville update of
/// docs/method.md section 5 (eq. 14-16). `a` (N x P), `a_pinv` (P x N) and `w` (P x d_out) are
/// the current pattern matrix, its pseudo-inverse and weights, `y` the targets (N x d_out).
/// `tol` decides `c == 0`: `||c|| <= tol * ||a_new||` (e.g. 1e-10).
pub fn greville_add_columns(
    a: MatRef<'_, f64>,
    a_pinv: MatRef<'_, f64>,
    w: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    new_cols: MatRef<'_, f64>,
    tol: f64,
) -> Result<PinvState, BroadError> {
    let (n, p) = (a.nrows(), a.ncols());
    let dim_err = |what: &str, exp: (usize, usize), got: (usize, usize)| {
        BroadError::Greville(format!(
            "{what} is {}x{}, expected {}x{}",
            got.0, got.1, exp.0, exp.1
        ))
    };
    if (a_pinv.nrows(), a_pinv.ncols()) != (p, n) {
        return Err(dim_err("A^+", (p, n), (a_pinv.nrows(), a_pinv.ncols())));
    }
    if y.nrows() != n {
        return Err(dim_err("Y", (n, y.ncols()), (y.nrows(), y.ncols())));
    }
    if (w.nrows(), w.ncols()) != (p, y.ncols()) {
        return Err(dim_err("W", (p, y.ncols()), (w.nrows(), w.ncols())));
    }
    if new_cols.nrows() != n {
        return Err(dim_err(
            "new columns",
            (n, new_cols.ncols()),
            (new_cols.nrows(), new_cols.ncols()),
        ));
    }
    if !(tol.is_finite() && tol >= 0.0) {
        return Err(BroadError::Greville(format!(
            "tolerance {tol} must be finite and >= 0"
        )));
    }
    for (name, m) in [
        ("A", a),
        ("A^+", a_pinv),
        ("W", w),
        ("Y", y),
        ("new columns", new_cols),
    ] {
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                if !m[(i, j)].is_finite() {
                    return Err(BroadError::Greville(format!(
                        "non-finite value {} in {name} at ({i}, {j})",
                        m[(i, j)]
                    )));
                }
            }
        }
    }
    let mut a_cur = a.to_owned();
    let mut pinv = a_pinv.to_owned();
    let mut w_cur = w.to_owned();
    for c_idx in 0..new_cols.ncols() {
        let col = new_cols.col(c_idx);
        let pc = a_cur.ncols();
        // d = A^+ a  (pc x 1)
        let mut d = Mat::<f64>::zeros(pc, 1);
        matmul(
            d.as_mut(),
            Accum::Replace,
            pinv.as_ref(),
            col.as_mat(),
            1.0,
            Par::Seq,
        );
        // c = a - A d  (n x 1)
        let mut c = col.as_mat().to_owned();
        matmul(
            c.as_mut(),
            Accum::Add,
            a_cur.as_ref(),
            d.as_ref(),
            -1.0,
            Par::Seq,
        );
        let c_norm2: f64 = (0..n).map(|i| c[(i, 0)] * c[(i, 0)]).sum();
        let a_norm2: f64 = (0..n).map(|i| col[i] * col[i]).sum();
        // b^T (1 x n)
        let mut bt = Mat::<f64>::zeros(1, n);
        if c_norm2.sqrt() > tol * a_norm2.sqrt() && c_norm2 > 0.0 {
            for i in 0..n {
                bt[(0, i)] = c[(i, 0)] / c_norm2;
            }
        } else {
            let dtd: f64 = (0..pc).map(|i| d[(i, 0)] * d[(i, 0)]).sum();
            matmul(
                bt.as_mut(),
                Accum::Replace,
                d.transpose(),
                pinv.as_ref(),
                1.0 / (1.0 + dtd),
                Par::Seq,
            );
        }
        // b^T Y (1 x d_out)
        let mut bty = Mat::<f64>::zeros(1, y.ncols());
        matmul(bty.as_mut(), Accum::Replace, bt.as_ref(), y, 1.0, Par::Seq);
        // A_p^+ = [A^+ - d b^T ; b^T]
        let mut new_pinv = Mat::<f64>::zeros(pc + 1, n);
        new_pinv
            .as_mut()
            .submatrix_mut(0, 0, pc, n)
            .copy_from(&pinv);
        matmul(
            new_pinv.as_mut().submatrix_mut(0, 0, pc, n),
            Accum::Add,
            d.as_ref(),
            bt.as_ref(),
            -1.0,
            Par::Seq,
        );
        new_pinv.as_mut().submatrix_mut(pc, 0, 1, n).copy_from(&bt);
        // W_p = [W - d b^T Y ; b^T Y]
        let dout = y.ncols();
        let mut new_w = Mat::<f64>::zeros(pc + 1, dout);
        new_w
            .as_mut()
            .submatrix_mut(0, 0, pc, dout)
            .copy_from(&w_cur);
        matmul(
            new_w.as_mut().submatrix_mut(0, 0, pc, dout),
            Accum::Add,
            d.as_ref(),
            bty.as_ref(),
            -1.0,
            Par::Seq,
        );
        new_w.as_mut().submatrix_mut(pc, 0, 1, dout).copy_from(&bty);
        // A_p = [A | a]
        let mut new_a = Mat::<f64>::zeros(n, pc + 1);
        new_a.as_mut().submatrix_mut(0, 0, n, pc).copy_from(&a_cur);
        new_a
            .as_mut()
            .submatrix_mut(0, pc, n, 1)
            .copy_from(col.as_mat());
        a_cur = new_a;
        pinv = new_pinv;
        w_cur = new_w;
    }
    Ok(PinvState {
        a: a_cur,
        a_pinv: pinv,
        w: w_cur,
    })
}
