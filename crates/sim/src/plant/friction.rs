//! Joint friction `F(qdot) = Fv qdot + Fc tanh(qdot / v_s)` (METHOD.md section 1), with the
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
            f += self.coulomb * (v / self.v_s).tanh();
        }
        f
    }

    /// `dF/dv` (>= 0).
    #[inline(always)]
    pub fn slope(&self, v: f64) -> f64 {
        let mut s = self.viscous;
        if self.coulomb != 0.0 {
            let t = (v / self.v_s).tanh();
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
        let t = (v / self.v_s).tanh();
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

/// `ln cosh x` without overflow.
#[inline(always)]
pub(crate) fn ln_cosh(x: f64) -> f64 {
    let a = x.abs();
    a + (-2.0 * a).exp().ln_1p() - std::f64::consts::LN_2
}
