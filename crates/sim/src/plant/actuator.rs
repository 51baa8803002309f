//! The actuator between the controller's command and the joint: the deadzone of docs/method.md
//! eq. 17 (typo fixed) followed by the effort-limit clamp.

/// The deadzone of one joint:
///
/// ```text
/// D(tau) = m_r (tau - d_r)   if tau >= d_r
///        = 0                 if d_l < tau < d_r
///        = m_l (tau - d_l)   if tau <= d_l
/// ```
///
/// Continuous (zero at both breakpoints) and non-decreasing. `d_l = d_r = 0` with unit
/// slopes is the identity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deadzone {
    /// Left breakpoint d_l (<= 0).
    pub d_left: f64,
    /// Right breakpoint d_r (>= 0).
    pub d_right: f64,
    /// Slope m_l for `tau <= d_l`.
    pub slope_left: f64,
    /// Slope m_r for `tau >= d_r`.
    pub slope_right: f64,
}

impl Default for Deadzone {
    fn default() -> Self {
        Self::identity()
    }
}

impl Deadzone {
    /// No deadzone: `D(tau) = tau`.
    pub const fn identity() -> Self {
        Self {
            d_left: 0.0,
            d_right: 0.0,
            slope_left: 1.0,
            slope_right: 1.0,
        }
    }

    /// A symmetric deadzone `[-d, d]` with unit slopes.
    pub fn symmetric(d: f64) -> Self {
        Self {
            d_left: -d.abs(),
            d_right: d.abs(),
            slope_left: 1.0,
            slope_right: 1.0,
        }
    }

    /// The deadzone output `D(tau)`.
    #[inline(always)]
    pub fn apply(&self, tau: f64) -> f64 {
        if tau >= self.d_right {
            self.slope_right * (tau - self.d_right)
        } else if tau <= self.d_left {
            self.slope_left * (tau - self.d_left)
        } else {
            0.0
        }
    }

    /// Whether `tau` lies strictly inside the dead band (`d_l < tau < d_r`), where the
    /// output is zero whatever the command.
    #[inline(always)]
    pub fn contains(&self, tau: f64) -> bool {
        self.d_left < tau && tau < self.d_right
    }
}

/// Clamps `value` to `[-limit, limit]` (`limit` may be infinite); returns the clamped
/// value and whether it was clamped.
#[inline(always)]
pub fn clamp_effort(value: f64, limit: f64) -> (f64, bool) {
    if value > limit {
        (limit, true)
    } else if value < -limit {
        (-limit, true)
    } else {
        (value, false)
    }
}
