//! What a joint adds to the rigid-body torque: rotor inertia, friction, an offset and
//! springs (docs/method.md section 1, the friction term `F` of eq. 1, here identified).
//!
//! ```text
//!   tau_joint = I_a q'' + F_v q' + F_c tanh(q' / w) + tau_0 + k_1 q + k_s sin q + k_c cos q
//! ```
//!
//! `tanh(q' / w)` is a smooth sign (width `w` in rad/s): Coulomb friction without the jump
//! at rest that no filter or integrator handles well. The spring terms stand for what a
//! URDF does not describe (Baxter's gravity-assist spring on s1, cable and hose forces).

use serde::{Deserialize, Serialize};

/// Number of per-joint features (regressor columns) of [`JointTerms`].
pub(crate) const JOINT_FEATURES: usize = 7;
/// Index of the first spring feature.
pub(crate) const FIRST_SPRING_FEATURE: usize = 4;

/// The identified terms of one joint (SI units: N m, or N for a prismatic joint).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTerms {
    /// Rotor inertia reflected through the gear, `I_a` (kg m^2).
    pub armature: f64,
    /// Viscous friction `F_v` (N m s/rad).
    pub viscous: f64,
    /// Coulomb friction level `F_c` (N m).
    pub coulomb: f64,
    /// Width `w` of the smooth sign (rad/s).
    pub coulomb_width: f64,
    /// Constant offset `tau_0` (N m): sensor bias or a constant load.
    pub offset: f64,
    /// Spring terms `[k_1, k_s, k_c]` on `q`, `sin q`, `cos q` (N m/rad, N m, N m).
    pub spring: [f64; 3],
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
        let mut f = [0.0; JOINT_FEATURES];
        features(q, qd, 0.0, self.coulomb_width, &mut f);
        self.viscous * f[1] + self.coulomb * f[2] + self.offset * f[3] + self.spring[0] * f[4] + self.spring[1] * f[5] + self.spring[2] * f[6]
    }

    /// From fitted coefficients in feature order.
    pub(crate) fn from_coefficients(c: &[f64], coulomb_width: f64) -> Self {
        JointTerms {
            armature: c[0],
            viscous: c[1],
            coulomb: c[2],
            coulomb_width,
            offset: c[3],
            spring: [c[4], c[5], c[6]],
        }
    }

    /// All coefficients finite and the width positive.
    pub(crate) fn is_valid(&self) -> bool {
        let c = [self.armature, self.viscous, self.coulomb, self.offset, self.spring[0], self.spring[1], self.spring[2]];
        c.iter().all(|v| v.is_finite()) && self.coulomb_width.is_finite() && self.coulomb_width > 0.0
    }
}

/// The features `[q'', q', tanh(q'/w), 1, q, sin q, cos q]` of one joint at one sample.
#[inline]
pub(crate) fn features(q: f64, qd: f64, qdd: f64, width: f64, out: &mut [f64; JOINT_FEATURES]) {
    let (s, c) = q.sin_cos();
    *out = [qdd, qd, (qd / width).tanh(), 1.0, q, s, c];
}
