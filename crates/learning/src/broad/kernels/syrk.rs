//! Register-tiled products of packed blocks, `C (+)= A B^T`, for the hot loops of the
//! ridge fit (METHOD.md section 5, the normal equations): the Gram `G += A_b^T A_b` (its
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
mod tests {
    use super::*;

    use super::super::test_values as values;

    /// Checks `c[j * ldc + i] == before + sum_s A[ra + i, s] A[rb + j, s]` (samples s0..,
    /// k of them, from the column-major block `at`, leading dimension ld) where `keep(i,
    /// j)`, and `c == before` everywhere else, to 1e-13 of `sum_s |A A|`.
    #[allow(clippy::too_many_arguments)]
    fn check_product(
        c: &[f64],
        ldc: usize,
        before: f64,
        at: &[f64],
        ld: usize,
        (ra, m): (usize, usize),
        (rb, n): (usize, usize),
        (s0, k): (usize, usize),
        keep: impl Fn(usize, usize) -> bool,
        what: &str,
    ) {
        for (idx, &v) in c.iter().enumerate() {
            let (i, j) = (idx % ldc, idx / ldc);
            if i < m && j < n && keep(i, j) {
                let (mut e, mut scale) = (0.0, 0.0);
                for s in s0..s0 + k {
                    let t = at[s * ld + ra + i] * at[s * ld + rb + j];
                    e += t;
                    scale += t.abs();
                }
                let err = (v - before - e).abs();
                assert!(
                    err <= 1e-13 * scale + 1e-15,
                    "{what}: C[{i}, {j}] = {v}, expected {} (error {err:e}, scale {scale:e})",
                    before + e
                );
            } else {
                assert_eq!(v, before, "{what}: C[{i}, {j}] must be untouched");
            }
        }
    }

    type Product = fn(&mut [f64], usize, &Slab, &Slab, Store);

    /// Both entry points: the dispatching one (the AVX2 + FMA kernel where the CPU has
    /// it) and the portable loops.
    fn paths() -> [(&'static str, Product); 2] {
        [("gemm_nt", gemm_nt), ("gemm_nt_portable", gemm_nt_portable)]
    }

    #[test]
    fn lower_triangle_matches_naive_on_awkward_sizes() {
        for &(p, k) in &[
            (1, 1),
            (2, 3),
            (5, 1),
            (7, 4),
            (8, 9),
            (13, 17),
            (24, 5),
            (25, 2),
            (51, 33),
            (100, 1),
            (203, 300),
        ] {
            // Two samples before the packed range, a leading dimension above P.
            let (ld, s0) = (p + 3, 2);
            let at = values(ld * (s0 + k), (p * 1000 + k) as u64);
            let mut slab = Slab::new(p, k);
            slab.pack(&at, ld, 0, s0, k);
            for (what, f) in paths() {
                let ldc = p + 2;
                let mut c = vec![0.25; ldc * p];
                f(&mut c, ldc, &slab, &slab, Store::AddLower);
                let what = format!("{what} lower P {p} k {k}");
                check_product(
                    &c,
                    ldc,
                    0.25,
                    &at,
                    ld,
                    (0, p),
                    (0, p),
                    (s0, k),
                    |i, j| i >= j,
                    &what,
                );
            }
        }
    }

    #[test]
    fn cross_product_matches_naive_on_awkward_sizes() {
        // A: all P rows; B: the last kn rows (a node growth's new columns).
        for &(p, kn, k) in &[
            (1, 1, 1),
            (9, 1, 5),
            (13, 6, 7),
            (30, 7, 1),
            (61, 13, 40),
            (150, 25, 257),
        ] {
            let ld = p;
            let at = values(ld * k, (p * 7 + kn * 3 + k) as u64);
            let mut all = Slab::new(p, k);
            let mut new = Slab::new(kn, k);
            all.pack(&at, ld, 0, 0, k);
            new.pack(&at, ld, p - kn, 0, k);
            for (what, f) in paths() {
                let ldc = p + 1;
                let mut c = vec![-1.5; ldc * kn];
                f(&mut c, ldc, &all, &new, Store::Add);
                let what = format!("{what} cross P {p} new {kn} k {k}");
                check_product(
                    &c,
                    ldc,
                    -1.5,
                    &at,
                    ld,
                    (0, p),
                    (p - kn, kn),
                    (0, k),
                    |_, _| true,
                    &what,
                );
            }
        }
    }

    #[test]
    fn a_slab_is_reused_with_fewer_samples() {
        let (p, cap) = (37, 64);
        let at = values(p * 100, 3);
        let mut slab = Slab::new(p, cap);
        slab.pack(&at, p, 0, 0, cap);
        // Repacked with fewer samples: the layout is compact, no stale values are read.
        slab.pack(&at, p, 0, 70, 11);
        for (what, f) in paths() {
            let mut c = vec![0.0; p * p];
            f(&mut c, p, &slab, &slab, Store::AddLower);
            check_product(
                &c,
                p,
                0.0,
                &at,
                p,
                (0, p),
                (0, p),
                (70, 11),
                |i, j| i >= j,
                what,
            );
        }
    }

    #[test]
    fn empty_operands_and_contractions() {
        let at = values(10, 1);
        let mut a = Slab::new(5, 2);
        a.pack(&at, 5, 0, 0, 0);
        let mut c = vec![1.0; 25];
        for (_, f) in paths() {
            f(&mut c, 5, &a, &a, Store::AddLower);
            f(&mut c, 5, &a, &a, Store::Add);
        }
        assert!(c.iter().all(|&v| v == 1.0));
        // An empty contraction overwrites with zeros.
        for (what, f) in paths() {
            let mut c = vec![1.0; 25];
            f(&mut c, 5, &a, &a, Store::Overwrite);
            assert!(c.iter().all(|&v| v == 0.0), "{what}");
        }
        let mut e = Slab::new(0, 2);
        e.pack(&at, 5, 0, 0, 2);
        a.pack(&at, 5, 0, 0, 2);
        for (_, f) in paths() {
            f(&mut c, 5, &a, &e, Store::Overwrite);
        }
        assert!(c.iter().all(|&v| v == 1.0));
    }

    /// `[pattern | targets]` rows and row-major operands (the distance products, scaled,
    /// overwriting C) pack and multiply like the plain block.
    #[test]
    fn targets_rows_and_overwrite_match_naive() {
        for &(p, d, k) in &[(1, 1, 1), (6, 2, 5), (29, 7, 33), (101, 3, 256)] {
            let at = values(p * k, 5 + p as u64);
            let y = values(d * k, 6 + d as u64);
            // The same matrix as one column-major block with the targets as extra rows.
            let mut aug = vec![0.0; (p + d) * k];
            for s in 0..k {
                aug[s * (p + d)..][..p].copy_from_slice(&at[s * p..][..p]);
                aug[s * (p + d) + p..][..d].copy_from_slice(&y[s * d..][..d]);
            }
            let mut slab = Slab::new(p + d, k);
            slab.pack_with_targets(&at, p, 0, k, &y, d);
            for (what, f) in paths() {
                let n = p + d;
                let mut c = vec![0.5; n * n];
                f(&mut c, n, &slab, &slab, Store::AddLower);
                let what = format!("{what} targets P {p} d {d} k {k}");
                check_product(
                    &c,
                    n,
                    0.5,
                    &aug,
                    n,
                    (0, n),
                    (0, n),
                    (0, k),
                    |i, j| i >= j,
                    &what,
                );
            }
            // Row-major operands: rows of `aug^T` (samples), contraction over the rows.
            let (m, n) = (p + d, k);
            let mut rows_a = Slab::new(k, m);
            rows_a.pack_rows(&aug, m, m, -2.0);
            let mut rows_b = Slab::new(k, m);
            rows_b.pack_rows(&aug, m, m, 1.0);
            for (what, f) in paths() {
                let mut c = vec![9.0; n * n];
                f(&mut c, n, &rows_a, &rows_b, Store::Overwrite);
                for j in 0..n {
                    for i in 0..n {
                        let (mut e, mut scale) = (0.0, 0.0);
                        for t in 0..m {
                            let v = -2.0 * aug[i * m + t] * aug[j * m + t];
                            e += v;
                            scale += v.abs();
                        }
                        let err = (c[j * n + i] - e).abs();
                        assert!(err <= 1e-13 * scale + 1e-15, "{what} rows {i} {j}: {err:e}");
                    }
                }
            }
        }
    }

    /// A slab written a few samples at a time holds exactly what one packing of the
    /// whole block holds, and `copy_rows` cuts the same rows that packing them gives
    /// (including the zero rows that pad the last panels). Compared bit for bit.
    #[test]
    fn chunked_writes_and_row_copies_equal_whole_packing() {
        for &(p, d, k, cap) in &[
            (1, 1, 1, 1),
            (6, 2, 5, 8),
            (29, 7, 33, 40),
            (103, 7, 257, 300),
        ] {
            let at = values(p * k, 11 + p as u64);
            let y = values(d * k, 12 + d as u64);
            let mut whole = Slab::new(p + d, cap);
            whole.pack_with_targets(&at, p, 0, k, &y, d);
            let mut chunked = Slab::new(p + d, cap);
            // Stale contents first: every value must be overwritten.
            chunked.pack_with_targets(&values(p * cap, 99), p, 0, cap, &values(d * cap, 98), d);
            chunked.set_len(k);
            let mut s0 = 0;
            for c in [1usize, 7, 24, 3].iter().cycle() {
                if s0 == k {
                    break;
                }
                let c = (*c).min(k - s0);
                chunked.write_chunk(&at[s0 * p..], p, s0, c, &y[s0 * d..], d);
                s0 += c;
            }
            assert_eq!(whole.data(), chunked.data(), "P {p} d {d} k {k}");
            for (row0, rows) in [(0, p + d), (p / 2, p - p / 2), (p + d - 1, 1)] {
                let mut cut = Slab::new(rows, cap);
                cut.copy_rows(&whole, row0);
                let mut aug = vec![0.0; (p + d) * k];
                for s in 0..k {
                    aug[s * (p + d)..][..p].copy_from_slice(&at[s * p..][..p]);
                    aug[s * (p + d) + p..][..d].copy_from_slice(&y[s * d..][..d]);
                }
                let mut packed = Slab::new(rows, cap);
                packed.pack(&aug, p + d, row0, 0, k);
                assert_eq!(
                    cut.data(),
                    packed.data(),
                    "rows {row0}.. of P {p} d {d} k {k}"
                );
            }
        }
    }
}
