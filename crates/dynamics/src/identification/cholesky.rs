//! nalgebra's Cholesky factorisation with its own arithmetic, done faster on the
//! identification's matrices (the barrier method's Newton systems: 100-200 columns, a
//! factorisation per step, half of an identification's time with nalgebra's).
//!
//! nalgebra factors left-looking, one column at a time: column `j` (rows `j..`) is updated by
//! every earlier column `k` in ascending order, `y = (-L_jk) x + y` element by element, then
//! its diagonal is replaced by its square root and the rest divided by it. Its update runs
//! through a strided generic loop, one earlier column per pass over column `j`, each earlier
//! column read again from the L2 cache for every later one. Here the same update of each
//! element in the same order, four earlier columns per pass and four later columns per read
//! of them: the same values bit for bit (`tests::equals_nalgebra_bit_for_bit`), so every
//! identification is unchanged.

use nalgebra::{Cholesky, DMatrix, Dyn};

/// `matrix.cholesky()` (only the lower triangle read, `None` when a pivot is not positive),
/// the same factor bit for bit.
pub(crate) fn cholesky(mut matrix: DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    let n = matrix.nrows();
    if matrix.ncols() != n {
        return None;
    }
    let a = matrix.as_mut_slice(); // column-major: entry (i, k) at k n + i
                                   // Columns in blocks of four: the earlier columns' updates of a block's columns are done
                                   // four earlier columns at a time, those four staying in the L1 cache for the block.
    let mut start = 0;
    while start < n {
        let width = (n - start).min(BLOCK);
        let (earlier, block) = a.split_at_mut(start * n);
        let mut k = 0;
        while k < start {
            let count = (start - k).min(BLOCK);
            for c in 0..width {
                let j = start + c;
                let column = &mut block[c * n + j..c * n + n];
                update(column, earlier, n, j, k, count);
            }
            k += count;
        }
        for c in 0..width {
            let j = start + c;
            let (done, rest) = block.split_at_mut(c * n);
            let column = &mut rest[j..n];
            update(column, done, n, j, 0, c);
            let diag = column[0];
            // nalgebra: a zero pivot fails, and so does one without a real square root.
            if !(diag > 0.0) {
                return None;
            }
            let denom = diag.sqrt();
            column[0] = denom;
            for y in &mut column[1..] {
                *y /= denom;
            }
        }
        start += width;
    }
    Some(Cholesky::pack_dirty(matrix))
}

/// Columns per block and earlier columns per pass.
const BLOCK: usize = 4;

/// Rows `j..n` of column `j` (`column`) updated by the `count` columns `first..` of
/// `columns` (column-major, `n` rows each), in ascending order: `y = (-L_jk) x + y`.
#[inline(always)]
fn update(column: &mut [f64], columns: &[f64], n: usize, j: usize, first: usize, count: usize) {
    // Each slice exactly as long as `column`, so that the loops index without checks.
    let len = column.len();
    let below = |k: usize| &columns[k * n + j..k * n + j + len];
    if count == BLOCK {
        let (c0, c1, c2, c3) = (
            below(first),
            below(first + 1),
            below(first + 2),
            below(first + 3),
        );
        let (f0, f1, f2, f3) = (-c0[0], -c1[0], -c2[0], -c3[0]);
        for (i, y) in column.iter_mut().enumerate() {
            let mut v = f0 * c0[i] + *y;
            v = f1 * c1[i] + v;
            v = f2 * c2[i] + v;
            *y = f3 * c3[i] + v;
        }
        return;
    }
    for k in first..first + count {
        let c = below(k);
        let f = -c[0];
        for (y, x) in column.iter_mut().zip(c) {
            *y = f * x + *y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive-definite `n x n` matrix `B B^T + d I` with entries of mixed
    /// magnitude.
    fn spd(n: usize, seed: u64, d: f64) -> DMatrix<f64> {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10f64.powi((state % 7) as i32 - 3)
        };
        let b = DMatrix::from_fn(n, n, |_, _| next());
        &b * b.transpose() + DMatrix::identity(n, n) * d
    }

    fn bits(m: &DMatrix<f64>) -> Vec<u64> {
        m.iter().map(|x| x.to_bits()).collect()
    }

    /// The factor, its solves and the failures equal nalgebra's, for sizes around the
    /// four-column blocks and those of the identification.
    #[test]
    fn equals_nalgebra_bit_for_bit() {
        for n in [1, 2, 3, 4, 5, 7, 8, 9, 31, 70, 133, 160] {
            for seed in 0..4 {
                let m = spd(n, 97 * n as u64 + seed, 1e-6 * seed as f64);
                let want = m.clone().cholesky().expect("SPD");
                let got = cholesky(m.clone()).expect("SPD");
                assert_eq!(
                    bits(want.l_dirty()),
                    bits(got.l_dirty()),
                    "n {n}, seed {seed}"
                );
                let rhs = DMatrix::from_fn(n, 2, |i, j| (i as f64 + 1.0) * (j as f64 - 0.5));
                assert_eq!(bits(&want.solve(&rhs)), bits(&got.solve(&rhs)), "n {n}");
            }
        }
        // Indefinite, singular, NaN: refused by both.
        let mut m = spd(9, 3, 0.0);
        m[(5, 5)] = -1.0;
        for bad in [
            m,
            DMatrix::zeros(4, 4),
            DMatrix::from_element(3, 3, f64::NAN),
        ] {
            assert!(bad.clone().cholesky().is_none());
            assert!(cholesky(bad).is_none());
        }
    }
}
