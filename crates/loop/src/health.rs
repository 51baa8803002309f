//! Whether the physics of a run stayed meaningful, step by step (docs/outputs.md, "When a
//! run fails"): the one divergence monitor of the scenario runner and of any other loop
//! (the MuJoCo co-simulation). It counts,
//! per joint, the share of time outside the position limits, with the command at the
//! effort limit and with the estimate beyond it; and divergence, which stops a variant.
//!
//! A variant has diverged when, at some control step,
//! * the plant's angle or velocity is not finite, an angle exceeds [`MAX_ANGLE`] in
//!   magnitude, or a velocity exceeds `max(MIN_SPEED_BOUND, SPEED_FACTOR x` the joint's
//!   velocity limit`)`;
//! * an encoder reading is not finite without an injected NaN fault (the sensor model was
//!   given values it cannot represent);
//! * the external-torque estimate is not finite or exceeds `ESTIMATE_FACTOR x` the effort
//!   limit.

// Bounds are written `!(x <= bound)` on purpose: a NaN fails them.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::Measurement;
use admittance_dynamics::Model;

/// Largest meaningful angle (rad): about 160 turns.
pub const MAX_ANGLE: f64 = 1.0e3;
/// A velocity above `SPEED_FACTOR` times the joint's limit is a simulation gone wrong.
pub const SPEED_FACTOR: f64 = 20.0;
/// ... or above this (rad/s), for joints with tiny or no velocity limits.
pub const MIN_SPEED_BOUND: f64 = 100.0;
/// An estimate above `ESTIMATE_FACTOR` times the effort limit is not an estimate.
pub const ESTIMATE_FACTOR: f64 = 10.0;

/// Why and when a variant stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct Divergence {
    /// Simulated time (s).
    pub time: f64,
    /// What left its bounds.
    pub reason: String,
}

/// Per-joint counters of a run's health, fed once per control step ([`HealthMonitor::add`]);
/// the rules that judge the finished run's metrics are `admittance_runfolder::health`.
#[derive(Clone, Debug)]
pub struct HealthMonitor {
    joints: Vec<String>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    speed_bound: Vec<f64>,
    effort: Vec<f64>,
    outside_limits: Vec<usize>,
    torque_saturated: Vec<usize>,
    estimate_saturated: Vec<usize>,
    steps: usize,
    /// The first divergence, once one happened.
    pub divergence: Option<Divergence>,
}

impl HealthMonitor {
    /// For the plant's model with its (scaled) effort limits.
    pub fn new(model: &Model, joints: &[String], effort: &[f64]) -> Self {
        let n = joints.len();
        let (lower, upper) = model.position_limits().unzip();
        Self {
            joints: joints.to_vec(),
            lower,
            upper,
            speed_bound: model
                .joints
                .iter()
                .map(|j| (SPEED_FACTOR * j.limits.velocity).max(MIN_SPEED_BOUND))
                .collect(),
            effort: effort.to_vec(),
            outside_limits: vec![0; n],
            torque_saturated: vec![0; n],
            estimate_saturated: vec![0; n],
            steps: 0,
            divergence: None,
        }
    }

    /// Counts one control step; returns the divergence when the step left the bounds.
    pub fn add(
        &mut self,
        time: f64,
        q: &[f64],
        qdot: &[f64],
        measurement: &Measurement,
        torque: &[f64],
        estimate: &[f64],
    ) -> Option<&Divergence> {
        self.steps += 1;
        for i in 0..self.joints.len() {
            if !(q[i] >= self.lower[i] && q[i] <= self.upper[i]) {
                self.outside_limits[i] += 1;
            }
            if torque[i].abs() >= self.effort[i] * (1.0 - 1e-9) {
                self.torque_saturated[i] += 1;
            }
            if !(estimate[i].abs() <= self.effort[i]) {
                self.estimate_saturated[i] += 1;
            }
        }
        if self.divergence.is_none() {
            if let Some(reason) = self.check(q, qdot, measurement, estimate) {
                self.divergence = Some(Divergence { time, reason });
            }
        }
        self.divergence.as_ref()
    }

    fn check(&self, q: &[f64], qdot: &[f64], m: &Measurement, estimate: &[f64]) -> Option<String> {
        for (i, name) in self.joints.iter().enumerate() {
            if !(q[i].abs() <= MAX_ANGLE) {
                return Some(format!("the angle of {name} reached {:.3e} rad", q[i]));
            }
            if !(qdot[i].abs() <= self.speed_bound[i]) {
                return Some(format!(
                    "the velocity of {name} reached {:.3e} rad/s (bound {} rad/s)",
                    qdot[i], self.speed_bound[i]
                ));
            }
            // A NaN reading (injected, or refused by the plausibility gates) takes the
            // loop's fault path (a safe hold, counted); only a finite or infinite value
            // beyond the bound says the sensors' settings are wrong.
            if !(m.q[i].abs() <= MAX_ANGLE) && !m.q[i].is_nan() {
                return Some(format!(
                    "the encoder reading of {name} is {:.3e} rad (check plant.sensors: its noise or resolution)",
                    m.q[i]
                ));
            }
            if !(estimate[i].abs() <= ESTIMATE_FACTOR * self.effort[i]) {
                return Some(format!(
                    "the external-torque estimate of {name} reached {:.3e} N m ({ESTIMATE_FACTOR} x its effort limit {} N m)",
                    estimate[i], self.effort[i]
                ));
            }
        }
        None
    }

    fn fractions(&self, counts: &[usize]) -> Vec<f64> {
        counts
            .iter()
            .map(|c| *c as f64 / self.steps.max(1) as f64)
            .collect()
    }

    /// `q_limit_violation_fraction`, `torque_saturation_fraction`,
    /// `estimate_saturation_fraction`.
    pub fn fractions_all(&self) -> [Vec<f64>; 3] {
        [
            self.fractions(&self.outside_limits),
            self.fractions(&self.torque_saturated),
            self.fractions(&self.estimate_saturated),
        ]
    }
}
