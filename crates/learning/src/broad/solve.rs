//! Ridge solution of the normal equations and its Cholesky-extension update
//! (docs/method.md section 5: `W = (lambda I + A^T A)^-1 A^T Y`, grown by a block-wise update
//! of the normal equations: Schur complement, extending their Cholesky factor).
//!
//! The bias column is **not** regularised: the system is `(A^T A + lambda D) W = A^T Y`
//! with D the identity except a zero at the bias column. The intercept absorbs the mean
//! torque (gravity, offsets), which has no reason to be small; shrinking it would bias
//! every prediction. The matrix stays positive definite for lambda > 0 because the bias
//! column (all ones) is non-zero.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Accum, Mat, MatRef, Par};

/// Lower Cholesky factor L of `G + lambda D` (only G's lower triangle is read), with
/// D = I except `D[bias, bias] = 0`. `None` if not positive definite.
pub(crate) fn factor(g: MatRef<'_, f64>, lambda: f64, bias: usize, par: Par) -> Option<Mat<f64>> {
    let p = g.nrows();
    let mut m = Mat::<f64>::zeros(p, p);
    for j in 0..p {
        for i in j..p {
            m[(i, j)] = g[(i, j)];
        }
        if j != bias {
            m[(j, j)] += lambda;
        }
    }
    cholesky_lower_in_place(&mut m, par).then_some(m)
}

/// In-place lower Cholesky; zeroes the strict upper triangle. False if not positive definite.
pub(crate) fn cholesky_lower_in_place(m: &mut Mat<f64>, par: Par) -> bool {
    let p = m.nrows();
    if p == 0 {
        return true;
    }
    let mut buf = MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
        p,
        par,
        Default::default(),
    ));
    let stack = MemStack::new(&mut buf);
    let ok = llt::factor::cholesky_in_place(
        m.as_mut(),
        Default::default(),
        par,
        stack,
        Default::default(),
    )
    .is_ok();
    if !ok {
        return false;
    }
    for j in 1..p {
        for i in 0..j {
            m[(i, j)] = 0.0;
        }
    }
    // Reject factors with non-finite or tiny pivots (numerically singular).
    let mut dmax = 0.0f64;
    let mut dmin = f64::INFINITY;
    for i in 0..p {
        let v = m[(i, i)];
        if !v.is_finite() {
            return false;
        }
        dmax = dmax.max(v);
        dmin = dmin.min(v);
    }
    dmin > dmax * 1e-12
}

/// Solves `L L^T X = rhs` with the lower factor L.
pub(crate) fn solve(l: MatRef<'_, f64>, rhs: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let mut x = rhs.to_owned();
    let mut buf = MemBuffer::new(llt::solve::solve_in_place_scratch::<f64>(
        l.nrows(),
        x.ncols(),
        par,
    ));
    let stack = MemStack::new(&mut buf);
    llt::solve::solve_in_place(l, x.as_mut(), par, stack);
    x
}

/// Extends the lower factor `l11` (P x P, of `G11 + lambda D11`) to the factor of the
/// grown matrix `[[G11 + lambda D11, G21^T], [G21, G22 + lambda I]]` (the new nodes are
/// all regularised): `L21 = G21 L11^-T`, `L22 = chol(G22 + lambda I - L21 L21^T)`.
/// `new_rows` is `[G21 | G22]`, k x (P + k) (only the lower triangle of G22 is read).
/// Cost O(P^2 k) instead of O((P + k)^3) for a new factorisation.
pub(crate) fn extend_factor(
    l11: MatRef<'_, f64>,
    new_rows: MatRef<'_, f64>,
    lambda: f64,
    par: Par,
) -> Option<Mat<f64>> {
    let p = l11.nrows();
    let k = new_rows.nrows();
    let pp = p + k;
    let mut l = Mat::<f64>::zeros(pp, pp);
    l.as_mut().submatrix_mut(0, 0, p, p).copy_from(l11);
    // L21^T = L11^-1 G21^T  (P x k).
    let mut l21t = new_rows.subcols(0, p).transpose().to_owned();
    solve_lower_triangular_in_place(l11, l21t.as_mut(), par);
    l.as_mut()
        .submatrix_mut(p, 0, k, p)
        .copy_from(l21t.transpose());
    // S = G22 + lambda I - L21 L21^T (lower triangle).
    let mut s = Mat::<f64>::zeros(k, k);
    for j in 0..k {
        for i in j..k {
            s[(i, j)] = new_rows[(i, p + j)];
        }
        s[(j, j)] += lambda;
    }
    tri_matmul(
        s.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Add,
        l21t.transpose(),
        BlockStructure::Rectangular,
        l21t.as_ref(),
        BlockStructure::Rectangular,
        -1.0,
        par,
    );
    if !cholesky_lower_in_place(&mut s, par) {
        return None;
    }
    l.as_mut().submatrix_mut(p, p, k, k).copy_from(&s);
    Some(l)
}

/// `sum_o` of `||y_o - A w_o||^2` from the Gram terms, per output:
/// `y^T y - 2 w^T A^T y + w^T G w` (G lower triangle only).
pub(crate) fn sse_from_gram(
    g_lower: MatRef<'_, f64>,
    aty: MatRef<'_, f64>,
    y_sq: &[f64],
    w: MatRef<'_, f64>,
) -> Vec<f64> {
    let p = g_lower.nrows();
    // G w with G symmetric from its lower triangle.
    let mut gw = Mat::<f64>::zeros(p, w.ncols());
    for o in 0..w.ncols() {
        for j in 0..p {
            let wj = w[(j, o)];
            gw[(j, o)] += g_lower[(j, j)] * wj;
            let mut acc = 0.0;
            for i in j + 1..p {
                let gij = g_lower[(i, j)];
                gw[(i, o)] += gij * wj;
                acc += gij * w[(i, o)];
            }
            gw[(j, o)] += acc;
        }
    }
    (0..w.ncols())
        .map(|o| {
            let mut wgw = 0.0;
            let mut way = 0.0;
            for j in 0..p {
                wgw += w[(j, o)] * gw[(j, o)];
                way += w[(j, o)] * aty[(j, o)];
            }
            (y_sq[o] - 2.0 * way + wgw).max(0.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::matmul::matmul;

    fn spd(p: usize, seed: u64) -> Mat<f64> {
        let a = Mat::<f64>::from_fn(p + 5, p, |i, j| {
            (((i * 31 + j * 17 + seed as usize) % 23) as f64 - 11.0) / 7.0
                + if i == j { 2.0 } else { 0.0 }
        });
        let mut g = Mat::<f64>::zeros(p, p);
        matmul(
            g.as_mut(),
            Accum::Replace,
            a.transpose(),
            a.as_ref(),
            1.0,
            Par::Seq,
        );
        g
    }

    fn max_abs_diff(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
        let mut m = 0.0f64;
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                m = m.max((a[(i, j)] - b[(i, j)]).abs());
            }
        }
        m
    }

    #[test]
    fn factor_reads_only_the_lower_triangle_and_skips_bias() {
        let g = spd(9, 1);
        let mut garbage = g.clone();
        for j in 1..9 {
            for i in 0..j {
                garbage[(i, j)] = 1e30;
            }
        }
        let l1 = factor(g.as_ref(), 0.5, 3, Par::Seq).unwrap();
        let l2 = factor(garbage.as_ref(), 0.5, 3, Par::Seq).unwrap();
        assert_eq!(l1, l2);
        // L L^T = G + 0.5 D with D[3,3] = 0.
        let mut llt = Mat::<f64>::zeros(9, 9);
        matmul(
            llt.as_mut(),
            Accum::Replace,
            l1.as_ref(),
            l1.transpose(),
            1.0,
            Par::Seq,
        );
        let mut expect = g.clone();
        for i in 0..9 {
            if i != 3 {
                expect[(i, i)] += 0.5;
            }
        }
        assert!(max_abs_diff(llt.as_ref(), expect.as_ref()) < 1e-10);
        // Not positive definite.
        let mut neg = g.clone();
        neg[(0, 0)] = -1.0;
        assert!(factor(neg.as_ref(), 0.0, 99, Par::Seq).is_none());
    }

    #[test]
    fn extended_factor_equals_factor_of_the_grown_matrix() {
        let (p, k) = (12, 5);
        let g = spd(p + k, 2);
        let lambda = 0.3;
        let bias = 2;
        let l11 = factor(g.as_ref().submatrix(0, 0, p, p), lambda, bias, Par::Seq).unwrap();
        let rows = g.as_ref().submatrix(p, 0, k, p + k).to_owned();
        let l = extend_factor(l11.as_ref(), rows.as_ref(), lambda, Par::Seq).unwrap();
        let full = factor(g.as_ref(), lambda, bias, Par::Seq).unwrap();
        assert!(max_abs_diff(l.as_ref(), full.as_ref()) < 1e-10);
        let rhs = Mat::<f64>::from_fn(p + k, 2, |i, j| (i + 3 * j) as f64);
        let x1 = solve(l.as_ref(), rhs.as_ref(), Par::Seq);
        let x2 = solve(full.as_ref(), rhs.as_ref(), Par::Seq);
        assert!(max_abs_diff(x1.as_ref(), x2.as_ref()) < 1e-9);
    }

    #[test]
    fn sse_from_gram_matches_direct() {
        let a = Mat::<f64>::from_fn(30, 4, |i, j| ((i * 7 + j * 3) % 11) as f64 / 5.0 - 1.0);
        let y = Mat::<f64>::from_fn(30, 2, |i, j| (i as f64 * 0.1 + j as f64).sin());
        let w = Mat::<f64>::from_fn(4, 2, |i, j| 0.1 * (i as f64) - 0.2 * j as f64);
        let mut g = Mat::<f64>::zeros(4, 4);
        matmul(
            g.as_mut(),
            Accum::Replace,
            a.transpose(),
            a.as_ref(),
            1.0,
            Par::Seq,
        );
        let mut aty = Mat::<f64>::zeros(4, 2);
        matmul(
            aty.as_mut(),
            Accum::Replace,
            a.transpose(),
            y.as_ref(),
            1.0,
            Par::Seq,
        );
        let y_sq: Vec<f64> = (0..2)
            .map(|o| (0..30).map(|i| y[(i, o)] * y[(i, o)]).sum())
            .collect();
        let sse = sse_from_gram(g.as_ref(), aty.as_ref(), &y_sq, w.as_ref());
        for o in 0..2 {
            let direct: f64 = (0..30)
                .map(|i| {
                    let pred: f64 = (0..4).map(|j| a[(i, j)] * w[(j, o)]).sum();
                    (y[(i, o)] - pred).powi(2)
                })
                .sum();
            assert!((sse[o] - direct).abs() < 1e-10 * direct.max(1.0));
        }
    }
}
