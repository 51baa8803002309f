//! Joint friction `F(qdot) = Fv qdot + Fc tanh(qdot / v_s)` (docs/method.md section 1), with the
//! derivative and the potential (antiderivative) the implicit velocity update needs.

/// The friction law of one joint (plus any environment damping added on that joint
/// while it is active: both are diagonal, monotone velocity-dependent torques).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// Viscous coefficient Fv (N m s/rad).
    pub viscous: f64,
    /// Coulomb level Fc (N m).
    pub coulomb: f64,
    /// Velocity scale v_s of the tanh (rad/s), > 0.
    pub v_s: f64,
}

impl Default for Friction {
    fn default() -> Self {
        Self::NONE
    }
}

impl Friction {
    /// No friction.
    pub const NONE: Friction = Friction {
        viscous: 0.0,
        coulomb: 0.0,
        v_s: 0.01,
    };

    /// Whether the law is zero.
    #[inline(always)]
    pub fn is_zero(&self) -> bool {
        self.viscous == 0.0 && self.coulomb == 0.0
    }

    /// The friction torque `F(v)` (it opposes motion: the plant subtracts it).
    #[inline(always)]
    pub fn torque(&self, v: f64) -> f64 {
        let mut f = self.viscous * v;
        if self.coulomb != 0.0 {
            f += self.coulomb * tanh(v / self.v_s);
        }
        f
    }

    /// `dF/dv` (>= 0).
    #[inline(always)]
    pub fn slope(&self, v: f64) -> f64 {
        let mut s = self.viscous;
        if self.coulomb != 0.0 {
            let t = tanh(v / self.v_s);
            s += self.coulomb / self.v_s * (1.0 - t * t);
        }
        s
    }

    /// `(F(v), dF/dv)` with one tanh.
    #[inline(always)]
    pub fn torque_and_slope(&self, v: f64) -> (f64, f64) {
        if self.coulomb == 0.0 {
            return (self.viscous * v, self.viscous);
        }
        let t = tanh(v / self.v_s);
        (
            self.viscous * v + self.coulomb * t,
            self.viscous + self.coulomb / self.v_s * (1.0 - t * t),
        )
    }

    /// The potential `P(v) = Fv v^2 / 2 + Fc v_s ln cosh(v / v_s)`, convex, `P' = F`.
    #[inline(always)]
    pub fn potential(&self, v: f64) -> f64 {
        let mut p = 0.5 * self.viscous * v * v;
        if self.coulomb != 0.0 {
            p += self.coulomb * self.v_s * ln_cosh(v / self.v_s);
        }
        p
    }
}

/// `tanh x` from one `exp` (or `exp_m1` near 0) instead of libm's `tanh`, about three
/// times cheaper; the friction law is evaluated several times per plant step. Error within
/// a few ulp (`tests::tanh_matches_std` checks 4 ulp against `f64::tanh`):
///
/// * `|x| < 0.55`: `e / (e + 2)` with `e = expm1(2 |x|)`, both accurate to an ulp, no
///   cancellation;
/// * `0.55 <= |x| < 22`: `1 - 2 / (exp(2 |x|) + 1)`, the subtracted term at most 0.5, so
///   its few-ulp error is at most an ulp or two of the result (>= 0.5);
/// * beyond: `1` (tanh 22 rounds to 1); the sign is copied, NaN stays NaN.
#[inline(always)]
pub(crate) fn tanh(x: f64) -> f64 {
    let a = x.abs();
    let t = if a < 0.55 {
        let e = (2.0 * a).exp_m1();
        e / (e + 2.0)
    } else if a < 22.0 {
        1.0 - 2.0 / ((2.0 * a).exp() + 1.0)
    } else if a.is_nan() {
        return x;
    } else {
        1.0
    };
    t.copysign(x)
}

/// `ln cosh x` without overflow.
#[inline(always)]
pub(crate) fn ln_cosh(x: f64) -> f64 {
    let a = x.abs();
    a + (-2.0 * a).exp().ln_1p() - std::f64::consts::LN_2
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let (ia, ib) = (a.to_bits() as i64, b.to_bits() as i64);
        if (ia < 0) != (ib < 0) {
            return u64::MAX;
        }
        (ia - ib).unsigned_abs()
    }

    #[test]
    fn tanh_matches_std() {
        let mut worst = 0;
        let mut x = 1e-300_f64;
        while x < 40.0 {
            for v in [x, -x, x * 1.000_123_4, 0.55, -0.55, 22.0, 21.999] {
                let (f, s) = (tanh(v), v.tanh());
                assert!(ulps(f, s) <= 4, "tanh({v}): {f} vs {s}");
                worst = worst.max(ulps(f, s));
            }
            x *= 1.001;
        }
        assert!(worst <= 4);
        assert_eq!(tanh(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(tanh(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(tanh(f64::INFINITY), 1.0);
        assert_eq!(tanh(f64::NEG_INFINITY), -1.0);
        assert!(tanh(f64::NAN).is_nan());
    }
}
