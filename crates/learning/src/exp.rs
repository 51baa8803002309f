//! The `exp` behind every Gaussian activation of the crate (the RBF layer of eq. 9 and
//! the broad network of docs/method.md section 5): `exp(-x)` for `x` in `[0, MAX_EXPONENT]`.
//!
//! Why not `f64::exp`: it is a scalar libm call (4-10 ns here), and a 512-node layer
//! evaluates 512 of them per control step, a broad fit 450 million. This one is
//! branch-free: Cody-Waite reduction `-x = k ln2 + r` with `|r| <= ln2 / 2`, a degree-13
//! Taylor polynomial for `e^r` (truncation below 5e-18 relative) evaluated by Estrin's
//! scheme (dependency depth 5 instead of Horner's 13, so that independent values overlap
//! in the pipeline), and the scale `2^k` written into the exponent bits. Relative error
//! below 2 ulp (4.4e-16) against `f64::exp` (tested; 4.31e-16 measured).
//!
//! The body is written once, generic over `FMA`; with `FMA = true` every `a * b + c` is
//! one rounding (`f64::mul_add`), the same bits whether a loop's vector body or its
//! scalar tail computes it. Loops vectorise it stage by stage ([`reduce`], [`poly`],
//! [`scale`]) over chunks of 16 values, so that four vectors' polynomial chains overlap.

/// Largest exponent magnitude evaluated: `exp(-708)` is about `3.3e-308`, the bottom of the
/// normal range; larger `x` are clamped to it.
pub(crate) const MAX_EXPONENT: f64 = 708.0;

const LOG2E: f64 = std::f64::consts::LOG2_E;
// fdlibm's split of ln 2 (LN2_HI has 32 trailing zero bits, so k * LN2_HI is exact for
// |k| < 2^11): 6.93147180369123816490e-01 and 1.90821492927058770002e-10.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
// 1.5 * 2^52: adding it rounds to an integer held in the low mantissa bits.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// Added to the bits of `SHIFTER + k` to give the bits of `k + 1023` (two's complement).
const BIAS: u64 = 1023u64.wrapping_sub(SHIFTER.to_bits());
/// Taylor coefficients 1/k!, k = 0..=13.
const C: [f64; 14] = [
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40320.0,
    1.0 / 362_880.0,
    1.0 / 3_628_800.0,
    1.0 / 39_916_800.0,
    1.0 / 479_001_600.0,
    1.0 / 6_227_020_800.0,
];

/// `a * b + c`: one rounding (`f64::mul_add`) in the `FMA` build, two otherwise.
#[inline(always)]
pub(crate) fn fmadd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `x` clamped to `[0, MAX_EXPONENT]`, with a NaN mapped to 0 (`f64::clamp` would keep the
/// NaN); compiles to one `max` and one `min`.
#[inline(always)]
#[allow(clippy::manual_clamp)]
fn clamp_exponent(x: f64) -> f64 {
    x.max(0.0).min(MAX_EXPONENT)
}

/// `sum_k C[k] r^k`, k = 0..=13 (`e^r` for the `r` of [`reduce`]), by Estrin's scheme.
#[inline(always)]
pub(crate) fn poly<const FMA: bool>(r: f64) -> f64 {
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let p01 = fmadd::<FMA>(C[1], r, C[0]);
    let p23 = fmadd::<FMA>(C[3], r, C[2]);
    let p45 = fmadd::<FMA>(C[5], r, C[4]);
    let p67 = fmadd::<FMA>(C[7], r, C[6]);
    let p89 = fmadd::<FMA>(C[9], r, C[8]);
    let p1011 = fmadd::<FMA>(C[11], r, C[10]);
    let p1213 = fmadd::<FMA>(C[13], r, C[12]);
    let q0 = fmadd::<FMA>(p23, r2, p01);
    let q1 = fmadd::<FMA>(p67, r2, p45);
    let q2 = fmadd::<FMA>(p1011, r2, p89);
    let t0 = fmadd::<FMA>(q1, r4, q0);
    let t1 = fmadd::<FMA>(p1213, r4, q2);
    fmadd::<FMA>(t1, r8, t0)
}

/// The reduction of `exp(-x)`: `x` clamped into `[0, MAX_EXPONENT]`, then `-x = k ln2 + r`;
/// returns `(t, r)` with `k` held in the low bits of `t` (see [`scale`]).
#[inline(always)]
pub(crate) fn reduce<const FMA: bool>(x: f64) -> (f64, f64) {
    let y = -clamp_exponent(x);
    let t = fmadd::<FMA>(y, LOG2E, SHIFTER);
    let k = t - SHIFTER;
    (t, fmadd::<FMA>(-k, LN2_LO, fmadd::<FMA>(-k, LN2_HI, y)))
}

/// `p * 2^k` for the `t` of [`reduce`] (k + 1023 is in [2, 1023] there).
#[inline(always)]
pub(crate) fn scale(p: f64, t: f64) -> f64 {
    p * f64::from_bits(t.to_bits().wrapping_add(BIAS) << 52)
}

/// `exp(-x)` for `x` in `[0, MAX_EXPONENT]`; other `x` (NaN included) are clamped into it
/// first, so the result is always finite and in `[3.3e-308, 1]`. Loops that want the
/// stages vectorised one at a time call [`reduce`], [`poly`] and [`scale`] themselves.
#[inline(always)]
pub(crate) fn exp_neg<const FMA: bool>(x: f64) -> f64 {
    let (t, r) = reduce::<FMA>(x);
    scale(poly::<FMA>(r), t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worst relative error against `f64::exp` over `[0, MAX_EXPONENT]` and some edges.
    fn max_rel_err<const FMA: bool>() -> f64 {
        let mut worst = 0.0f64;
        let mut x = 0.0f64;
        let edges: [f64; 8] = [
            0.0,
            1e-300,
            1e-17,
            1e-9,
            0.346_573_590_279_972_6,
            0.5,
            1.0,
            700.0,
        ];
        while x <= MAX_EXPONENT {
            let e = (-x).exp();
            worst = worst.max(((exp_neg::<FMA>(x) - e) / e).abs());
            x += 0.000_731_3;
        }
        for &x in &edges {
            let e = (-x).exp();
            worst = worst.max(((exp_neg::<FMA>(x) - e) / e).abs());
        }
        worst
    }

    #[test]
    fn scalar_exp_is_accurate_and_clamped() {
        // 2 ulp (4.4e-16); measured 4.31e-16 both ways.
        let (plain, fused) = (max_rel_err::<false>(), max_rel_err::<true>());
        assert!(plain < 4.45e-16 && fused < 4.45e-16, "{plain:e} {fused:e}");
        assert_eq!(exp_neg::<true>(0.0), 1.0);
        assert_eq!(exp_neg::<true>(-5.0), 1.0);
        assert_eq!(exp_neg::<true>(f64::NAN), 1.0);
        assert_eq!(exp_neg::<true>(1e300), exp_neg::<true>(MAX_EXPONENT));
        assert!(exp_neg::<true>(f64::INFINITY) > 0.0);
    }
}
