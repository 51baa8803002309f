//! What a joint adds to the rigid-body torque: rotor inertia, friction, an offset and
//! springs (docs/method.md section 1, the friction term `F` of eq. 1, here identified).
//!
//! ```text
//!   tau_joint = I_a q'' + F_v q' + F_c1 tanh(q' / w) + F_c2 tanh(q' / 10 w) + tau_0
//!             + k_1 sin q + k_2 cos q + k_3 sin 2q + k_4 cos 2q
//! ```
//!
//! `tanh(q' / w)` is a smooth sign (width `w` in rad/s): Coulomb friction without the jump
//! at rest that no filter or integrator handles well; the second, ten times wider, lets
//! the friction curve bend near rest as Stribeck friction does (Gaz et al. 2019 fit a
//! sigmoid for the same reason). The spring terms, a Fourier series of order 2 in the
//! joint's own angle, stand for what a URDF does not describe (Baxter's gravity-assist
//! spring on s1, cable and hose forces). Fitted over less than half a turn of the joint,
//! they continue along their tangent beyond that range (`spring_range`), as a natural
//! spline does beyond its last knot: there the series' own continuation bends back within a
//! fraction of a turn and says nothing the recording measured.

use serde::{Deserialize, Serialize};

/// Number of per-joint features (regressor columns) of [`JointTerms`].
pub(crate) const JOINT_FEATURES: usize = 9;
/// Index of the first spring feature.
pub(crate) const FIRST_SPRING_FEATURE: usize = 5;
/// Number of spring features (`sin q, cos q, sin 2q, cos 2q`).
pub(crate) const SPRING_FEATURES: usize = JOINT_FEATURES - FIRST_SPRING_FEATURE;
/// Indices of the two Coulomb features ([`coulomb_features`]).
pub(crate) const COULOMB_FEATURES: [usize; 2] = [2, 3];
/// How much wider the second smooth sign is than the first.
const SECOND_WIDTH: f64 = 10.0;

/// The identified terms of one joint (SI units: N m, or N for a prismatic joint).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTerms {
    /// Rotor inertia reflected through the gear, `I_a` (kg m^2).
    pub armature: f64,
    /// Viscous friction `F_v` (N m s/rad).
    pub viscous: f64,
    /// Coulomb friction levels `[F_c1, F_c2]` of the smooth signs of width `w` and `10 w`
    /// (N m).
    pub coulomb: [f64; 2],
    /// Width `w` of the narrower smooth sign (rad/s).
    pub coulomb_width: f64,
    /// Constant offset `tau_0` (N m): sensor bias or a constant load.
    pub offset: f64,
    /// Spring terms `[k_1 .. k_4]` on `sin q`, `cos q`, `sin 2q`, `cos 2q` (N m).
    pub spring: [f64; 4],
    /// The positions `[lowest, highest]` the springs were fitted over (rad or m): beyond
    /// them the spring torque continues linearly with the slope it has at the nearer end.
    /// `None`: the series everywhere (joints without springs, springs fitted over half a
    /// turn or more, continuous joints, whose springs repeat every turn, and files written
    /// before it was recorded).
    #[serde(default)]
    pub spring_range: Option<[f64; 2]>,
}

impl JointTerms {
    /// The joint's torque at position `q`, velocity `qd` and acceleration `qdd`.
    #[inline]
    pub fn torque(&self, q: f64, qd: f64, qdd: f64) -> f64 {
        self.armature * qdd + self.velocity_and_position_torque(q, qd)
    }

    /// The joint's torque without the rotor inertia term: friction, offset and springs.
    #[inline]
    pub fn velocity_and_position_torque(&self, q: f64, qd: f64) -> f64 {
        let [narrow, wide] = coulomb_features(qd, self.coulomb_width);
        self.viscous * qd
            + self.coulomb[0] * narrow
            + self.coulomb[1] * wide
            + self.offset
            + self.spring_torque(q)
    }

    /// The springs' torque at position `q` (linear beyond `spring_range`).
    #[inline]
    pub fn spring_torque(&self, q: f64) -> f64 {
        let mut f = [0.0; SPRING_FEATURES];
        spring_features(q, self.spring_range, &mut f);
        self.spring.iter().zip(&f).map(|(k, f)| k * f).sum()
    }

    /// From fitted coefficients in feature order.
    pub(crate) fn from_coefficients(c: &[f64], coulomb_width: f64) -> Self {
        JointTerms {
            armature: c[0],
            viscous: c[1],
            coulomb: [c[2], c[3]],
            coulomb_width,
            offset: c[4],
            spring: [c[5], c[6], c[7], c[8]],
            spring_range: None,
        }
    }

    /// The coefficients in feature order.
    fn coefficients(&self) -> [f64; JOINT_FEATURES] {
        let (c, s) = (&self.coulomb, &self.spring);
        [
            self.armature,
            self.viscous,
            c[0],
            c[1],
            self.offset,
            s[0],
            s[1],
            s[2],
            s[3],
        ]
    }

    /// Whether any term is non-zero.
    pub fn is_zero(&self) -> bool {
        self.coefficients().iter().all(|c| *c == 0.0)
    }

    /// Whether the terms are physically possible (issue 30): rotor inertia and viscous
    /// friction not negative, and a friction curve that opposes the velocity at every speed:
    /// `F_c1 tanh(v/w) + F_c2 tanh(v/10w) >= 0` for `v > 0`, which holds exactly when
    /// `F_c1 + F_c2 >= 0` (at high speed) and `10 F_c1 + F_c2 >= 0` (near rest; `tanh(a) <=
    /// 10 tanh(a/10)`). A Stribeck dip (`F_c2 < 0`) and a slow rise through rest (`F_c1 < 0`)
    /// are allowed; a torque that pushes the joint along is not. Rounding of the fit's own
    /// coordinates (1e-9 of the levels) is tolerated.
    pub fn is_physical(&self) -> bool {
        self.physical_problem().is_none()
    }

    /// The first physical condition these terms break, as a phrase for an error message.
    pub fn physical_problem(&self) -> Option<String> {
        if let (Some([low, high]), false) = (self.spring_range, self.spring_range_is_ordered()) {
            return Some(format!(
                "spring range [{low}, {high}] is not [lowest, highest] (finite, lowest first)"
            ));
        }
        if !self.is_valid() {
            return Some("a coefficient is not finite or the Coulomb width is not positive".into());
        }
        if self.armature < 0.0 {
            return Some(format!(
                "rotor inertia {} kg m^2 is negative",
                self.armature
            ));
        }
        if self.viscous < 0.0 {
            return Some(format!(
                "viscous friction {} N m s/rad is negative",
                self.viscous
            ));
        }
        let [c1, c2] = self.coulomb;
        let slack = -1e-9 * (c1.abs() + c2.abs()) - 1e-12;
        if c1 + c2 < slack || 10.0 * c1 + c2 < slack {
            return Some(format!(
                "Coulomb levels {c1} and {c2} N m give a friction that pushes the joint along \
                 (need F_c1 + F_c2 >= 0 and 10 F_c1 + F_c2 >= 0)"
            ));
        }
        None
    }

    /// All coefficients finite, the width positive and the spring range finite, lowest
    /// first.
    pub(crate) fn is_valid(&self) -> bool {
        self.coefficients().iter().all(|v| v.is_finite())
            && self.coulomb_width.is_finite()
            && self.coulomb_width > 0.0
            && self.spring_range_is_ordered()
    }

    /// No spring range, or one that is finite, lowest first.
    fn spring_range_is_ordered(&self) -> bool {
        self.spring_range
            .is_none_or(|[l, h]| l.is_finite() && h.is_finite() && l <= h)
    }
}

/// The features `[q'', q', tanh(q'/w), tanh(q'/10w), 1, sin q, cos q, sin 2q, cos 2q]` of
/// one joint at one sample (the springs' continued beyond `spring_range`).
#[inline]
pub(crate) fn features(
    q: f64,
    qd: f64,
    qdd: f64,
    width: f64,
    spring_range: Option<[f64; 2]>,
    out: &mut [f64; JOINT_FEATURES],
) {
    let [narrow, wide] = coulomb_features(qd, width);
    out[..FIRST_SPRING_FEATURE].copy_from_slice(&[qdd, qd, narrow, wide, 1.0]);
    let mut springs = [0.0; SPRING_FEATURES];
    spring_features(q, spring_range, &mut springs);
    out[FIRST_SPRING_FEATURE..].copy_from_slice(&springs);
}

/// The spring features `[sin q, cos q, sin 2q, cos 2q]` at `q`; beyond `range`, their value
/// at the nearer end plus their slope there times the distance (a tangent line).
#[inline]
pub(crate) fn spring_features(q: f64, range: Option<[f64; 2]>, out: &mut [f64; SPRING_FEATURES]) {
    // max/min, not clamp: no panic on a reversed or NaN range.
    let edge = range.map_or(q, |[low, high]| q.max(low).min(high));
    let beyond = if edge == q { 0.0 } else { q - edge };
    let (s, c) = edge.sin_cos();
    // sin 2q and cos 2q from sin q and cos q: one sin_cos call per sample.
    let (s2, c2) = (2.0 * s * c, c * c - s * s);
    *out = [
        s + beyond * c,
        c - beyond * s,
        s2 + 2.0 * beyond * c2,
        c2 - 2.0 * beyond * s2,
    ];
}

/// The two Coulomb features `[tanh(q'/w), tanh(q'/10w)]` of a joint at velocity `qd`.
#[inline]
pub(crate) fn coulomb_features(qd: f64, width: f64) -> [f64; 2] {
    [(qd / width).tanh(), (qd / (SECOND_WIDTH * width)).tanh()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sprung(range: Option<[f64; 2]>) -> JointTerms {
        JointTerms {
            coulomb_width: 0.01,
            offset: 1.5,
            spring: [20.0, -4.0, 3.0, 2.5],
            spring_range: range,
            ..Default::default()
        }
    }

    #[test]
    fn springs_follow_the_series_inside_their_range_and_its_tangent_beyond() {
        let series = sprung(None);
        let tailed = sprung(Some([-0.4, 0.9]));
        for q in [-0.4, -0.1, 0.3, 0.9] {
            assert_eq!(tailed.spring_torque(q), series.spring_torque(q));
        }
        // Beyond each end: the value there plus the slope there times the distance.
        for (edge, q) in [(0.9, 1.7), (-0.4, -1.5)] {
            let h = 1e-6;
            let slope =
                (series.spring_torque(edge + h) - series.spring_torque(edge - h)) / (2.0 * h);
            let line = series.spring_torque(edge) + slope * (q - edge);
            assert!((tailed.spring_torque(q) - line).abs() < 1e-6);
            // The series itself bends away from that line (what the tangent replaces).
            assert!((series.spring_torque(q) - line).abs() > 1.0);
        }
        // The whole position torque carries it (what every consumer evaluates).
        assert!(
            (tailed.velocity_and_position_torque(1.7, 0.0) - 1.5 - tailed.spring_torque(1.7)).abs()
                < 1e-12
        );
    }

    #[test]
    fn a_reversed_or_unfinished_spring_range_is_named_and_does_not_panic() {
        for range in [[0.9, -0.4], [f64::NAN, 1.0], [0.0, f64::INFINITY]] {
            let terms = sprung(Some(range));
            let problem = terms.physical_problem().expect("refused");
            assert!(problem.contains("spring range"), "{problem}");
            let _ = terms.velocity_and_position_torque(0.5, 0.1);
        }
    }
}
