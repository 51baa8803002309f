//! Inner loops of the broad network: the Gaussian activations, distances and dot
//! products. Each loop is written once as an `#[inline(always)]` generic body and
//! compiled twice: for the baseline target and, on x86-64, with AVX2 + FMA enabled
//! (selected at run time, the check is a cached atomic load).
//!
//! The `exp` is the crate's branch-free one ([`crate::exp`]): a fit at the paper's size
//! evaluates N * L = 450 million Gaussians (and a node growth as many again), where the
//! libm `exp` (a scalar call, about 4-10 ns each here) would cost seconds.
//!
//! The matrix products of a fit (Gram, cross terms, distances) are in [`syrk`].

pub(crate) mod syrk;

use crate::exp::exp_neg;

/// Gaussian activations below `exp(-GAUSS_FLUSH)` (about 1.7e-154) are set to 0, so that
/// the product of two activations is never subnormal: FMAs on subnormals are several
/// times slower on the x86 cores measured here (a fit's Gram slowed by ~20 % when a few
/// percent of its products were subnormal). The change to an activation is below
/// 1.7e-154 in absolute terms.
const GAUSS_FLUSH: f64 = 354.0;

/// `exp(-x)` for the Gaussian activations (`x = d^2 / eta^2 >= 0`), flushed to 0 above
/// `GAUSS_FLUSH`.
#[inline(always)]
fn gauss<const FMA: bool>(x: f64) -> f64 {
    let e = exp_neg::<FMA>(x);
    if x > GAUSS_FLUSH {
        0.0
    } else {
        e
    }
}

/// One activation from `-2 x.u` (`neg2dot`), `||x||^2` and `||u||^2`: the squared
/// distance `||x||^2 + ||u||^2 - 2 x.u`, clamped at 0 against rounding (a NaN becomes 0).
#[inline(always)]
fn gauss_from_neg2dot<const FMA: bool>(neg2dot: f64, xn: f64, un: f64, inv_eta2: f64) -> f64 {
    let d2 = xn + un + neg2dot;
    let d2 = if d2 > 0.0 { d2 } else { 0.0 };
    gauss::<FMA>(d2 * inv_eta2)
}

/// Values per chunk of the activation loops: the `exp` runs stage by stage over 16
/// lanes (four AVX2 vectors), so that four independent polynomial chains overlap. It
/// measured 1.44 ns per activation against 1.67 for an intrinsic loop over two vectors
/// and 2.15 for a plain loop with a Horner polynomial (one core, L1-resident column).
const CHUNK: usize = 16;

/// `out[j] = gauss(x[j])` for one chunk, [`gauss`] stage by stage (the same operations,
/// so the same bits).
#[inline(always)]
fn gauss_chunk<const FMA: bool>(x: &[f64; CHUNK], out: &mut [f64]) {
    let mut t = [0.0f64; CHUNK];
    let mut r = [0.0f64; CHUNK];
    let mut p = [0.0f64; CHUNK];
    for j in 0..CHUNK {
        (t[j], r[j]) = crate::exp::reduce::<FMA>(x[j]);
    }
    for j in 0..CHUNK {
        p[j] = crate::exp::poly::<FMA>(r[j]);
    }
    for (j, o) in out.iter_mut().enumerate().take(CHUNK) {
        let e = crate::exp::scale(p[j], t[j]);
        *o = if x[j] > GAUSS_FLUSH { 0.0 } else { e };
    }
}

#[inline(always)]
fn gauss_from_neg2dots_body<const FMA: bool>(
    col: &mut [f64],
    xn: f64,
    un: &[f64],
    inv_eta2: &[f64],
) {
    let n = col.len().min(un.len()).min(inv_eta2.len());
    let full = n / CHUNK * CHUNK;
    let mut x = [0.0f64; CHUNK];
    for ((c, u), w) in col[..full]
        .chunks_exact_mut(CHUNK)
        .zip(un.chunks_exact(CHUNK))
        .zip(inv_eta2.chunks_exact(CHUNK))
    {
        for j in 0..CHUNK {
            let d2 = xn + u[j] + c[j];
            x[j] = if d2 > 0.0 { d2 } else { 0.0 } * w[j];
        }
        gauss_chunk::<FMA>(&x, c);
    }
    for j in full..n {
        col[j] = gauss_from_neg2dot::<FMA>(col[j], xn, un[j], inv_eta2[j]);
    }
}

#[inline(always)]
fn gauss_from_sqdist_body<const FMA: bool>(d2: &mut [f64], inv_eta2: &[f64]) {
    let n = d2.len().min(inv_eta2.len());
    let full = n / CHUNK * CHUNK;
    let mut x = [0.0f64; CHUNK];
    for (d, w) in d2[..full]
        .chunks_exact_mut(CHUNK)
        .zip(inv_eta2.chunks_exact(CHUNK))
    {
        for j in 0..CHUNK {
            x[j] = d[j] * w[j];
        }
        gauss_chunk::<FMA>(&x, d);
    }
    for j in full..n {
        d2[j] = gauss::<FMA>(d2[j] * inv_eta2[j]);
    }
}

/// `exp(x)` of each value (`x <= 0`; positive values give 1, below `-MAX_EXPONENT` 0).
#[inline(always)]
fn exp_slice_body<const FMA: bool>(v: &mut [f64]) {
    let full = v.len() / CHUNK * CHUNK;
    let mut x = [0.0f64; CHUNK];
    let mut t = [0.0f64; CHUNK];
    let mut r = [0.0f64; CHUNK];
    for c in v[..full].chunks_exact_mut(CHUNK) {
        for j in 0..CHUNK {
            x[j] = -c[j];
            (t[j], r[j]) = crate::exp::reduce::<FMA>(x[j]);
        }
        for j in 0..CHUNK {
            let e = crate::exp::scale(crate::exp::poly::<FMA>(r[j]), t[j]);
            c[j] = if x[j] > crate::exp::MAX_EXPONENT {
                0.0
            } else {
                e
            };
        }
    }
    for e in &mut v[full..] {
        *e = exp_nonpositive::<FMA>(*e);
    }
}

/// Points per block of the block-major layout read by [`sqdist`].
const SQDIST_BLOCK: usize = 16;

/// Position of coordinate `k` of point `j` in the block-major copy of `l` points of
/// dimension `d`: the first `l / 16 * 16` points in blocks of 16, each block dimension-major
/// (`d * 16` values, coordinate `k` of its 16 points side by side), then the remaining
/// points dimension-major. [`sqdist`] reads the whole copy as one sequential stream, which
/// the hardware prefetchers follow (a plain dimension-major copy reads `d` streams `l`
/// values apart).
#[inline]
pub(crate) fn block_major_index(l: usize, d: usize, k: usize, j: usize) -> usize {
    const W: usize = SQDIST_BLOCK;
    let full = l / W * W;
    if j < full {
        (j / W) * W * d + k * W + j % W
    } else {
        full * d + k * (l - full) + (j - full)
    }
}

/// Block-major copy ([`block_major_index`]) of `l` row-major points of dimension `d`.
pub(crate) fn block_major(points: &[f64], d: usize, l: usize) -> Vec<f64> {
    let mut out = vec![0.0; d * l];
    for (j, p) in points.chunks_exact(d.max(1)).take(l).enumerate() {
        for (k, &x) in p.iter().enumerate() {
            out[block_major_index(l, d, k, j)] = x;
        }
    }
    out
}

#[inline(always)]
fn sqdist_body<const FMA: bool>(xs: &[f64], centres: &[f64], dist: &mut [f64]) {
    // Register-blocked: 16 nodes at a time stay in registers over all input dimensions.
    const W: usize = SQDIST_BLOCK;
    let l = dist.len();
    let d = xs.len();
    let centres = &centres[..d * l];
    let full = l / W * W;
    let (blocks, tail) = centres.split_at(full * d);
    for (block, out) in blocks.chunks_exact(W * d).zip(dist.chunks_exact_mut(W)) {
        let mut acc = [0.0f64; W];
        for (&x, row) in xs.iter().zip(block.chunks_exact(W)) {
            for t in 0..W {
                let e = x - row[t];
                acc[t] = if FMA {
                    e.mul_add(e, acc[t])
                } else {
                    e * e + acc[t]
                };
            }
        }
        out.copy_from_slice(&acc);
    }
    let rem = l - full;
    for (t, out) in dist[full..].iter_mut().enumerate() {
        let mut acc = 0.0;
        for (k, &x) in xs.iter().enumerate() {
            let e = x - tail[k * rem + t];
            acc = if FMA { e.mul_add(e, acc) } else { e * e + acc };
        }
        *out = acc;
    }
}

#[inline(always)]
fn dot_body<const FMA: bool>(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 16];
    let chunks = n / 16;
    for c in 0..chunks {
        let aa = &a[c * 16..c * 16 + 16];
        let bb = &b[c * 16..c * 16 + 16];
        for i in 0..16 {
            acc[i] = if FMA {
                aa[i].mul_add(bb[i], acc[i])
            } else {
                aa[i] * bb[i] + acc[i]
            };
        }
    }
    let mut s = 0.0;
    for i in chunks * 16..n {
        s += a[i] * b[i];
    }
    let mut t = [0.0f64; 4];
    for i in 0..4 {
        t[i] = (acc[i] + acc[i + 4]) + (acc[i + 8] + acc[i + 12]);
    }
    s + (t[0] + t[1]) + (t[2] + t[3])
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn gauss_from_neg2dots(col: &mut [f64], xn: f64, un: &[f64], ie: &[f64]) {
        super::gauss_from_neg2dots_body::<true>(col, xn, un, ie)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn gauss_from_sqdist(d2: &mut [f64], ie: &[f64]) {
        super::gauss_from_sqdist_body::<true>(d2, ie)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn sqdist(xs: &[f64], ct: &[f64], dist: &mut [f64]) {
        super::sqdist_body::<true>(xs, ct, dist)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn dot(a: &[f64], b: &[f64]) -> f64 {
        super::dot_body::<true>(a, b)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn exp_slice(v: &mut [f64]) {
        super::exp_slice_body::<true>(v)
    }
}

/// True when the CPU has AVX2 and FMA (std caches the detection in an atomic).
#[inline]
pub(crate) fn has_avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// `col[j] <- exp(-max(0, xn + un[j] + col[j]) * inv_eta2[j])`: turns `-2 x.u_j`
/// (from a GEMM) into the Gaussian activation of docs/method.md section 5 (0 below about
/// 1.7e-154, see `GAUSS_FLUSH`).
#[inline]
pub(crate) fn gauss_from_neg2dots(col: &mut [f64], xn: f64, un: &[f64], inv_eta2: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { avx2::gauss_from_neg2dots(col, xn, un, inv_eta2) };
    }
    gauss_from_neg2dots_body::<false>(col, xn, un, inv_eta2)
}

/// `d2[j] <- exp(-d2[j] * inv_eta2[j])` (0 below about 1.7e-154, see `GAUSS_FLUSH`).
#[inline]
pub(crate) fn gauss_from_sqdist(d2: &mut [f64], inv_eta2: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { avx2::gauss_from_sqdist(d2, inv_eta2) };
    }
    gauss_from_sqdist_body::<false>(d2, inv_eta2)
}

/// `dist[j] <- sum_k (xs[k] - c_j[k])^2` for the L = dist.len() points `c_j` stored
/// block-major ([`block_major_index`]).
#[inline]
pub(crate) fn sqdist(xs: &[f64], centres_t: &[f64], dist: &mut [f64]) {
    debug_assert!(centres_t.len() >= xs.len() * dist.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { avx2::sqdist(xs, centres_t, dist) };
    }
    sqdist_body::<false>(xs, centres_t, dist)
}

/// Dot product with 16 independent accumulators (vectorises).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { avx2::dot(a, b) };
    }
    dot_body::<false>(a, b)
}

/// `exp(x)` for `x <= 0`: positive values give 1, values below `-MAX_EXPONENT` (results
/// below the normal range) give 0.
#[inline(always)]
fn exp_nonpositive<const FMA: bool>(x: f64) -> f64 {
    let e = exp_neg::<FMA>(-x);
    if -x > crate::exp::MAX_EXPONENT {
        0.0
    } else {
        e
    }
}

/// In-place fast `exp` of a slice of non-positive values (positive values give 1, values
/// below -708 give 0). Public for benchmarking against `f64::exp` (see
/// `benches/broad_predict.rs`).
pub fn exp_nonpositive_slice(v: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { avx2::exp_slice(v) };
    }
    exp_slice_body::<false>(v)
}

/// Deterministic pseudo-random values in [-0.5, 0.5) (64-bit LCG), for the tests.
#[cfg(test)]
pub(crate) fn test_values(n: usize, seed: u64) -> Vec<f64> {
    let mut x = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    (0..n)
        .map(|_| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_rel_err<const FMA: bool>() -> f64 {
        let mut worst = 0.0f64;
        let mut x = -708.0f64;
        while x <= 0.0 {
            let e = x.exp();
            let a = exp_nonpositive::<FMA>(x);
            worst = worst.max(((a - e) / e).abs());
            x += 0.000_731_3;
        }
        for &x in &[
            0.0,
            -0.0,
            -1e-300,
            -1e-17,
            -1e-9,
            -0.346_573_590_279_972_6,
            -0.5,
            -1.0,
            -700.0,
            -707.9,
        ] {
            let e = f64::exp(x);
            worst = worst.max(((exp_nonpositive::<FMA>(x) - e) / e).abs());
        }
        worst
    }

    #[test]
    fn fast_exp_is_accurate() {
        let w = max_rel_err::<false>();
        assert!(w < 4.45e-16, "max relative error {w}");
        #[cfg(target_arch = "x86_64")]
        if has_avx2_fma() {
            let mut v: Vec<f64> = (0..100_000).map(|i| -(i as f64) * 0.007_079_3).collect();
            let reference: Vec<f64> = v.iter().map(|x| x.exp()).collect();
            exp_nonpositive_slice(&mut v);
            for (a, e) in v.iter().zip(&reference) {
                assert!(((a - e) / e).abs() < 4.45e-16, "{a} vs {e}");
            }
        }
    }

    /// The chunked activation loops (AVX2 + FMA build where the CPU has it, else the
    /// baseline build) give the bits of the one-value functions on every length (whole
    /// chunks and a tail), NaN, flushed and clamped values included.
    #[test]
    fn chunked_activation_loops_match_the_one_value_functions() {
        let fused = has_avx2_fma();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for n in [0, 1, 3, 15, 16, 17, 32, 45, 1001] {
            let mut col: Vec<f64> = test_values(n, 11).iter().map(|v| 400.0 * v).collect();
            let un: Vec<f64> = test_values(n, 12)
                .iter()
                .map(|v| 30.0 * (v + 0.5))
                .collect();
            let ie: Vec<f64> = test_values(n, 13).iter().map(|v| 2.0 * (v + 0.6)).collect();
            if n > 2 {
                col[1] = f64::NAN;
                col[2] = -1e300;
            }
            let one = |c: f64, u: f64, w: f64| match fused {
                true => gauss_from_neg2dot::<true>(c, 3.5, u, w),
                false => gauss_from_neg2dot::<false>(c, 3.5, u, w),
            };
            let expected: Vec<f64> = (0..n).map(|j| one(col[j], un[j], ie[j])).collect();
            let mut got = col.clone();
            gauss_from_neg2dots(&mut got, 3.5, &un, &ie);
            assert_eq!(bits(&got), bits(&expected), "neg2dots, n = {n}");
            assert!(n < 64 || got.contains(&0.0), "some values flushed");

            let d2: Vec<f64> = col.iter().map(|v| v.abs()).collect();
            let g = |x: f64| {
                if fused {
                    gauss::<true>(x)
                } else {
                    gauss::<false>(x)
                }
            };
            let expected: Vec<f64> = (0..n).map(|j| g(d2[j] * ie[j])).collect();
            let mut got = d2.clone();
            gauss_from_sqdist(&mut got, &ie);
            assert_eq!(bits(&got), bits(&expected), "sqdist, n = {n}");

            let v: Vec<f64> = col.iter().map(|v| -2.0 * v.abs()).collect();
            let e = |x: f64| match fused {
                true => exp_nonpositive::<true>(x),
                false => exp_nonpositive::<false>(x),
            };
            let expected: Vec<f64> = v.iter().map(|&x| e(x)).collect();
            let mut got = v.clone();
            exp_nonpositive_slice(&mut got);
            assert_eq!(bits(&got), bits(&expected), "exp slice, n = {n}");
        }
    }

    #[test]
    fn fast_exp_underflows_to_zero() {
        assert_eq!(exp_nonpositive::<false>(-709.0), 0.0);
        assert_eq!(exp_nonpositive::<false>(-1e300), 0.0);
        assert_eq!(exp_nonpositive::<false>(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive::<false>(0.0), 1.0);
        let mut v = vec![3.0, -1e5, 0.0];
        exp_nonpositive_slice(&mut v);
        assert_eq!(v, vec![1.0, 0.0, 1.0]);
    }

    #[test]
    fn dot_and_sqdist_match_naive() {
        let a: Vec<f64> = (0..1037).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..1037).map(|i| (i as f64 * 0.11).cos()).collect();
        let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        assert!((dot(&a, &b) - naive).abs() < 1e-12);
        let l = 37;
        let d = 5;
        // Row-major points; 37 = two blocks of 16 and a tail of 5.
        let pts: Vec<f64> = (0..l * d).map(|i| (i as f64 * 0.3).sin()).collect();
        let ct = block_major(&pts, d, l);
        let xs: Vec<f64> = (0..d).map(|i| i as f64 * 0.1).collect();
        let mut dist = vec![0.0; l];
        sqdist(&xs, &ct, &mut dist);
        for j in 0..l {
            let e: f64 = (0..d).map(|k| (xs[k] - pts[j * d + k]).powi(2)).sum();
            assert!((dist[j] - e).abs() < 1e-14);
            for k in 0..d {
                assert_eq!(ct[block_major_index(l, d, k, j)], pts[j * d + k]);
            }
        }
    }
}
