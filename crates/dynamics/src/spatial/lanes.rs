//! Sines and cosines of eight angles at once, for the joint placements of the CRBA.

/// Lanes of [`sin_cos_lanes`].
pub(crate) const SIN_COS_LANES: usize = 8;

/// Largest |x| reduced in the vector path of [`sin_cos_lanes`]: `k * PIO2_HI` is exact
/// while the quadrant k has at most 20 bits (PIO2_HI has 33).
const SIN_COS_REDUCED: f64 = 1.0e6;

/// `(sin x, cos x)` of eight values at once, branch-free: the quadrant `k = round(2 x / pi)`,
/// `r = x - k pi/2` in three parts (Cody and Waite), and the minimax polynomials of
/// fdlibm's kernels on [-pi/4, pi/4] (within an ulp of the libm values); |x| above
/// [`SIN_COS_REDUCED`] or non-finite go to [`f64::sin_cos`].
// The constants as published (their extra digits round to the same doubles).
#[allow(clippy::excessive_precision)]
#[inline(always)]
pub(crate) fn sin_cos_lanes(
    x: &[f64; SIN_COS_LANES],
) -> ([f64; SIN_COS_LANES], [f64; SIN_COS_LANES]) {
    const PIO2_HI: f64 = 1.570_796_326_734_125_614_17;
    const PIO2_MID: f64 = 6.077_100_506_303_965_976_6e-11;
    const PIO2_LO: f64 = 2.022_266_248_711_166_455_8e-21;
    const ROUND: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    const S: [f64; 6] = [
        -1.666_666_666_666_663_243_48e-1,
        8.333_333_333_322_489_461_24e-3,
        -1.984_126_982_985_794_931_34e-4,
        2.755_731_370_707_006_767_89e-6,
        -2.505_076_025_340_686_341_95e-8,
        1.589_690_995_211_550_102_21e-10,
    ];
    const C: [f64; 6] = [
        4.166_666_666_666_660_190_37e-2,
        -1.388_888_888_887_410_957_49e-3,
        2.480_158_728_947_672_941_78e-5,
        -2.755_731_435_139_066_330_35e-7,
        2.087_572_321_298_174_827_90e-9,
        -1.135_964_755_778_819_482_65e-11,
    ];
    // False for NaN too.
    let reducible = |v: f64| v.abs() <= SIN_COS_REDUCED;
    let mut sin = [0.0; SIN_COS_LANES];
    let mut cos = [0.0; SIN_COS_LANES];
    let mut far = false;
    for l in 0..SIN_COS_LANES {
        let v = x[l];
        far |= !reducible(v);
        let k = (v * std::f64::consts::FRAC_2_PI + ROUND) - ROUND;
        let r = ((v - k * PIO2_HI) - k * PIO2_MID) - k * PIO2_LO;
        let z = r * r;
        let ps = S[1] + z * (S[2] + z * (S[3] + z * (S[4] + z * S[5])));
        let sr = r + z * r * (S[0] + z * ps);
        let pc = z * (C[0] + z * (C[1] + z * (C[2] + z * (C[3] + z * (C[4] + z * C[5])))));
        let hz = 0.5 * z;
        let w = 1.0 - hz;
        let cr = w + (((1.0 - w) - hz) + z * pc);
        // Quadrant k mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
        let q = (k as i64 & 3) as u8;
        let (a, b) = if q & 1 == 0 { (sr, cr) } else { (cr, sr) };
        sin[l] = if q & 2 == 0 { a } else { -a };
        cos[l] = if (q + 1) & 2 == 0 { b } else { -b };
    }
    if far {
        for l in 0..SIN_COS_LANES {
            if !reducible(x[l]) {
                (sin[l], cos[l]) = x[l].sin_cos();
            }
        }
    }
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_lanes_match_libm() {
        let mut worst: f64 = 0.0;
        let mut check = |x: [f64; SIN_COS_LANES]| {
            let (s, c) = sin_cos_lanes(&x);
            for l in 0..SIN_COS_LANES {
                let (ws, wc) = x[l].sin_cos();
                if !x[l].is_finite() {
                    assert!(s[l].is_nan() && c[l].is_nan());
                    continue;
                }
                worst = worst.max((s[l] - ws).abs()).max((c[l] - wc).abs());
            }
        };
        let mut v = -40.0;
        while v < 40.0 {
            check(std::array::from_fn(|l| v + l as f64 * 1.37e-3));
            v += 0.0123;
        }
        // Quadrant boundaries, tiny, large (vector path) and far (libm) values.
        let pio2 = std::f64::consts::FRAC_PI_2;
        check([
            0.0,
            -0.0,
            1e-300,
            pio2,
            -pio2,
            3.0 * pio2,
            1e5 + 0.3,
            -9.9e5,
        ]);
        check([
            2e6,
            -3e9,
            1e300,
            f64::NAN,
            f64::INFINITY,
            7.0,
            100.0 * pio2,
            1e-9,
        ]);
        assert!(worst < 4e-16, "largest difference to libm {worst:e}");
    }
}
