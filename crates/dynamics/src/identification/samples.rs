//! Free-motion samples as identification reads them: row-major `N x n` arrays.

use crate::error::DynamicsError;

/// Joint positions, velocities, accelerations and torques of `len()` samples of an arm
/// with `dof` joints, row-major (`q[k * dof + i]` is joint `i` at sample `k`), in SI units.
#[derive(Clone, Copy, Debug)]
pub struct Samples<'a> {
    /// Joint positions (rad or m).
    pub q: &'a [f64],
    /// Joint velocities (rad/s or m/s).
    pub qdot: &'a [f64],
    /// Joint accelerations (rad/s^2 or m/s^2).
    pub qddot: &'a [f64],
    /// Measured joint torques (N m or N): the motors' torque, no external force acting.
    pub tau: &'a [f64],
    /// Number of joints.
    pub dof: usize,
}

impl Samples<'_> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.q.len().checked_div(self.dof).unwrap_or(0)
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample `k`'s four rows.
    pub(crate) fn row(&self, k: usize) -> (&[f64], &[f64], &[f64], &[f64]) {
        let r = k * self.dof..(k + 1) * self.dof;
        (
            &self.q[r.clone()],
            &self.qdot[r.clone()],
            &self.qddot[r.clone()],
            &self.tau[r],
        )
    }

    /// Equal lengths, a multiple of `dof`, `dof` equal to the model's, every value finite.
    pub(crate) fn check(&self, what: &str, dof: usize) -> Result<(), DynamicsError> {
        let bad = |m: String| Err(DynamicsError::InvalidArgument(format!("{what}: {m}")));
        if self.dof != dof {
            return bad(format!("{} joints, the model has {dof}", self.dof));
        }
        let len = self.q.len();
        if dof == 0
            || !len.is_multiple_of(dof)
            || [self.qdot.len(), self.qddot.len(), self.tau.len()]
                .iter()
                .any(|&l| l != len)
        {
            return bad(format!(
                "arrays of {}, {}, {} and {} values do not make whole samples of {dof} joints",
                len,
                self.qdot.len(),
                self.qddot.len(),
                self.tau.len()
            ));
        }
        for (name, values) in [
            ("q", self.q),
            ("qdot", self.qdot),
            ("qddot", self.qddot),
            ("tau", self.tau),
        ] {
            if let Some(p) = values.iter().position(|v| !v.is_finite()) {
                return bad(format!(
                    "{name} of joint {} at sample {} is {}",
                    p % dof,
                    p / dof,
                    values[p]
                ));
            }
        }
        Ok(())
    }
}
