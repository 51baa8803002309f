//! Register-tiled products of packed blocks, `C (+)= A B^T`, for the hot loops of the
//! ridge fit (docs/method.md section 5, the normal equations): the Gram `G += A_b^T A_b` (its
//! lower triangle; N P^2 / 2 multiply-adds, 2.5e11 at the paper's size), `A_b^T Y_b`
//! (Y packed as extra rows under the pattern), the cross terms of a node growth
//! (`A_b^T A_new`), and the `-2 U X^T` products of the Gaussian distances.
//!
//! BLIS-style: each operand is packed into a [`Slab`], panels of 4 rows with the
//! contraction index (the samples of a block) contiguous inside a panel, so that both
//! operands stream with unit stride. The AVX2 + FMA kernel keeps an 8 x 6 tile of C in
//! 12 ymm accumulators over the whole contraction (2 vector loads and 6 broadcasts per
//! 12 FMAs; 8 x 6 rather than 12 x 4 because the latter needs all 16 registers and the
//! compiler then spills an accumulator). Loop order: blocks of `MC` rows of A (L2), a
//! 6-column tile of B (L1), the 8-row tiles of A streaming from L2. Without AVX2 + FMA
//! the same products run as plain loops (the callers use faer there instead).

/// Rows per packed panel: one ymm of f64.
const PW: usize = 4;
/// Rows per register tile (2 panels).
const MR: usize = 8;
/// Columns per register tile (broadcasts).
const NR: usize = 6;
/// Rows of A per L2-resident block (multiple of `MR`): `MC * KC * 8` bytes = 384 KiB of
/// the 512 KiB L2.
const MC: usize = 96;
/// Contraction length (samples) per slab: a 6-column tile of B reads two panels,
/// `2 * KC * 32` bytes = 32 KiB (the L1 size). Every slab sweeps the whole of C once (the
/// Gram is 8.5 MB at the paper's size, beyond L2 and shared in L3 with whatever else
/// runs), so a longer contraction halves that traffic against 256; the kernel itself ran
/// at 46.0, 46.6 and 46.8 GFLOP/s with 256, 512 and 768 (one quiet core).
pub(crate) const KC: usize = 512;

/// How a product lands in C.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Store {
    /// `C += A B^T` on the lower triangle only (`i >= j`); for the Gram, where A and B are
    /// the same slab. Tiles wholly above the diagonal are skipped.
    AddLower,
    /// `C += A B^T`.
    Add,
    /// `C = A B^T`.
    Overwrite,
}

/// A packed operand: `rows` rows of a matrix with a contraction length `k`. Row `i`,
/// contraction index `s` at `(i / 4) * 4k + 4s + i % 4` from a 32-byte aligned start.
/// The panels cover whole groups of 24 rows so that every 8-row or 6-column tile reads
/// inside the slab; rows past `rows` are 0.
#[derive(Clone, Debug)]
pub(crate) struct Slab {
    buf: Vec<f64>,
    /// Offset of the aligned start in `buf`.
    off: usize,
    rows: usize,
    panels: usize,
    cap: usize,
    k: usize,
}

impl Slab {
    /// Slab for `rows` rows and a contraction length up to `kc`.
    pub(crate) fn new(rows: usize, kc: usize) -> Self {
        let panels = rows.div_ceil(24) * (24 / PW);
        let buf = vec![0.0; panels * PW * kc + PW];
        // Alignment only affects speed (the kernel uses unaligned loads).
        let off = match buf.as_ptr().align_offset(32) {
            o if o < PW => o,
            _ => 0,
        };
        Self {
            buf,
            off,
            rows,
            panels,
            cap: kc,
            k: 0,
        }
    }

    /// The largest contraction length it can hold.
    pub(crate) fn capacity(&self) -> usize {
        self.cap
    }

    /// Sets the row count, growing the buffer if needed (contents stale until packed).
    pub(crate) fn set_rows(&mut self, rows: usize) {
        let panels = rows.div_ceil(24) * (24 / PW);
        if panels * PW * self.cap + PW > self.buf.len() {
            *self = Slab::new(rows, self.cap);
        } else {
            self.rows = rows;
            self.panels = panels;
            self.k = 0;
        }
    }

    /// Packs rows `row0 .. row0 + rows` of samples `s0 .. s0 + k` of the column-major
    /// block `at` (leading dimension `ld`: sample s is `at[s * ld ..][..ld]`).
    ///
    /// # Panics
    /// If `k` exceeds the capacity or the block is too short (caller bugs).
    #[cfg(test)]
    pub(crate) fn pack(&mut self, at: &[f64], ld: usize, row0: usize, s0: usize, k: usize) {
        self.set_len(k);
        self.write_samples(at, ld, row0, s0, 0, k, &[], 0);
    }

    /// Packs `[pattern | targets]`: the first `rows - d` rows from `at` as in
    /// [`pack`](Self::pack) (from row 0), the last `d` rows from the row-major targets
    /// `y` (sample s is `y[s * d..][..d]`).
    ///
    /// # Panics
    /// If `d > rows`, `k` exceeds the capacity or a source is too short (caller bugs).
    #[cfg(test)]
    pub(crate) fn pack_with_targets(
        &mut self,
        at: &[f64],
        ld: usize,
        s0: usize,
        k: usize,
        y: &[f64],
        d: usize,
    ) {
        self.set_len(k);
        self.write_samples(at, ld, 0, s0, 0, k, y, d);
    }

    /// Sets the contraction length to `k` (contents stale until written), so that a
    /// slab can be filled a few samples at a time with [`write_chunk`](Self::write_chunk).
    ///
    /// # Panics
    /// If `k` exceeds the capacity (a caller bug).
    pub(crate) fn set_len(&mut self, k: usize) {
        assert!(k <= self.cap, "slab capacity exceeded");
        self.k = k;
    }

    /// Writes samples `dst .. dst + count` of `[pattern | targets]` as in
    /// [`pack_with_targets`](Self::pack_with_targets), from the first `count` columns of
    /// the column-major chunk `at` (leading dimension `ld`) and the first `count` rows
    /// of the row-major targets `y`. Forming a block's pattern a few samples at a time
    /// and writing each chunk at once keeps the chunk in L2 and needs no block-sized
    /// buffer beside the slab.
    ///
    /// # Panics
    /// If the samples lie beyond the length set by [`set_len`](Self::set_len), or a
    /// source is too short (caller bugs).
    pub(crate) fn write_chunk(
        &mut self,
        at: &[f64],
        ld: usize,
        dst: usize,
        count: usize,
        y: &[f64],
        d: usize,
    ) {
        assert!(dst + count <= self.k, "chunk beyond the slab's length");
        self.write_samples(at, ld, 0, 0, dst, count, y, d);
    }

    /// Samples `s0 .. s0 + count` of the sources into slab samples `dst .. dst + count`.
    #[allow(clippy::too_many_arguments)]
    fn write_samples(
        &mut self,
        at: &[f64],
        ld: usize,
        row0: usize,
        s0: usize,
        dst: usize,
        count: usize,
        y: &[f64],
        d: usize,
    ) {
        assert!(d <= self.rows, "more target rows than rows");
        let rows = self.rows;
        let n_at = rows - d;
        let k4 = PW * self.k;
        if count == 0 {
            return;
        }
        if n_at > 0 {
            assert!(row0 + n_at <= ld, "row range outside the block");
            assert!(
                (s0 + count - 1) * ld + row0 + n_at <= at.len(),
                "block too short"
            );
        }
        assert!((s0 + count) * d <= y.len(), "targets too short");
        let buf = &mut self.buf[self.off..self.off + self.panels * k4];
        // Whole panels from `at`, 8 samples at a time: each panel receives 32
        // contiguous values (whole cache lines) from 8 sequential column streams.
        let full = n_at / PW;
        const G: usize = 8;
        let mut s = 0;
        while s < count {
            let g = G.min(count - s);
            for q in 0..full {
                let out = &mut buf[q * k4 + PW * (dst + s)..][..PW * g];
                for (t, o) in out.chunks_exact_mut(PW).enumerate() {
                    o.copy_from_slice(&at[(s0 + s + t) * ld + row0 + q * PW..][..PW]);
                }
            }
            s += g;
        }
        // The rest value by value: the last rows of `at`, the targets, zeros.
        for i in full * PW..self.panels * PW {
            let out = &mut buf[(i / PW) * k4 + PW * dst + i % PW..];
            for s in 0..count {
                out[PW * s] = if i < n_at {
                    at[(s0 + s) * ld + row0 + i]
                } else if i < rows {
                    y[(s0 + s) * d + i - n_at]
                } else {
                    0.0
                };
            }
        }
    }

    /// Copies rows `row0 .. row0 + self.rows` of `src` (all its samples), e.g. the new
    /// nodes' rows of a growth out of the whole pattern's slab.
    ///
    /// # Panics
    /// If the rows lie outside `src` or its length exceeds the capacity (caller bugs).
    pub(crate) fn copy_rows(&mut self, src: &Slab, row0: usize) {
        assert!(row0 + self.rows <= src.rows, "rows outside the source slab");
        self.set_len(src.k);
        let (k, k4) = (src.k, PW * src.k);
        let from = src.data();
        let to = &mut self.buf[self.off..self.off + self.panels * k4];
        for i in 0..self.panels * PW {
            let out = &mut to[(i / PW) * k4 + i % PW..];
            if i < self.rows {
                let r = row0 + i;
                let inp = &from[(r / PW) * k4 + r % PW..];
                for s in 0..k {
                    out[PW * s] = inp[PW * s];
                }
            } else {
                for s in 0..k {
                    out[PW * s] = 0.0;
                }
            }
        }
    }

    /// Packs `scale * x` for a row-major `x` (row r is `x[r * ld..][..k]`, contraction
    /// along the row), e.g. the node centres (L x d_in) or a block's standardised inputs.
    ///
    /// # Panics
    /// If `k` exceeds the capacity or `x` is too short (caller bugs).
    pub(crate) fn pack_rows(&mut self, x: &[f64], ld: usize, k: usize, scale: f64) {
        assert!(k <= self.cap, "slab capacity exceeded");
        let k4 = PW * k;
        self.k = k;
        if k == 0 {
            return;
        }
        if self.rows > 0 {
            assert!(
                k <= ld && (self.rows - 1) * ld + k <= x.len(),
                "rows too short"
            );
        }
        let dst = &mut self.buf[self.off..self.off + self.panels * k4];
        for r in 0..self.panels * PW {
            let out = &mut dst[(r / PW) * k4 + r % PW..];
            if r < self.rows {
                for (t, &v) in x[r * ld..][..k].iter().enumerate() {
                    out[PW * t] = scale * v;
                }
            } else {
                for t in 0..k {
                    out[PW * t] = 0.0;
                }
            }
        }
    }

    /// The packed data (`panels * 4k` values).
    fn data(&self) -> &[f64] {
        &self.buf[self.off..self.off + self.panels * PW * self.k]
    }

    /// The packed data, for comparisons in other modules' tests.
    #[cfg(test)]
    pub(crate) fn data_for_tests(&self) -> &[f64] {
        self.data()
    }
}

/// True when the AVX2 + FMA kernel runs on this CPU (a cached check).
#[inline]
pub(crate) fn simd_available() -> bool {
    super::has_avx2_fma()
}

/// `C[i, j] (+)= sum_s A[i, s] B[j, s]` for `i < a.rows`, `j < b.rows`, as `store` says;
/// C column-major with leading dimension `ldc` (`C[i, j] = c[j * ldc + i]`).
///
/// Uses the AVX2 + FMA kernel when the CPU has it, else [`gemm_nt_portable`].
///
/// # Panics
/// If the slabs hold different contraction lengths or C is too small (caller bugs).
pub(crate) fn gemm_nt(c: &mut [f64], ldc: usize, a: &Slab, b: &Slab, store: Store) {
    check(c, ldc, a, b);
    #[cfg(target_arch = "x86_64")]
    if simd_available() {
        // SAFETY: the CPU supports AVX2 and FMA (checked just above), and `check` has
        // verified the sizes that `avx2::gemm_nt` requires.
        unsafe { avx2::gemm_nt(c, ldc, a, b, store) };
        return;
    }
    gemm_nt_portable(c, ldc, a, b, store);
}

/// The product of [`gemm_nt`] by plain loops over the packed slabs (any CPU); the tests
/// check both paths on every machine.
pub(crate) fn gemm_nt_portable(c: &mut [f64], ldc: usize, a: &Slab, b: &Slab, store: Store) {
    check(c, ldc, a, b);
    let k = a.k;
    let (ad, bd) = (a.data(), b.data());
    for j in 0..b.rows {
        let bp = &bd[(j / PW) * PW * k..][..PW * k];
        let i_start = if store == Store::AddLower { j } else { 0 };
        for i in i_start..a.rows {
            let ap = &ad[(i / PW) * PW * k..][..PW * k];
            let mut acc = 0.0;
            for s in 0..k {
                acc += ap[PW * s + i % PW] * bp[PW * s + j % PW];
            }
            let out = &mut c[j * ldc + i];
            *out = if store == Store::Overwrite {
                acc
            } else {
                *out + acc
            };
        }
    }
}

fn check(c: &[f64], ldc: usize, a: &Slab, b: &Slab) {
    assert_eq!(a.k, b.k, "slabs hold different contraction lengths");
    if a.rows > 0 && b.rows > 0 {
        assert!(ldc >= a.rows, "leading dimension below the row count");
        assert!(
            c.len() >= (b.rows - 1) * ldc + a.rows,
            "C is too small for the product"
        );
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Slab, Store, MC, MR, NR, PW};
    use std::arch::x86_64::*;

    /// The blocked loop of [`super::gemm_nt`].
    ///
    /// # Safety
    /// The CPU supports AVX2 and FMA; `a.k == b.k`; if both slabs have rows,
    /// `ldc >= a.rows` and `c.len() >= (b.rows - 1) * ldc + a.rows`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn gemm_nt(c: &mut [f64], ldc: usize, a: &Slab, b: &Slab, store: Store) {
        let (m, n, k) = (a.rows, b.rows, a.k);
        if m == 0 || n == 0 {
            return;
        }
        let lower = store == Store::AddLower;
        let overwrite = store == Store::Overwrite;
        let (ad, bd) = (a.data(), b.data());
        let cp = c.as_mut_ptr();
        let mut ic = 0;
        while ic < m {
            let ie = (ic + MC).min(m);
            let mut j0 = 0;
            // Lower: a column tile starting at or past the block's last row is above it.
            while j0 < n && !(lower && j0 >= ie) {
                // Columns j0 .. j0 + 6 start in panel j0 / 4 at lane 0 or 2 (j0 is even).
                let bp = bd[(j0 / PW) * PW * k..].as_ptr();
                let cols = NR.min(n - j0);
                // Lower: skip the tiles whose last row is above the tile's first column.
                let mut i0 = if lower && j0 > ic {
                    ic + (j0 - ic) / MR * MR
                } else {
                    ic
                };
                while i0 < ie {
                    let rows = MR.min(m - i0);
                    // Keep (r, c) iff i0 + r >= j0 + c, i.e. r - c >= j0 - i0.
                    let diag = if lower && i0 < j0 + NR - 1 {
                        Some(j0 as isize - i0 as isize)
                    } else {
                        None
                    };
                    let ap = ad[(i0 / PW) * PW * k..].as_ptr();
                    // SAFETY: i0 < m is a multiple of 8 and j0 < n a multiple of 6; the
                    // slabs hold whole 24-row groups of panels (`Slab::new`), so rows
                    // i0 .. i0 + 8 of A and j0 .. j0 + 6 of B are packed (zero past the
                    // last row), each panel 4k long. j0 * ldc + i0 < (n - 1) * ldc + m
                    // <= c.len(), and the tile writes c[(j0 + cc) * ldc + i0 + r] only
                    // for r < rows <= m - i0 and cc < cols <= n - j0, within the same
                    // bound.
                    unsafe {
                        let cij = cp.add(j0 * ldc + i0);
                        let t = Tile {
                            ldc,
                            rows,
                            cols,
                            diag,
                            overwrite,
                        };
                        if j0 % PW == 0 {
                            tile::<0>(k, ap, bp, cij, t)
                        } else {
                            tile::<2>(k, ap, bp, cij, t)
                        }
                    };
                    i0 += MR;
                }
                j0 += NR;
            }
            ic = ie;
        }
    }

    /// Where a tile goes: leading dimension, valid rows and columns, diagonal and mode.
    #[derive(Clone, Copy)]
    struct Tile {
        ldc: usize,
        rows: usize,
        cols: usize,
        /// `Some(d)`: keep only the entries with `r - c >= d`.
        diag: Option<isize>,
        overwrite: bool,
    }

    /// One 8 x 6 tile: `C[r, c] (+)= sum_s a[r, s] b[c, s]` for `r < t.rows`,
    /// `c < t.cols` (and `r - c >= d` with `t.diag = Some(d)`). `a` is the start of 2
    /// consecutive panels (row r = 4v + lane at `a[v * 4k + 4s + lane]`); `b` is the start
    /// of the panel holding column 0 at lane `SHIFT` (0 or 2), column c at panel offset
    /// `(SHIFT + c) / 4`, lane `(SHIFT + c) % 4`.
    ///
    /// # Safety
    /// AVX2 + FMA; `a[..8k]` and `b[..8k]` readable; `c[cc * t.ldc + r]` writable for
    /// `r < t.rows`, `cc < t.cols`.
    #[target_feature(enable = "avx2,fma")]
    unsafe fn tile<const SHIFT: usize>(
        k: usize,
        a: *const f64,
        b: *const f64,
        c: *mut f64,
        t: Tile,
    ) {
        // Offset of column cc's value for s = 0, relative to b.
        let boff = |cc: usize| ((SHIFT + cc) / PW) * PW * k + (SHIFT + cc) % PW;
        // SAFETY (whole body): every load reads a[v * 4k + 4s + 0..4] (v < 2) or
        // b[boff(cc) + 4s] (cc < 6) with s < k, inside the panels the caller guarantees;
        // the stores are limited to the rows and columns the caller guarantees writable.
        unsafe {
            let a0 = a;
            let a1 = a.add(PW * k);
            let (b0, b1, b2) = (b.add(boff(0)), b.add(boff(1)), b.add(boff(2)));
            let (b3, b4, b5) = (b.add(boff(3)), b.add(boff(4)), b.add(boff(5)));
            let z = _mm256_setzero_pd();
            let (mut c00, mut c01) = (z, z);
            let (mut c10, mut c11) = (z, z);
            let (mut c20, mut c21) = (z, z);
            let (mut c30, mut c31) = (z, z);
            let (mut c40, mut c41) = (z, z);
            let (mut c50, mut c51) = (z, z);
            for s in 0..k {
                let o = PW * s;
                let x0 = _mm256_loadu_pd(a0.add(o));
                let x1 = _mm256_loadu_pd(a1.add(o));
                let y = _mm256_broadcast_sd(&*b0.add(o));
                c00 = _mm256_fmadd_pd(x0, y, c00);
                c01 = _mm256_fmadd_pd(x1, y, c01);
                let y = _mm256_broadcast_sd(&*b1.add(o));
                c10 = _mm256_fmadd_pd(x0, y, c10);
                c11 = _mm256_fmadd_pd(x1, y, c11);
                let y = _mm256_broadcast_sd(&*b2.add(o));
                c20 = _mm256_fmadd_pd(x0, y, c20);
                c21 = _mm256_fmadd_pd(x1, y, c21);
                let y = _mm256_broadcast_sd(&*b3.add(o));
                c30 = _mm256_fmadd_pd(x0, y, c30);
                c31 = _mm256_fmadd_pd(x1, y, c31);
                let y = _mm256_broadcast_sd(&*b4.add(o));
                c40 = _mm256_fmadd_pd(x0, y, c40);
                c41 = _mm256_fmadd_pd(x1, y, c41);
                let y = _mm256_broadcast_sd(&*b5.add(o));
                c50 = _mm256_fmadd_pd(x0, y, c50);
                c51 = _mm256_fmadd_pd(x1, y, c51);
            }
            let acc = [
                [c00, c01],
                [c10, c11],
                [c20, c21],
                [c30, c31],
                [c40, c41],
                [c50, c51],
            ];
            if t.rows == MR && t.cols == NR && t.diag.is_none() {
                for (cc, col) in acc.iter().enumerate() {
                    let cp = c.add(cc * t.ldc);
                    for (v, x) in col.iter().enumerate() {
                        let p = cp.add(PW * v);
                        let x = if t.overwrite {
                            *x
                        } else {
                            _mm256_add_pd(_mm256_loadu_pd(p), *x)
                        };
                        _mm256_storeu_pd(p, x);
                    }
                }
            } else {
                let mut tmp = [0.0f64; MR * NR];
                for (cc, col) in acc.iter().enumerate() {
                    for (v, x) in col.iter().enumerate() {
                        _mm256_storeu_pd(tmp.as_mut_ptr().add(cc * MR + PW * v), *x);
                    }
                }
                let d = t.diag.unwrap_or(isize::MIN);
                for cc in 0..t.cols {
                    let cp = c.add(cc * t.ldc);
                    for r in 0..t.rows {
                        if r as isize - cc as isize >= d {
                            let v = tmp[cc * MR + r];
                            *cp.add(r) = if t.overwrite { v } else { *cp.add(r) + v };
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
