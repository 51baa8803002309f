//! Plausibility gates on a robot's raw measurements (issue 34), checked before any state
//! (filter, observer, admittance model) sees them. A finite sample can still be absurd: an
//! angle of 1e20 rad or a torque of 1e300 N m passes every finiteness check and, integrated
//! once by the momentum observer, poisons its estimate for seconds. Per joint:
//!
//! * **angle**: outside `[lower - margin, upper + margin]` of the URDF's limits;
//! * **jump**: farther from the last accepted angle than `jump_factor x velocity limit x
//!   elapsed time` (no motor moves faster than its velocity limit; the elapsed time since the
//!   last accepted sample, so that a dropout does not lock the gate, and since that angle
//!   was first read, so that a driver repeating its last packet does not trip it);
//! * **torque**: `|tau| > torque_factor x effort limit`.
//!
//! A joint without a limit (infinite or zero in the URDF) is not gated on it. A rejected
//! value is replaced by NaN, so that it takes the path a NaN takes (the signal chain and
//! the input conditioner hold their last outputs, the controller writes its safe hold):
//! nothing integrates it, and the loop resumes from the next plausible sample.

use admittance_dynamics::Model;
use serde::{Deserialize, Serialize};

use crate::error::LoopError;

/// The gates' settings (`[signals.gates]` of a robot's loop file), each with its default.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GateConfig {
    /// Whether measurements are gated. Default true.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// How far outside its URDF limits an angle may read (rad or m) before it is refused.
    /// Default 0.2.
    #[serde(default = "default_angle_margin")]
    pub angle_margin: f64,
    /// Multiple of the velocity limit a jump between two accepted samples may reach.
    /// Default 3.
    #[serde(default = "default_factor")]
    pub jump_factor: f64,
    /// Multiple of the effort limit a measured torque may reach. Default 3.
    #[serde(default = "default_factor")]
    pub torque_factor: f64,
}

fn yes() -> bool {
    true
}
fn default_angle_margin() -> f64 {
    0.2
}
fn default_factor() -> f64 {
    3.0
}

impl Default for GateConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            angle_margin: default_angle_margin(),
            jump_factor: default_factor(),
            torque_factor: default_factor(),
        }
    }
}

impl GateConfig {
    /// Every problem, each at its key under `prefix` (empty: valid).
    pub fn problems(&self, prefix: &str) -> Vec<LoopError> {
        let mut out = Vec::new();
        for (key, v, min) in [
            ("angle_margin", self.angle_margin, 0.0),
            ("jump_factor", self.jump_factor, 1.0),
            ("torque_factor", self.torque_factor, 1.0),
        ] {
            if !(v.is_finite() && v >= min) {
                out.push(LoopError::invalid(
                    format!("{prefix}.{key}"),
                    format!("is {v}, must be finite and >= {min}"),
                ));
            }
        }
        out
    }
}

/// Which gate refused a value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Implausible {
    /// The angle is outside the joint's limits by more than the margin.
    Angle,
    /// The angle jumped farther than the joint can move in the time since the last
    /// accepted sample.
    Jump,
    /// The torque exceeds the multiple of the effort limit.
    Torque,
    /// A measured velocity exceeds the multiple of the velocity limit (the jump gate's
    /// speed; [`MEASURED_SPEED_BOUND`] for a joint without one).
    Velocity,
}

/// The largest measured joint speed accepted for a joint whose URDF gives no velocity limit
/// (rad/s or m/s): no motor turns a joint at 1000 rad/s.
pub const MEASURED_SPEED_BOUND: f64 = 1000.0;

/// The first refused value of a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GateFault {
    /// The joint (chain order).
    pub joint: usize,
    /// The gate.
    pub gate: Implausible,
}

/// The gates of one arm; allocation-free per sample.
#[derive(Clone, Debug)]
pub struct PlausibilityGates {
    enabled: bool,
    lower: Vec<f64>,
    upper: Vec<f64>,
    max_speed: Vec<f64>,
    max_torque: Vec<f64>,
    last_q: Vec<f64>,
    last_time: Vec<f64>,
    /// The control period (s): the least time a jump is allowed.
    period: f64,
    /// Samples with at least one refused value, since construction.
    faults: u64,
}

impl PlausibilityGates {
    /// The gates of `model`'s joints with `config` (checked here, at `signals.gates`) for
    /// samples `period` seconds apart.
    pub fn new(model: &Model, config: &GateConfig, period: f64) -> Result<Self, LoopError> {
        if let Some(e) = config.problems("signals.gates").into_iter().next() {
            return Err(e);
        }
        let limited = |v: f64| v.is_finite() && v > 0.0;
        let n = model.nq();
        let mut gates = Self {
            enabled: config.enabled,
            lower: vec![f64::NEG_INFINITY; n],
            upper: vec![f64::INFINITY; n],
            max_speed: vec![f64::INFINITY; n],
            max_torque: vec![f64::INFINITY; n],
            last_q: vec![f64::NAN; n],
            last_time: vec![f64::NAN; n],
            period,
            faults: 0,
        };
        for (i, j) in model.joints.iter().enumerate() {
            let l = &j.limits;
            if l.lower.is_finite() && l.upper.is_finite() && l.upper > l.lower {
                gates.lower[i] = l.lower - config.angle_margin;
                gates.upper[i] = l.upper + config.angle_margin;
            }
            if limited(l.velocity) {
                gates.max_speed[i] = config.jump_factor * l.velocity;
            }
            if limited(l.effort) {
                gates.max_torque[i] = config.torque_factor * l.effort;
            }
        }
        Ok(gates)
    }

    /// Checks the sample taken at `time`: every refused value of `q` and `tau` is replaced
    /// by NaN in place; returns the first refusal, if any. Non-finite values are left to
    /// the NaN path and not counted here.
    pub fn check(
        &mut self,
        time: f64,
        q: &mut [f64],
        tau: Option<&mut [f64]>,
    ) -> Option<GateFault> {
        if !self.enabled {
            return None;
        }
        let mut first = None;
        for i in 0..q.len().min(self.lower.len()) {
            let v = q[i];
            if !v.is_finite() {
                continue;
            }
            let gate = if v < self.lower[i] || v > self.upper[i] {
                Some(Implausible::Angle)
            } else if self.last_q[i].is_finite()
                && (v - self.last_q[i]).abs()
                    > self.max_speed[i] * (time - self.last_time[i]).abs().max(self.period)
            {
                Some(Implausible::Jump)
            } else {
                None
            };
            match gate {
                Some(gate) => {
                    q[i] = f64::NAN;
                    first = first.or(Some(GateFault { joint: i, gate }));
                }
                // A repeated reading is no news of when the angle was: a driver that repeats
                // its last packet (issue 34) would otherwise make the jump after it look
                // like one period's.
                None if v == self.last_q[i] => {}
                None => {
                    self.last_q[i] = v;
                    self.last_time[i] = time;
                }
            }
        }
        if let Some(tau) = tau {
            for i in 0..tau.len().min(self.max_torque.len()) {
                if tau[i].is_finite() && tau[i].abs() > self.max_torque[i] {
                    tau[i] = f64::NAN;
                    first = first.or(Some(GateFault {
                        joint: i,
                        gate: Implausible::Torque,
                    }));
                }
            }
        }
        if first.is_some() {
            self.faults += 1;
        }
        first
    }

    /// Checks measured velocities (a robot that reports them): every value beyond its
    /// joint's speed bound is replaced by NaN in place; returns the first refusal. A sample
    /// is counted once, with `counted` when [`Self::check`] already refused a value of it.
    pub fn check_velocity(&mut self, qdot: &mut [f64], counted: bool) -> Option<GateFault> {
        if !self.enabled {
            return None;
        }
        let mut first = None;
        for (i, v) in qdot.iter_mut().enumerate().take(self.max_speed.len()) {
            let bound = if self.max_speed[i].is_finite() {
                self.max_speed[i]
            } else {
                MEASURED_SPEED_BOUND
            };
            if v.is_finite() && v.abs() > bound {
                *v = f64::NAN;
                first = first.or(Some(GateFault {
                    joint: i,
                    gate: Implausible::Velocity,
                }));
            }
        }
        if first.is_some() && !counted {
            self.faults += 1;
        }
        first
    }

    /// Samples with at least one refused value so far.
    pub fn faults(&self) -> u64 {
        self.faults
    }

    /// Back to the state after construction (no accepted angle yet, no count).
    pub fn reset(&mut self) {
        self.last_q.fill(f64::NAN);
        self.last_time.fill(f64::NAN);
        self.faults = 0;
    }
}
