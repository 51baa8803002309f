//! What identification fits and how it chooses: one default per setting, one check.

use serde::{Deserialize, Serialize};

use crate::error::DynamicsError;
use crate::identification::fit_acceleration::FIT_ACCELERATION_HZ;

/// The Coulomb widths (rad/s) `identify` chooses among when none is given; the first is
/// the reference that another must beat on held-out motion (and the width of a model
/// without joint terms). None wider: 0.02 lowered the SO arms' held-out and new-motion
/// error but made the SO-100's contact floor flag 36 of 39 strong pushes within 50 ms
/// instead of 42 of 42 (docs/experiments.md, "Why the UR3 missed 0.2").
pub const COULOMB_WIDTH_CANDIDATES: [f64; 3] = [0.01, 0.003, 0.005];

/// Settings of [`crate::identify`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IdentificationSettings {
    /// Fit per-joint rotor inertia, viscous and Coulomb friction and an offset
    /// ([`crate::JointTerms`]). Default true.
    pub friction: bool,
    /// Width of the Coulomb friction's narrower smooth sign `tanh(q' / w)` (rad/s); the
    /// second is 10 times wider. `None` (default): chosen on held-out motion among
    /// [`COULOMB_WIDTH_CANDIDATES`] (each joint's terms carry the width taken).
    pub coulomb_width: Option<f64>,
    /// Offer each joint spring terms (`sin q`, `cos q`, `sin 2q`, `cos 2q`); each keeps them only
    /// where they lower the error on held-out motion by 1 % or more. Default true (needs
    /// `friction`).
    pub springs: bool,
    /// Contiguous stretches for blocked cross-validation when no validation recording is
    /// given. Default 5.
    pub folds: usize,
    /// Ridge weight toward the prior (the URDF), relative to each column's scale; `None`
    /// (default): chosen on held-out motion from 1e-8 to 1e2.
    pub ridge: Option<f64>,
    /// When the ridge is chosen: the share of the best held-out error within which the
    /// strongest ridge is taken instead of the best (0 to 0.5). Default 0 (the best). Held-out
    /// stretches that repeat the training motion cannot tell ridges apart by less than a few
    /// per cent, and the one nearer the prior is the one that holds on new motion.
    #[serde(skip_serializing_if = "is_zero")]
    pub ridge_tolerance: f64,
    /// Fit over physically possible bodies only (positive mass, positive definite inertia
    /// obeying the triangle inequalities: log-Cholesky coordinates). Default true.
    pub physical_consistency: bool,
    /// With `physical_consistency`, how heavy and how large a body may be: its mass at most
    /// this many times the prior's (the URDF's, at the torque's size) plus a twentieth of
    /// the arm's, and spread no farther than twice the link's size from its joint (docs/
    /// method.md section 8); `None`: no bound. Default 2 (files written before the setting
    /// existed read as `None`, as they were fitted).
    #[serde(default = "no_bound")]
    pub max_mass_ratio: Option<f64>,
    /// How much of the measured acceleration the prediction trusts (0 to 1); `None`
    /// (default): chosen on held-out motion (see `IdentificationSummary::acceleration_gain`).
    pub acceleration_gain: Option<f64>,
    /// The samples' rate (Hz). When given, one delay of the torques behind the motion (up to
    /// 30 ms or 2 samples either way, at most 25 candidates) is chosen on held-out motion
    /// and stored as `delay_s` (unless `delay` is false), and the fit's acceleration is
    /// smoothed (`fit_acceleration_hz`); `None` (default): neither.
    pub sample_rate_hz: Option<f64>,
    /// Offer a delay of the torques behind the motion (needs `sample_rate_hz`). Default true;
    /// false where held-out stretches cannot judge one (a recording whose motion repeats).
    /// Not written to files: `summary.delay_s` and `summary.held_out` say what was done.
    #[serde(skip)]
    pub delay: bool,
    /// Zero-phase low-pass (Hz) on the measured acceleration that the fit regresses the
    /// inertial torque on (needs `sample_rate_hz`; predictions, the acceleration gain and the
    /// held-out errors use the acceleration as measured); `None`: the fit uses it as
    /// measured too. Default [`FIT_ACCELERATION_HZ`]. Not written to files:
    /// `summary.fit_acceleration_hz` records the cut-off applied.
    #[serde(skip)]
    pub fit_acceleration_hz: Option<f64>,
}

impl Default for IdentificationSettings {
    fn default() -> Self {
        IdentificationSettings {
            friction: true,
            coulomb_width: None,
            springs: true,
            folds: 5,
            ridge: None,
            ridge_tolerance: 0.0,
            physical_consistency: true,
            max_mass_ratio: Some(2.0),
            acceleration_gain: None,
            sample_rate_hz: None,
            delay: true,
            fit_acceleration_hz: Some(FIT_ACCELERATION_HZ),
        }
    }
}

impl IdentificationSettings {
    /// Checks every setting; the error names it.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        let bad = |key: &str, m: String| {
            Err(DynamicsError::InvalidArgument(format!(
                "identification setting {key}: {m}"
            )))
        };
        if let Some(w) = self.coulomb_width {
            if !(w.is_finite() && w > 0.0) {
                return bad(
                    "coulomb_width",
                    format!(
                        "is {w}, must be a positive number of rad/s (or absent: chosen on \
                         held-out motion)"
                    ),
                );
            }
        }
        if !(2..=50).contains(&self.folds) {
            return bad(
                "folds",
                format!("is {}, must be 2 to 50 (default 5)", self.folds),
            );
        }
        if let Some(r) = self.ridge {
            if !(r.is_finite() && r >= 0.0) {
                return bad(
                    "ridge",
                    format!("is {r}, must be >= 0 (or absent: chosen on held-out motion)"),
                );
            }
        }
        if !(0.0..=0.5).contains(&self.ridge_tolerance) {
            return bad(
                "ridge_tolerance",
                format!(
                    "is {}, must be 0 to 0.5 (a share of the best held-out error; default 0)",
                    self.ridge_tolerance
                ),
            );
        }
        if let Some(r) = self.max_mass_ratio {
            if !(r.is_finite() && r >= 1.0) {
                return bad(
                    "max_mass_ratio",
                    format!("is {r}, must be at least 1 (or absent: no bound; default 2)"),
                );
            }
        }
        if let Some(g) = self.acceleration_gain {
            if !(0.0..=1.0).contains(&g) {
                return bad(
                    "acceleration_gain",
                    format!("is {g}, must be 0 to 1 (or absent: chosen on held-out motion)"),
                );
            }
        }
        if let Some(r) = self.sample_rate_hz {
            if !(r.is_finite() && r > 0.0) {
                return bad(
                    "sample_rate_hz",
                    format!("is {r}, must be a positive number of Hz (or absent: no delay)"),
                );
            }
        }
        if let Some(f) = self.fit_acceleration_hz {
            if !(f.is_finite() && f > 0.0) {
                return bad(
                    "fit_acceleration_hz",
                    format!("is {f}, must be a positive number of Hz (or absent: as measured)"),
                );
            }
        }
        if self.springs && !self.friction {
            return bad(
                "springs",
                "needs friction = true (springs are joint terms)".into(),
            );
        }
        Ok(())
    }
}

/// What a file without `max_mass_ratio` was fitted with: no bound.
fn no_bound() -> Option<f64> {
    None
}

/// Whether a setting is at its default of 0 (left out of the files, so that files written
/// before the setting existed read back the same).
pub(super) fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A settings record written before `max_mass_ratio` existed reads as no bound (how it
    /// was fitted); a new one carries the default bound.
    #[test]
    fn older_settings_read_without_the_mass_bound() {
        let mut value = serde_json::to_value(IdentificationSettings::default()).unwrap();
        assert_eq!(value["max_mass_ratio"], serde_json::json!(2.0));
        value.as_object_mut().unwrap().remove("max_mass_ratio");
        let old: IdentificationSettings = serde_json::from_value(value).unwrap();
        assert_eq!(old.max_mass_ratio, None);
        assert_eq!(
            old,
            IdentificationSettings {
                max_mass_ratio: None,
                ..Default::default()
            }
        );
    }
}
