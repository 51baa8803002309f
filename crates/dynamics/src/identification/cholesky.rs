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
//! of them; with AVX-512 (checked at run time), eight rows of four later columns per
//! register pass. The same values bit for bit (`tests::equals_nalgebra_bit_for_bit`, every
//! kernel the CPU has), so every identification is unchanged.

use nalgebra::{Cholesky, DMatrix, Dyn};

/// `matrix.cholesky()` (only the lower triangle read, `None` when a pivot is not positive),
/// the same factor bit for bit.
pub(crate) fn cholesky(mut matrix: DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    let n = matrix.nrows();
    if matrix.ncols() != n {
        return None;
    }
    let a = matrix.as_mut_slice(); // column-major: entry (i, k) at k n + i
                                   // The same operations compiled for wider vectors when the CPU has them: separate
                                   // multiplies and adds either way (Rust never fuses them), so the same bits.
    #[cfg(target_arch = "x86_64")]
    let factored = if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU has AVX-512F (checked just above).
        unsafe { factor_avx512(a, n) }
    } else if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        unsafe { factor_avx2(a, n) }
    } else {
        factor(a, n, &Portable)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let factored = factor(a, n, &Portable);
    factored.then(|| Cholesky::pack_dirty(matrix))
}

/// [`factor`] with the AVX-512 kernel.
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn factor_avx512(a: &mut [f64], n: usize) -> bool {
    factor(a, n, &avx512::Avx512)
}

/// [`factor`] with 256-bit vectors.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn factor_avx2(a: &mut [f64], n: usize) -> bool {
    factor(a, n, &Portable)
}

/// The updates of the factorisation: `y = (-L_jk) x + y` of every element, the earlier
/// columns `k` in ascending order.
trait Kernel {
    /// Rows `j..n` of column `j` (`column`) updated by the `count` columns `first..` of
    /// `columns` (column-major, `n` rows each).
    fn column(
        &self,
        column: &mut [f64],
        columns: &[f64],
        n: usize,
        j: usize,
        first: usize,
        count: usize,
    );

    /// The `width` columns `start..` (`block`, from row 0) updated by the `count` columns
    /// `first..` of `columns`, each from its diagonal down.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn block(
        &self,
        block: &mut [f64],
        columns: &[f64],
        n: usize,
        start: usize,
        width: usize,
        first: usize,
        count: usize,
    ) {
        column_by_column(self, block, columns, n, start, width, first, count);
    }
}

/// [`Kernel::block`] one column after the other.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn column_by_column<K: Kernel + ?Sized>(
    kernel: &K,
    block: &mut [f64],
    columns: &[f64],
    n: usize,
    start: usize,
    width: usize,
    first: usize,
    count: usize,
) {
    for c in 0..width {
        let j = start + c;
        kernel.column(
            &mut block[c * n + j..c * n + n],
            columns,
            n,
            j,
            first,
            count,
        );
    }
}

/// The kernel in plain Rust (vectorised as far as the compiler's target allows).
struct Portable;

impl Kernel for Portable {
    #[inline(always)]
    fn column(
        &self,
        column: &mut [f64],
        columns: &[f64],
        n: usize,
        j: usize,
        first: usize,
        count: usize,
    ) {
        update(column, columns, n, j, first, count)
    }
}

/// The lower triangle of the column-major `n x n` matrix `a` replaced by its Cholesky
/// factor, as nalgebra does it; `false` when a pivot is not positive.
#[inline(always)]
fn factor(a: &mut [f64], n: usize, kernel: &impl Kernel) -> bool {
    // Columns in blocks of four: the earlier columns' updates of a block's columns are done
    // four earlier columns at a time, those four staying in the L1 cache for the block.
    let mut start = 0;
    while start < n {
        let width = (n - start).min(BLOCK);
        let (earlier, block) = a.split_at_mut(start * n);
        let mut k = 0;
        while k < start {
            let count = (start - k).min(BLOCK);
            kernel.block(block, earlier, n, start, width, k, count);
            k += count;
        }
        for c in 0..width {
            let j = start + c;
            let (done, rest) = block.split_at_mut(c * n);
            let column = &mut rest[j..n];
            kernel.column(column, done, n, j, 0, c);
            let diag = column[0];
            // nalgebra: a zero pivot fails, and so does one without a real square root.
            if !(diag > 0.0) {
                return false;
            }
            let denom = diag.sqrt();
            column[0] = denom;
            for y in &mut column[1..] {
                *y /= denom;
            }
        }
        start += width;
    }
    true
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

/// The kernel in AVX-512 registers, eight rows at a time and the last few masked, four
/// later columns at once where a block has them: the same multiplies and adds of each
/// element in the same order.
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::{Kernel, BLOCK};

    /// Constructed only where the CPU has AVX-512F ([`super::factor_avx512`]).
    pub(super) struct Avx512;

    /// The lanes of rows `i..` up to `len`.
    #[inline(always)]
    fn mask(len: usize, i: usize) -> __mmask8 {
        if len - i >= 8 {
            0xff
        } else {
            (1u8 << (len - i)) - 1
        }
    }

    impl Kernel for Avx512 {
        #[inline(always)]
        fn column(
            &self,
            column: &mut [f64],
            columns: &[f64],
            n: usize,
            j: usize,
            first: usize,
            count: usize,
        ) {
            let len = column.len();
            if count == 0 {
                return;
            }
            // Every stretch read below lies in `columns`.
            assert!(columns.len() >= (first + count - 1) * n + j + len);
            // SAFETY: AVX-512F (the type's contract); reads and writes within the slices
            // (checked above; masked lanes are not touched).
            unsafe {
                let y = column.as_mut_ptr();
                let below = |k: usize| columns.as_ptr().add(k * n + j);
                for k in first..first + count {
                    let c = below(k);
                    let f = _mm512_set1_pd(-*c);
                    let mut i = 0;
                    while i < len {
                        let m = mask(len, i);
                        let v = _mm512_maskz_loadu_pd(m, y.add(i));
                        let x = _mm512_maskz_loadu_pd(m, c.add(i));
                        _mm512_mask_storeu_pd(y.add(i), m, _mm512_add_pd(_mm512_mul_pd(f, x), v));
                        i += 8;
                    }
                }
            }
        }

        #[inline(always)]
        fn block(
            &self,
            block: &mut [f64],
            columns: &[f64],
            n: usize,
            start: usize,
            width: usize,
            first: usize,
            count: usize,
        ) {
            if width != BLOCK || count != BLOCK {
                super::column_by_column(self, block, columns, n, start, width, first, count);
                return;
            }
            // The triangle above row start + 4, column by column; the rows below it, which
            // every column of the block has, four columns at once.
            for c in 0..BLOCK {
                let j = start + c;
                self.column(
                    &mut block[c * n + j..c * n + start + BLOCK],
                    columns,
                    n,
                    j,
                    first,
                    count,
                );
            }
            let top = start + BLOCK;
            if top >= n {
                return;
            }
            assert!(
                block.len() >= (BLOCK - 1) * n + n && columns.len() >= (first + BLOCK - 1) * n + n
            );
            // SAFETY: AVX-512F (the type's contract); rows top..n of the columns read and
            // written (checked above; masked lanes are not touched).
            unsafe {
                let x: [*const f64; BLOCK] =
                    std::array::from_fn(|r| columns.as_ptr().add((first + r) * n));
                let y: [*mut f64; BLOCK] = std::array::from_fn(|c| block.as_mut_ptr().add(c * n));
                // -L(start + c, first + r)
                let f: [[__m512d; BLOCK]; BLOCK] = std::array::from_fn(|c| {
                    std::array::from_fn(|r| _mm512_set1_pd(-*x[r].add(start + c)))
                });
                let mut i = top;
                while i < n {
                    let m = mask(n, i);
                    let xs: [__m512d; BLOCK] =
                        std::array::from_fn(|r| _mm512_maskz_loadu_pd(m, x[r].add(i)));
                    for c in 0..BLOCK {
                        let mut v = _mm512_maskz_loadu_pd(m, y[c].add(i));
                        for r in 0..BLOCK {
                            v = _mm512_add_pd(_mm512_mul_pd(f[c][r], xs[r]), v);
                        }
                        _mm512_mask_storeu_pd(y[c].add(i), m, v);
                    }
                    i += 8;
                }
            }
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

    /// `m`'s lower triangle factored by each kernel the CPU has (`None`: a pivot failed).
    fn kernels(m: &DMatrix<f64>) -> Vec<(&'static str, Option<DMatrix<f64>>)> {
        let n = m.nrows();
        let run = |f: &dyn Fn(&mut [f64]) -> bool| {
            let mut a = m.clone();
            f(a.as_mut_slice()).then_some(a)
        };
        let mut out = vec![("portable", run(&|a| factor(a, n, &Portable)))];
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2.
                out.push(("avx2", run(&|a| unsafe { factor_avx2(a, n) })));
            }
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has AVX-512F.
                out.push(("avx512", run(&|a| unsafe { factor_avx512(a, n) })));
            }
        }
        out
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
                // Every kernel this CPU can run, not only the one `cholesky` picks.
                for (name, factored) in kernels(&m) {
                    let factored = factored.expect("SPD");
                    for c in 0..n {
                        for r in c..n {
                            assert_eq!(
                                factored[(r, c)].to_bits(),
                                want.l_dirty()[(r, c)].to_bits(),
                                "{name}: n {n}, seed {seed}, ({r}, {c})"
                            );
                        }
                    }
                }
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
            for (name, factored) in kernels(&bad) {
                assert!(factored.is_none(), "{name}");
            }
            assert!(cholesky(bad).is_none());
        }
    }
}
