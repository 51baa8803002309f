//! Inner loops of the broad network: a vectorisable `exp` for the Gaussian activations,
//! distances and dot products. Each loop is written once as an `#[inline(always)]`
//! generic body and compiled twice: for the baseline target and, on x86-64, with
//! AVX2 + FMA enabled (selected at run time, the check is a cached atomic load).
//!
//! Why a custom `exp`: a fit at the paper's size evaluates N * L = 450 million Gaussians
//! (and a node growth as many again). The libm `exp` is a scalar call (about 4-10 ns
//! each here), which alone would cost seconds; the branch-free version below
//! auto-vectorises (4 lanes with AVX2) and is accurate to about 1 ulp (relative error
//! below 4e-16 on [-708, 0], tested against `f64::exp`).
//!
//! The matrix products of a fit (Gram, cross terms, distances) are in [`syrk`].

pub(crate) mod syrk;

/// exp(x) for x <= 0, branch-free. Cody-Waite reduction `x = k ln2 + r`, |r| <= ln2/2,
/// a degree-13 Taylor polynomial for e^r (truncation error < 5e-18 relative), and the
/// scale 2^k built from the exponent bits. Arguments below -708.39 (results below the
/// smallest normal double) return 0; arguments > 0 are not supported (callers clamp).
#[inline(always)]
pub(crate) fn exp_nonpos<const FMA: bool>(x: f64) -> f64 {
    const LOG2E: f64 = std::f64::consts::LOG2_E;
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000); // 6.93147180369123816490e-01
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76); // 1.90821492927058770002e-10
                                                               // 1.5 * 2^52: adding it rounds to an integer and leaves the integer in the low bits.
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    const MAGIC_BITS: u64 = 0x4338_0000_0000_0000;
    const MIN_ARG: f64 = -708.39;
    #[inline(always)]
    fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
        if FMA {
            a.mul_add(b, c)
        } else {
            a * b + c
        }
    }
    let xc = if x < MIN_ARG { MIN_ARG } else { x };
    let t = madd::<FMA>(xc, LOG2E, MAGIC);
    let kf = t - MAGIC;
    let r = madd::<FMA>(-kf, LN2_HI, xc);
    let r = madd::<FMA>(-kf, LN2_LO, r);
    // Horner, coefficients 1/j!, j = 13..0.
    let mut p = 1.0 / 6_227_020_800.0;
    p = madd::<FMA>(p, r, 1.0 / 479_001_600.0);
    p = madd::<FMA>(p, r, 1.0 / 39_916_800.0);
    p = madd::<FMA>(p, r, 1.0 / 3_628_800.0);
    p = madd::<FMA>(p, r, 1.0 / 362_880.0);
    p = madd::<FMA>(p, r, 1.0 / 40_320.0);
    p = madd::<FMA>(p, r, 1.0 / 5_040.0);
    p = madd::<FMA>(p, r, 1.0 / 720.0);
    p = madd::<FMA>(p, r, 1.0 / 120.0);
    p = madd::<FMA>(p, r, 1.0 / 24.0);
    p = madd::<FMA>(p, r, 1.0 / 6.0);
    p = madd::<FMA>(p, r, 0.5);
    p = madd::<FMA>(p, r, 1.0);
    p = madd::<FMA>(p, r, 1.0);
    // k + 1023 in the exponent field; t's low bits hold k (two's complement).
    let k_bits = t.to_bits().wrapping_sub(MAGIC_BITS).wrapping_add(1023);
    let scale = f64::from_bits(k_bits << 52);
    let y = p * scale;
    if x < MIN_ARG {
        0.0
    } else {
        y
    }
}

/// Gaussian activations below `exp(GAUSS_FLUSH)` (about 1.7e-154) are set to 0, so that
/// the product of two activations is never subnormal: FMAs on subnormals are several
/// times slower on the x86 cores measured here (a fit's Gram slowed by ~20 % when a few
/// percent of its products were subnormal). The change to an activation is below
/// 1.7e-154 in absolute terms.
const GAUSS_FLUSH: f64 = -354.0;

/// `exp(arg)` for the Gaussian activations (arg <= 0), flushed below `GAUSS_FLUSH`.
#[inline(always)]
fn gauss<const FMA: bool>(arg: f64) -> f64 {
    let e = exp_nonpos::<FMA>(arg);
    if arg < GAUSS_FLUSH {
        0.0
    } else {
        e
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
    let (col, un, ie) = (&mut col[..n], &un[..n], &inv_eta2[..n]);
    for j in 0..n {
        // ||x - u||^2 = ||x||^2 + ||u||^2 - 2 x.u, clamped at 0 against rounding.
        let d2 = xn + un[j] + col[j];
        let d2 = if d2 > 0.0 { d2 } else { 0.0 };
        col[j] = gauss::<FMA>(-d2 * ie[j]);
    }
}

#[inline(always)]
fn gauss_from_sqdist_body<const FMA: bool>(d2: &mut [f64], inv_eta2: &[f64]) {
    let n = d2.len().min(inv_eta2.len());
    let (d2, ie) = (&mut d2[..n], &inv_eta2[..n]);
    for j in 0..n {
        d2[j] = gauss::<FMA>(-d2[j] * ie[j]);
    }
}

#[inline(always)]
fn sqdist_body<const FMA: bool>(xs: &[f64], centres_t: &[f64], dist: &mut [f64]) {
    // Register-blocked: 16 nodes at a time stay in registers over all input dimensions.
    const W: usize = 16;
    let l = dist.len();
    let d = xs.len();
    let centres_t = &centres_t[..d * l];
    let mut j0 = 0;
    while j0 + W <= l {
        let mut acc = [0.0f64; W];
        for (k, &x) in xs.iter().enumerate() {
            let row = &centres_t[k * l + j0..k * l + j0 + W];
            for t in 0..W {
                let e = x - row[t];
                acc[t] = if FMA {
                    e.mul_add(e, acc[t])
                } else {
                    e * e + acc[t]
                };
            }
        }
        dist[j0..j0 + W].copy_from_slice(&acc);
        j0 += W;
    }
    for j in j0..l {
        let mut acc = 0.0;
        for (k, &x) in xs.iter().enumerate() {
            let e = x - centres_t[k * l + j];
            acc = if FMA { e.mul_add(e, acc) } else { e * e + acc };
        }
        dist[j] = acc;
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
        for x in v.iter_mut() {
            *x = super::exp_nonpos::<true>(if *x < 0.0 { *x } else { 0.0 });
        }
    }
}

/// True when the CPU has AVX2 and FMA (std caches the detection in an atomic).
#[inline]
fn has_avx2_fma() -> bool {
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
/// (from a GEMM) into the Gaussian activation of METHOD.md section 5 (0 below about
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

/// `dist[j] <- sum_k (xs[k] - centres_t[k * L + j])^2` with L = dist.len() and the
/// centres stored transposed (node index fastest).
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

/// In-place fast `exp` of a slice of non-positive values (positive values give 1).
/// Public for benchmarking against `f64::exp` (see `benches/broad_predict.rs`).
pub fn exp_nonpositive_slice(v: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { avx2::exp_slice(v) };
    }
    for x in v.iter_mut() {
        *x = exp_nonpos::<false>(if *x < 0.0 { *x } else { 0.0 });
    }
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
            let a = exp_nonpos::<FMA>(x);
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
            -708.3,
        ] {
            let e = f64::exp(x);
            worst = worst.max(((exp_nonpos::<FMA>(x) - e) / e).abs());
        }
        worst
    }

    #[test]
    fn fast_exp_is_accurate() {
        let w = max_rel_err::<false>();
        assert!(w < 4e-16, "max relative error {w}");
        #[cfg(target_arch = "x86_64")]
        if has_avx2_fma() {
            let mut v: Vec<f64> = (0..100_000).map(|i| -(i as f64) * 0.007_080_3).collect();
            let reference: Vec<f64> = v.iter().map(|x| x.exp()).collect();
            exp_nonpositive_slice(&mut v);
            for (a, e) in v.iter().zip(&reference) {
                assert!(((a - e) / e).abs() < 4e-16, "{a} vs {e}");
            }
        }
    }

    #[test]
    fn fast_exp_underflows_to_zero() {
        assert_eq!(exp_nonpos::<false>(-709.0), 0.0);
        assert_eq!(exp_nonpos::<false>(-1e300), 0.0);
        assert_eq!(exp_nonpos::<false>(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpos::<false>(0.0), 1.0);
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
        let ct: Vec<f64> = (0..l * d).map(|i| (i as f64 * 0.3).sin()).collect();
        let xs: Vec<f64> = (0..d).map(|i| i as f64 * 0.1).collect();
        let mut dist = vec![0.0; l];
        sqdist(&xs, &ct, &mut dist);
        for j in 0..l {
            let e: f64 = (0..d).map(|k| (xs[k] - ct[k * l + j]).powi(2)).sum();
            assert!((dist[j] - e).abs() < 1e-14);
        }
    }
}
