//! The noise floor from free motion the identification did not fit (issue 31, item 1).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::floor::{ContactCalibration, ContactFloor};
use super::spread::fit_spread;
use super::tail::{event_peaks, level_for_rate};
use crate::error::ConfigError;

/// Settings of [`calibrate_contact_with`] (a scenario's `[contact]` table).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactCalibrationConfig {
    /// False contact events per hour the floor allows, all joints together (default 1).
    pub false_alarms_per_hour: f64,
    /// False collision events per hour as a fraction of the contact rate (default 0.01).
    pub collision_rate_ratio: f64,
    /// The collision level is at least this multiple of the contact level (default 1.5).
    pub collision_min_ratio: f64,
    /// A flag is released below this fraction of its level (default 0.7).
    pub release_fraction: f64,
    /// Let the levels grow with `|qdot|` and `|qddot|` where the estimate's spread does on
    /// the calibration motion (default true).
    pub grow_with_motion: bool,
}

impl Default for ContactCalibrationConfig {
    fn default() -> Self {
        ContactCalibrationConfig {
            false_alarms_per_hour: 1.0,
            collision_rate_ratio: 0.01,
            collision_min_ratio: 1.5,
            release_fraction: 0.7,
            grow_with_motion: true,
        }
    }
}

impl ContactCalibrationConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let positive = |key: &str, v: f64, hint: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ConfigError::new(key, format!("is {v}: must be finite and > 0")).hint(hint))
            }
        };
        positive(
            "false_alarms_per_hour",
            self.false_alarms_per_hour,
            "false contact events per hour, all joints together (default 1)",
        )?;
        positive(
            "collision_rate_ratio",
            self.collision_rate_ratio,
            "the collision rate as a fraction of the contact rate (default 0.01)",
        )?;
        if !(self.collision_rate_ratio <= 1.0) {
            return Err(ConfigError::new(
                "collision_rate_ratio",
                "must be <= 1: a collision is rarer than a contact",
            ));
        }
        if !(self.collision_min_ratio.is_finite() && self.collision_min_ratio >= 1.0) {
            return Err(ConfigError::new(
                "collision_min_ratio",
                format!("is {}: must be >= 1", self.collision_min_ratio),
            ));
        }
        let r = self.release_fraction;
        if !(r > 0.0 && r <= 1.0) {
            return Err(ConfigError::new(
                "release_fraction",
                format!("is {r}: must be in (0, 1]"),
            ));
        }
        Ok(())
    }
}

/// Shortest calibration accepted (s).
const MIN_DURATION_S: f64 = 10.0;

/// [`calibrate_contact_with`] with the default settings and the user's false-alarm rate.
pub fn calibrate_contact(
    estimates: &[f64],
    qdot: &[f64],
    qddot: &[f64],
    joints: usize,
    dt: f64,
    false_alarms_per_hour: f64,
) -> Result<ContactFloor, ConfigError> {
    let config = ContactCalibrationConfig {
        false_alarms_per_hour,
        ..Default::default()
    };
    calibrate_contact_with(estimates, qdot, qddot, joints, dt, &config)
}

/// The noise floor from the external-torque estimates over free motion the identification
/// did not fit (every estimate there is a false torque), sample-major (`joints` values per
/// sample), with the measured `qdot` and `qddot` of the same samples, sample period `dt`
/// (docs/method.md section 5, "Contact").
///
/// Per joint: the spread of the estimate as a function of `qdot_i` and `qddot_i` (the
/// `spread` module: growth with speed and acceleration, a peak at reversals), then the
/// level of `|estimate| / s` whose events occur `false_alarms_per_hour / joints` times per
/// hour (so that all joints together raise the user's rate), from the tail of the per-event
/// peaks (see the `tail` module); the collision level likewise at the rate times
/// `collision_rate_ratio`, and at least `collision_min_ratio` contact levels.
pub fn calibrate_contact_with(
    estimates: &[f64],
    qdot: &[f64],
    qddot: &[f64],
    joints: usize,
    dt: f64,
    config: &ContactCalibrationConfig,
) -> Result<ContactFloor, ConfigError> {
    config.validate()?;
    check_data(estimates, qdot, qddot, joints, dt)?;
    let samples = estimates.len() / joints;
    let hours = samples as f64 * dt / 3600.0;
    let rate = config.false_alarms_per_hour / joints as f64;
    let collision_rate = rate * config.collision_rate_ratio;
    let release = config.release_fraction;
    let column =
        |v: &[f64], i: usize| -> Vec<f64> { (0..samples).map(|k| v[k * joints + i]).collect() };
    let mut floor = empty_floor(joints, samples, dt, config);
    let mut shortfall = Vec::new();
    for i in 0..joints {
        let (e, v, a) = (column(estimates, i), column(qdot, i), column(qddot, i));
        let spread = fit_spread(&e, &v, &a, config.grow_with_motion);
        let s0 = spread.standstill;
        let z: Vec<f64> = (0..samples)
            .map(|k| e[k] / (s0 * spread.shape.factor(v[k], a[k])))
            .collect();
        let contact = level_for_rate(&z, hours, release, rate);
        let collision = level_for_rate(&z, hours, release, collision_rate);
        let c = &mut floor.calibration;
        let contact_level = contact.level * s0;
        floor.contact_thresholds.push(contact_level);
        floor
            .collision_thresholds
            .push((collision.level * s0).max(config.collision_min_ratio * contact_level));
        let shape = spread.shape;
        floor.speed_gain.push(shape.speed_gain);
        floor.acceleration_gain.push(shape.acceleration_gain);
        floor.moving_drop.push(shape.moving_drop);
        floor.rest_width.push(shape.rest_width);
        floor.reversal_gain.push(shape.reversal_gain);
        floor.knee_speed.push(shape.knee_speed);
        floor.knee_gain.push(shape.knee_gain);
        c.max_abs_qdot
            .push(v.iter().fold(0.0, |m, x| m.max(x.abs())));
        c.max_abs_qddot
            .push(a.iter().fold(0.0, |m, x| m.max(x.abs())));
        c.rms
            .push((e.iter().map(|x| x * x).sum::<f64>() / samples as f64).sqrt());
        c.rest_spread.push(s0);
        c.peak.push(e.iter().fold(0.0, |m, x| m.max(x.abs())));
        c.events_at_contact
            .push(event_peaks(&z, contact.level, release).len());
        c.tail_events.push(contact.base_events);
        c.tail_shape.push(contact.shape);
        // A Gaussian's sd is sqrt(pi / 2) mean absolute values.
        c.smallest_detected
            .push((contact.level + 1.645 * std::f64::consts::FRAC_PI_2.sqrt()) * s0);
        if contact.base_events < super::tail::MIN_TAIL_EVENTS {
            shortfall.push(i);
        }
    }
    floor.calibration.assumption = assumption(config, hours, &shortfall);
    floor.validate()?;
    Ok(floor)
}

fn check_data(
    estimates: &[f64],
    qdot: &[f64],
    qddot: &[f64],
    joints: usize,
    dt: f64,
) -> Result<(), ConfigError> {
    if joints == 0 {
        return Err(ConfigError::new("joints", "is 0"));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(ConfigError::new(
            "dt",
            format!("is {dt}: must be finite and > 0"),
        ));
    }
    for (key, v) in [("estimates", estimates), ("qdot", qdot), ("qddot", qddot)] {
        if v.len() % joints != 0 || v.len() != estimates.len() {
            return Err(ConfigError::new(
                key,
                format!(
                    "has {} values: expected {} (samples x {joints} joints, sample-major)",
                    v.len(),
                    estimates.len()
                ),
            ));
        }
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(ConfigError::new(
                format!("{key}[{}][{}]", k / joints, k % joints),
                "is not finite",
            ));
        }
    }
    let duration = (estimates.len() / joints) as f64 * dt;
    if duration < MIN_DURATION_S {
        return Err(ConfigError::new(
            "estimates",
            format!("cover {duration:.2} s: a floor needs at least {MIN_DURATION_S} s of free motion"),
        )
        .hint("record minutes of free motion the identification did not fit: a rate per hour is extrapolated from it"));
    }
    Ok(())
}

fn empty_floor(
    joints: usize,
    samples: usize,
    dt: f64,
    config: &ContactCalibrationConfig,
) -> ContactFloor {
    ContactFloor {
        joints: Vec::new(),
        contact_thresholds: Vec::with_capacity(joints),
        collision_thresholds: Vec::with_capacity(joints),
        speed_gain: Vec::with_capacity(joints),
        acceleration_gain: Vec::with_capacity(joints),
        moving_drop: Vec::with_capacity(joints),
        rest_width: Vec::with_capacity(joints),
        reversal_gain: Vec::with_capacity(joints),
        knee_speed: Vec::with_capacity(joints),
        knee_gain: Vec::with_capacity(joints),
        release_fraction: config.release_fraction,
        false_alarms_per_hour: config.false_alarms_per_hour,
        collision_false_alarms_per_hour: config.false_alarms_per_hour * config.collision_rate_ratio,
        calibration: ContactCalibration {
            duration_s: samples as f64 * dt,
            dt,
            samples,
            max_abs_qdot: Vec::new(),
            max_abs_qddot: Vec::new(),
            rms: Vec::new(),
            rest_spread: Vec::new(),
            peak: Vec::new(),
            events_at_contact: Vec::new(),
            tail_events: Vec::new(),
            tail_shape: Vec::new(),
            smallest_detected: Vec::new(),
            assumption: String::new(),
        },
        source: BTreeMap::new(),
        created_by: format!("admittance-control {}", env!("CARGO_PKG_VERSION")),
    }
}

fn assumption(config: &ContactCalibrationConfig, hours: f64, shortfall: &[usize]) -> String {
    let mut s = format!(
        "guarantee: at most {} false contact events per hour (collision: {}), all joints together, in free motion like the calibration's \
         ({:.1} min): the task moves within the calibration's speeds and accelerations, with the same identification, observer and filters. \
         Assumptions: events (rising edges with release at {} of the level) are counted, not samples; the rate is split evenly over the joints; \
         above the base level the per-event peaks have a generalised-Pareto tail (shape 0 to 0.25; exponential with fewer than 50 events), extrapolated to the rate.",
        config.false_alarms_per_hour,
        config.false_alarms_per_hour * config.collision_rate_ratio,
        hours * 60.0,
        config.release_fraction,
    );
    if !shortfall.is_empty() {
        s += &format!(" Warning: joints {shortfall:?} had fewer than 20 events above the base level; record more free motion for a tighter floor.");
    }
    s
}
