//! Settings of [`super::excitation`]: the motion's length and rate, its harmonics, and the
//! envelope it stays in (a range around a pose, fractions of the speed and acceleration
//! limits), each with one default and one check.

use serde::{Deserialize, Serialize};

use super::excitation::Bounds;
use crate::error::DynamicsError;
use crate::model::Model;

/// Speed limit (rad/s or m/s) of a joint whose URDF gives none.
pub const DEFAULT_VELOCITY_LIMIT: f64 = 1.5;
/// Most samples an excitation may have.
const MAX_SAMPLES: f64 = 2.0e6;

/// Settings of [`excitation`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExcitationSettings {
    /// Length of the motion (s); a whole number of periods. Default 60.
    pub duration: f64,
    /// Period of the series (s): the duration or a divisor of it. Default 10.
    pub period: f64,
    /// Harmonics per joint (at least 2: the first is fixed by the rest to start at rest).
    /// Default 5.
    pub harmonics: usize,
    /// Sampling rate of the output (Hz). Default 200.
    pub rate_hz: f64,
    /// Acceleration limit of every joint (rad/s^2; URDFs give none). Default 3.
    pub acceleration_limit: f64,
    /// Part of each joint's range kept free at either end (0 to 0.5). Default 0.05.
    pub position_margin: f64,
    /// Seed of the random starts. Default 1.
    pub seed: u64,
    /// Condition-number evaluations of the local search after the random starts.
    /// Default 2000 (about 2 s for a 7-joint arm).
    pub iterations: usize,
    /// Centre of the envelope, one value per joint (rad or m); empty (the default): the
    /// middle of each joint's limits (0 for a joint without limits).
    pub pose: Vec<f64>,
    /// Half-width of each joint's range around `pose` (rad or m): one value for every
    /// joint or one per joint; infinite: the URDF's whole range. The range is also kept
    /// inside the limits less `position_margin`. Default `[0.5]`.
    pub range: Vec<f64>,
    /// Fraction (0 to 1] of each joint's velocity limit (the URDF's, or
    /// [`DEFAULT_VELOCITY_LIMIT`]) the motion may reach. Default 0.3.
    pub velocity_fraction: f64,
    /// Fraction (0 to 1] of `acceleration_limit` the motion may reach. Default 0.3.
    pub acceleration_fraction: f64,
}

/// Default half-width of each joint's range around the pose (rad or m).
pub const DEFAULT_EXCITATION_RANGE: f64 = 0.5;
/// Default fraction of the velocity and acceleration limits an excitation may reach.
pub const DEFAULT_LIMIT_FRACTION: f64 = 0.3;

impl Default for ExcitationSettings {
    fn default() -> Self {
        ExcitationSettings {
            duration: 60.0,
            period: 10.0,
            harmonics: 5,
            rate_hz: 200.0,
            acceleration_limit: 3.0,
            position_margin: 0.05,
            seed: 1,
            iterations: 2000,
            pose: Vec::new(),
            range: vec![DEFAULT_EXCITATION_RANGE],
            velocity_fraction: DEFAULT_LIMIT_FRACTION,
            acceleration_fraction: DEFAULT_LIMIT_FRACTION,
        }
    }
}

impl ExcitationSettings {
    /// Checks every setting; the error names it.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        let bad = |key: &str, m: String| {
            Err(DynamicsError::InvalidArgument(format!(
                "excitation setting {key}: {m}"
            )))
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.duration) {
            return bad(
                "duration",
                format!("is {}, must be a positive number of seconds", self.duration),
            );
        }
        if !positive(self.period)
            || self.period > self.duration * (1.0 + 1e-12)
            || !whole(self.duration / self.period)
        {
            return bad(
                "period",
                format!(
                    "is {}, must divide the duration {} s into a whole number of periods",
                    self.period, self.duration
                ),
            );
        }
        if !(2..=50).contains(&self.harmonics) {
            return bad(
                "harmonics",
                format!("is {}, must be 2 to 50 (default 5)", self.harmonics),
            );
        }
        let least = 10.0 * self.harmonics as f64 / self.period;
        if !positive(self.rate_hz) || self.rate_hz < least {
            return bad("rate_hz", format!("is {}, must be at least {least} Hz (10 samples per cycle of the highest harmonic)", self.rate_hz));
        }
        if !whole(self.duration * self.rate_hz) || self.duration * self.rate_hz > MAX_SAMPLES {
            return bad(
                "rate_hz",
                format!(
                    "{} Hz over {} s must make a whole number of samples, at most {MAX_SAMPLES}",
                    self.rate_hz, self.duration
                ),
            );
        }
        if !positive(self.acceleration_limit) {
            return bad(
                "acceleration_limit",
                format!(
                    "is {}, must be a positive number of rad/s^2 (default 3)",
                    self.acceleration_limit
                ),
            );
        }
        if !(self.position_margin >= 0.0 && self.position_margin < 0.5) {
            return bad(
                "position_margin",
                format!(
                    "is {}, must be at least 0 and below 0.5 (default 0.05)",
                    self.position_margin
                ),
            );
        }
        for (key, v) in [
            ("velocity_fraction", self.velocity_fraction),
            ("acceleration_fraction", self.acceleration_fraction),
        ] {
            if !(v > 0.0 && v <= 1.0) {
                return bad(
                    key,
                    format!("is {v}, must be above 0 and at most 1 (default 0.3)"),
                );
            }
        }
        if self.range.is_empty() {
            return bad(
                "range",
                "is empty: give one half-width for every joint or one per joint (default 0.5)"
                    .into(),
            );
        }
        if let Some((i, v)) = self.range.iter().enumerate().find(|(_, v)| !(**v > 0.0)) {
            return bad("range", format!("element {i} is {v}, must be a positive half-width (rad or m; infinite: the whole range)"));
        }
        if let Some((i, v)) = self.pose.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return bad(
                "pose",
                format!("element {i} is {v}, must be a finite position"),
            );
        }
        Ok(())
    }

    /// Checks the envelope against `model`: one pose value per joint (or none), one range
    /// per joint (or one for all), each pose inside its joint's limits less the margin.
    pub fn validate_for(&self, model: &Model) -> Result<(), DynamicsError> {
        self.validate()?;
        let n = model.nq();
        let bad = |key: &str, m: String| {
            Err(DynamicsError::InvalidArgument(format!(
                "excitation setting {key}: {m}"
            )))
        };
        if !self.pose.is_empty() && self.pose.len() != n {
            return bad(
                "pose",
                format!(
                    "has {} values for an arm of {n} joints: give one per joint",
                    self.pose.len()
                ),
            );
        }
        if self.range.len() != 1 && self.range.len() != n {
            return bad(
                "range",
                format!(
                    "has {} values for an arm of {n} joints: give one for all or one per joint",
                    self.range.len()
                ),
            );
        }
        for (i, (j, b)) in model.joints.iter().zip(Bounds::of(model, self)).enumerate() {
            if let Some(&p) = self.pose.get(i) {
                if !(p >= b.lowest - 1e-12 && p <= b.highest + 1e-12) {
                    return bad(
                        "pose",
                        format!(
                            "joint {} ({}) at {p} is outside its limits less the margin [{}, {}]",
                            i, j.name, b.lowest, b.highest
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

fn whole(x: f64) -> bool {
    (x - x.round()).abs() <= 1e-6 * x.abs().max(1.0) && x.round() >= 1.0
}
