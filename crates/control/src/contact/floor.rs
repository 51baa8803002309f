//! The noise floor: per-joint contact and collision thresholds and what they were made from.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::spread::LevelShape;
use crate::error::ConfigError;

/// Per-joint thresholds on the external-torque estimate for a stated false-alarm rate
/// (issue 31; docs/method.md section 5, "Contact").
///
/// At joint velocity `qdot_i` and acceleration `qddot_i`, joint `i`'s contact level is
/// `contact_thresholds[i]` (its level at standstill) times [`LevelShape::factor`],
///
/// ```text
///   1 + speed_gain |qdot| + acceleration_gain |qddot| + knee_gain (|qdot| - knee_speed)+
///     + reversal_gain |qddot| r - moving_drop (1 - r),   r = exp(-(qdot / rest_width)^2)
/// ```
///
/// (the estimate's spread changes so on the calibration motion: it grows with speed and
/// acceleration and peaks at reversals, the higher the sharper), the collision level likewise
/// with `collision_thresholds`; a flag raised at a level is released below
/// `release_fraction` of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactFloor {
    /// Joint names in chain order (may be empty when the caller gave none).
    #[serde(default)]
    pub joints: Vec<String>,
    /// Contact level at rest per joint (N m, > 0).
    pub contact_thresholds: Vec<f64>,
    /// Collision level at rest per joint (N m, >= the contact level).
    pub collision_thresholds: Vec<f64>,
    /// Relative growth of both levels with `|qdot_i|` (1 per rad/s, >= 0).
    pub speed_gain: Vec<f64>,
    /// Relative growth of both levels with `|qddot_i|` (1 per rad/s^2, >= 0).
    pub acceleration_gain: Vec<f64>,
    /// The fraction both levels drop by once the joint moves faster than `rest_width` (in
    /// `[0, 1)`). This and the next four are empty in floors of format version 1 (no drop,
    /// no knee, no reversal gain), else one value per joint.
    #[serde(default)]
    pub moving_drop: Vec<f64>,
    /// The velocity width of the rest peak (rad/s, > 0).
    #[serde(default)]
    pub rest_width: Vec<f64>,
    /// Relative growth of both levels with `|qddot_i|` at a reversal (1 per rad/s^2, >= 0).
    #[serde(default)]
    pub reversal_gain: Vec<f64>,
    /// The speed beyond which the levels grow by `knee_gain` more (rad/s, >= 0).
    #[serde(default)]
    pub knee_speed: Vec<f64>,
    /// Relative growth of both levels per rad/s beyond `knee_speed` (>= 0).
    #[serde(default)]
    pub knee_gain: Vec<f64>,
    /// A joint's flag is released when its estimate falls below this fraction of the level
    /// that raised it (in `(0, 1]`).
    pub release_fraction: f64,
    /// The promised rate of false contact events, all joints together (per hour).
    pub false_alarms_per_hour: f64,
    /// The promised rate of false collision events, all joints together (per hour).
    pub collision_false_alarms_per_hour: f64,
    /// What the floor was calibrated on and what it guarantees.
    pub calibration: ContactCalibration,
    /// The data it was made from (files, identification, checksums), as the caller recorded
    /// it.
    #[serde(default)]
    pub source: BTreeMap<String, Value>,
    /// The program that made it.
    #[serde(default)]
    pub created_by: String,
}

/// What a [`ContactFloor`] was calibrated on, per joint where it is a list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactCalibration {
    /// Length of the free motion (s).
    pub duration_s: f64,
    /// Sample period (s).
    pub dt: f64,
    /// Number of samples.
    pub samples: usize,
    /// Largest `|qdot_i|` in the calibration (rad/s): the guarantee holds within it.
    pub max_abs_qdot: Vec<f64>,
    /// Largest `|qddot_i|` in the calibration (rad/s^2).
    pub max_abs_qddot: Vec<f64>,
    /// Rms of the estimate (the false torque) per joint (N m).
    pub rms: Vec<f64>,
    /// Spread (mean `|estimate|`) at rest per joint (N m), the unit of the normalised
    /// estimate.
    pub rest_spread: Vec<f64>,
    /// Largest `|estimate|` seen per joint (N m).
    pub peak: Vec<f64>,
    /// False contact events the floor raises on its own calibration data, per joint.
    pub events_at_contact: Vec<usize>,
    /// Events above the tail fit's base level per joint (the fit's sample size).
    pub tail_events: Vec<usize>,
    /// Generalised-Pareto shape of the per-event peaks per joint (kept >= 0).
    pub tail_shape: Vec<f64>,
    /// The smallest steady torque detected at rest with 95 % probability per sample (N m):
    /// the contact level plus 1.645 rest spreads of the estimate's noise.
    pub smallest_detected: Vec<f64>,
    /// What the floor guarantees and under which assumptions.
    pub assumption: String,
}

impl ContactFloor {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.contact_thresholds.len()
    }

    /// Checks every field; the error names the key and element.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let n = self.dof();
        if n == 0 {
            return Err(ConfigError::new(
                "contact_thresholds",
                "is empty: a floor holds one threshold per joint",
            ));
        }
        for (key, v) in [
            ("collision_thresholds", &self.collision_thresholds),
            ("speed_gain", &self.speed_gain),
            ("acceleration_gain", &self.acceleration_gain),
        ] {
            if v.len() != n {
                return Err(ConfigError::new(
                    key,
                    format!("has {} values, contact_thresholds has {n}", v.len()),
                ));
            }
        }
        self.validate_shapes(n)?;
        if !self.joints.is_empty() && self.joints.len() != n {
            return Err(ConfigError::new(
                "joints",
                format!(
                    "names {} joints, the thresholds are for {n}",
                    self.joints.len()
                ),
            ));
        }
        for i in 0..n {
            let c = self.contact_thresholds[i];
            if !(c.is_finite() && c > 0.0) {
                return Err(ConfigError::new(
                    format!("contact_thresholds[{i}]"),
                    format!("is {c}: must be finite and > 0"),
                ));
            }
            let k = self.collision_thresholds[i];
            if !(k.is_finite() && k >= c) {
                return Err(ConfigError::new(
                    format!("collision_thresholds[{i}]"),
                    format!("is {k}: must be finite and >= the contact threshold {c}"),
                ));
            }
            for (key, g) in [
                ("speed_gain", self.speed_gain[i]),
                ("acceleration_gain", self.acceleration_gain[i]),
            ] {
                if !(g.is_finite() && g >= 0.0) {
                    return Err(ConfigError::new(
                        format!("{key}[{i}]"),
                        format!("is {g}: must be finite and >= 0"),
                    ));
                }
            }
        }
        let r = self.release_fraction;
        if !(r > 0.0 && r <= 1.0) {
            return Err(ConfigError::new(
                "release_fraction",
                format!("is {r}: must be in (0, 1]"),
            ));
        }
        for (key, v) in [
            ("false_alarms_per_hour", self.false_alarms_per_hour),
            (
                "collision_false_alarms_per_hour",
                self.collision_false_alarms_per_hour,
            ),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ConfigError::new(
                    key,
                    format!("is {v}: must be finite and > 0"),
                ));
            }
        }
        Ok(())
    }

    /// Joint `i`'s factor on both levels at this velocity and acceleration (1 at standstill;
    /// the struct's formula).
    #[inline]
    pub fn scale(&self, i: usize, qdot: f64, qddot: f64) -> f64 {
        self.shape(i).factor(qdot, qddot)
    }

    /// Joint `i`'s level shape (zeros for the terms a version-1 floor does not have).
    #[inline]
    pub fn shape(&self, i: usize) -> LevelShape {
        let at = |v: &[f64], default: f64| v.get(i).copied().unwrap_or(default);
        LevelShape {
            speed_gain: self.speed_gain[i],
            acceleration_gain: self.acceleration_gain[i],
            moving_drop: at(&self.moving_drop, 0.0),
            rest_width: at(&self.rest_width, 1.0),
            reversal_gain: at(&self.reversal_gain, 0.0),
            knee_speed: at(&self.knee_speed, 0.0),
            knee_gain: at(&self.knee_gain, 0.0),
        }
    }

    /// The shape terms of format version 2: all empty or one per joint, each in its range.
    fn validate_shapes(&self, n: usize) -> Result<(), ConfigError> {
        let terms: [(&str, &Vec<f64>, f64, f64); 5] = [
            ("moving_drop", &self.moving_drop, 0.0, 1.0),
            (
                "rest_width",
                &self.rest_width,
                f64::MIN_POSITIVE,
                f64::INFINITY,
            ),
            ("reversal_gain", &self.reversal_gain, 0.0, f64::INFINITY),
            ("knee_speed", &self.knee_speed, 0.0, f64::INFINITY),
            ("knee_gain", &self.knee_gain, 0.0, f64::INFINITY),
        ];
        let given = self.moving_drop.len();
        for (key, v, low, high) in terms {
            if v.len() != given || (given != 0 && given != n) {
                return Err(ConfigError::new(
                    key,
                    format!(
                        "has {} values: moving_drop, rest_width, reversal_gain, knee_speed and \
                         knee_gain are all empty or all have one value per joint ({n})",
                        v.len()
                    ),
                ));
            }
            for (i, &x) in v.iter().enumerate() {
                if !(x.is_finite() && x >= low && x < high) {
                    return Err(ConfigError::new(
                        format!("{key}[{i}]"),
                        format!("is {x}: must be finite, >= {low} and < {high}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Joint `i`'s contact level (N m) at this velocity and acceleration.
    #[inline]
    pub fn contact_level(&self, i: usize, qdot: f64, qddot: f64) -> f64 {
        self.contact_thresholds[i] * self.scale(i, qdot, qddot)
    }

    /// The floor as a table, one row per joint, with its guarantee and assumption.
    pub fn describe(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "contact floor for {:.3} false contact events per hour ({:.4} collision events per hour), all joints together",
            self.false_alarms_per_hour, self.collision_false_alarms_per_hour
        );
        let _ = writeln!(
            s,
            "{:<14} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>10} {:>10}",
            "joint",
            "rms",
            "contact",
            "collision",
            "smallest",
            "moving",
            "/(rad/s)",
            "max|qdot|",
            "max|qddot|"
        );
        let c = &self.calibration;
        for i in 0..self.dof() {
            let name = self
                .joints
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("{i}"));
            let _ = writeln!(
                s,
                "{:<14} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>10.2} {:>10.2}",
                name,
                c.rms.get(i).copied().unwrap_or(f64::NAN),
                self.contact_thresholds[i],
                self.collision_thresholds[i],
                c.smallest_detected.get(i).copied().unwrap_or(f64::NAN),
                self.contact_thresholds[i]
                    * (1.0 - self.moving_drop.get(i).copied().unwrap_or(0.0)),
                self.speed_gain[i],
                c.max_abs_qdot.get(i).copied().unwrap_or(f64::NAN),
                c.max_abs_qddot.get(i).copied().unwrap_or(f64::NAN),
            );
        }
        let _ = writeln!(
            s,
            "(N m; levels at standstill; moving: the contact level once the joint moves, before \
             it grows by 1 + gain |qdot| + gain_acc |qddot|)"
        );
        let _ = write!(s, "{}", c.assumption);
        s
    }
}
