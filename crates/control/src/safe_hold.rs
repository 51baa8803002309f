//! The safe behaviour on faults: "hold with damping" (issue 3, "Bars"), shared by every
//! controller.

use std::sync::Arc;

use admittance_dynamics::{gravity_torque, Data, Model};
use serde::{Deserialize, Serialize};

use crate::config::{clamp_effort, effort_limits, Bound, JointValues};
use crate::controller::ControlInput;
use crate::error::{ConfigError, Fault, StepStatus};

fn default_damping() -> JointValues {
    JointValues::Uniform(0.5)
}
fn default_stale_steps() -> u32 {
    30
}
fn default_stale_velocity() -> f64 {
    0.3
}
fn yes() -> bool {
    true
}

/// Configuration of [`SafeHold`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SafeHoldConfig {
    /// `K_hold` (N m s/rad), per joint or one value; default 0.5. In a discrete loop at
    /// period `dt` the damping is stable only while `K_hold dt / I < 2` for the smallest
    /// effective joint inertia `I` (Baxter's w2: about 6e-4 kg m^2, so `K_hold < 1.2` at
    /// 1 kHz).
    #[serde(default = "default_damping")]
    pub damping: JointValues,
    /// `N`: a joint's measurement is stale when its position has been bit-identical to the
    /// previous sample for `N` consecutive steps while that joint is expected to move. Zero
    /// disables the check. Default 30: a joint held by static friction at a reversal, while
    /// the PD lags its reference, repeats its reading for several milliseconds (8 and 15 gave
    /// false alarms in the 450 s free-motion scenarios, 25 none). Shorter dropouts are still
    /// reported from the samples' time stamps (`stale_measurements`).
    #[serde(default = "default_stale_steps")]
    pub stale_steps: u32,
    /// Joint `i` is expected to move when its reference speed `|q_ref'_i|` exceeds this
    /// speed (rad/s), or when its reading was moving faster than this when it last changed
    /// (the change divided by the periods since the change before); default 0.3. Choose `N` and this speed so that
    /// `stale_velocity * N * dt` is well above the encoder quantisation: a slowly moving
    /// joint legitimately repeats its quantised angle for a few steps, and a joint held by
    /// static friction at a reversal repeats it while its reference moves on (defaults:
    /// 9e-3 rad in 30 steps at 1 kHz, 94 counts of a 16-bit encoder).
    #[serde(default = "default_stale_velocity")]
    pub stale_velocity: f64,
    /// Whether the hold includes the nominal gravity `G_nominal(q_hold)`; default true. Turn
    /// it off for a plant whose gravity is carried elsewhere.
    #[serde(default = "yes")]
    pub gravity_compensation: bool,
    /// Effort limits (N m) overriding the model's URDF effort limits.
    #[serde(default)]
    pub effort_limits: Option<JointValues>,
}

impl Default for SafeHoldConfig {
    fn default() -> Self {
        SafeHoldConfig {
            damping: default_damping(),
            stale_steps: default_stale_steps(),
            stale_velocity: default_stale_velocity(),
            gravity_compensation: true,
            effort_limits: None,
        }
    }
}

/// Input validation, staleness detection and the safe output shared by every controller.
///
/// **Safe behaviour ("hold with damping")**: on a fault the torque written is
///
/// ```text
///     tau_i = clamp( G_nominal,i(q_hold) - K_hold,i * qdot_i , -effort_i, effort_i )
/// ```
///
/// where `q_hold` is the last valid measured position (a finite, non-stale `q`),
/// `qdot_i` is taken as zero when it is not finite (or when `qdot` has the wrong length),
/// and the gravity term is zero before any valid position was seen (or when
/// [`SafeHoldConfig::gravity_compensation`] is off). Controllers freeze their adaptation
/// while faulted and resume the normal law at the first valid step.
///
/// **Faults detected**, in this order: wrong lengths (`q`, `qdot`, `q_ref`, `qdot_ref`,
/// `qddot_ref`, `external_torque_estimate`, `torque`); `dt` not finite and positive;
/// non-finite `q`; stale `q`; non-finite `qdot`; non-finite references; non-finite
/// estimate. [`finish`](SafeHold::finish) adds non-finite law outputs.
///
/// **Staleness**, per joint: each step whose finite `q_i` is bit-identical to the previous
/// sample while joint `i` is expected to move (see [`SafeHoldConfig::stale_velocity`]: its
/// reference is fast, or its reading was moving fast when it last changed) increments the
/// joint's counter; any change, or no expected motion before the counter
/// reaches `N` ([`SafeHoldConfig::stale_steps`]), resets it. The fault names the first joint
/// whose counter is at least `N` and lasts until that joint's reading changes.
#[derive(Clone, Debug)]
pub struct SafeHold {
    model: Arc<Model>,
    data: Data,
    limits: Vec<f64>,
    damping: Vec<f64>,
    stale_steps: u32,
    stale_velocity: f64,
    gravity_compensation: bool,
    q_hold: Vec<f64>,
    has_hold: bool,
    last_q: Vec<f64>,
    has_last_q: bool,
    /// Per joint: consecutive identical samples while motion was expected.
    identical: Vec<u32>,
    /// Per joint: valid samples since the reading last changed.
    since_change: Vec<u32>,
    /// Per joint: whether the reading moved faster than `stale_velocity` at its last change.
    /// A joint that was moving cannot stop within a period short of an impact, so a reading
    /// that then repeats is suspect even when the reference slows meanwhile (the observer
    /// reads a frozen encoder as a contact, and the admittance model slows the reference).
    moving_at_change: Vec<bool>,
    faults: u64,
    last_fault: Option<Fault>,
}

impl SafeHold {
    /// A safe hold for `model` (the nominal model) with `config`.
    pub fn new(model: Arc<Model>, config: &SafeHoldConfig) -> Result<Self, ConfigError> {
        let n = model.nq();
        let limits = effort_limits(&model, config.effort_limits.as_ref(), "effort_limits")?;
        let damping = config.damping.resolve("damping", n, Bound::NonNegative)?;
        let stale_velocity = Bound::NonNegative.check("stale_velocity", config.stale_velocity)?;
        let data = Data::new(&model);
        Ok(SafeHold {
            model,
            data,
            limits,
            damping,
            stale_steps: config.stale_steps,
            stale_velocity,
            gravity_compensation: config.gravity_compensation,
            q_hold: vec![0.0; n],
            has_hold: false,
            last_q: vec![0.0; n],
            has_last_q: false,
            identical: vec![0; n],
            since_change: vec![0; n],
            moving_at_change: vec![false; n],
            faults: 0,
            last_fault: None,
        })
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.limits.len()
    }

    /// The nominal model.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// Effort limits (N m) applied to every output.
    pub fn effort_limits(&self) -> &[f64] {
        &self.limits
    }

    /// The last valid measured position, if any.
    pub fn hold_position(&self) -> Option<&[f64]> {
        self.has_hold.then_some(&self.q_hold[..])
    }

    /// Number of faulted steps since construction or [`reset`](Self::reset).
    pub fn fault_count(&self) -> u64 {
        self.faults
    }

    /// The most recent fault, if any.
    pub fn last_fault(&self) -> Option<Fault> {
        self.last_fault
    }

    /// Forgets the hold position, the staleness history and the fault counters.
    pub fn reset(&mut self) {
        self.has_hold = false;
        self.has_last_q = false;
        self.identical.fill(0);
        self.since_change.fill(0);
        self.moving_at_change.fill(false);
        self.faults = 0;
        self.last_fault = None;
    }

    /// Validates `input`, `dt` and the length of `torque`, updating the staleness counter
    /// and the hold position. Call exactly once per step.
    pub fn check(&mut self, input: &ControlInput, dt: f64, torque_len: usize) -> Result<(), Fault> {
        let n = self.dof();
        let lengths: [(&'static str, usize); 7] = [
            ("q", input.q.len()),
            ("qdot", input.qdot.len()),
            ("q_ref", input.q_ref.len()),
            ("qdot_ref", input.qdot_ref.len()),
            ("qddot_ref", input.qddot_ref.len()),
            (
                "external_torque_estimate",
                input.external_torque_estimate.len(),
            ),
            ("torque", torque_len),
        ];
        for (argument, found) in lengths {
            if found != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found,
                });
            }
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Fault::InvalidTimeStep);
        }
        if let Some(joint) = first_non_finite(input.q) {
            return Err(Fault::NonFiniteMeasurement {
                argument: "q",
                joint,
            });
        }
        self.update_staleness(input.q, input.qdot_ref, dt);
        if self.stale_steps > 0 {
            if let Some(joint) = self.identical.iter().position(|&c| c >= self.stale_steps) {
                return Err(Fault::StaleMeasurement {
                    joint,
                    steps: self.identical[joint],
                });
            }
        }
        self.q_hold.copy_from_slice(input.q);
        self.has_hold = true;
        if let Some(joint) = first_non_finite(input.qdot) {
            return Err(Fault::NonFiniteMeasurement {
                argument: "qdot",
                joint,
            });
        }
        for (argument, values) in [
            ("q_ref", input.q_ref),
            ("qdot_ref", input.qdot_ref),
            ("qddot_ref", input.qddot_ref),
        ] {
            if let Some(joint) = first_non_finite(values) {
                return Err(Fault::NonFiniteReference { argument, joint });
            }
        }
        if let Some(joint) = first_non_finite(input.external_torque_estimate) {
            return Err(Fault::NonFiniteEstimate { joint });
        }
        Ok(())
    }

    fn update_staleness(&mut self, q: &[f64], qdot_ref: &[f64], dt: f64) {
        let fast = |x: f64| x.is_finite() && x.abs() > self.stale_velocity;
        for i in 0..self.identical.len() {
            let same = self.has_last_q && q[i].to_bits() == self.last_q[i].to_bits();
            if self.has_last_q && !same {
                // The reading's speed over its last change: the change over the periods
                // since the change before (a coarse encoder's single count after a long
                // plateau is slow, a fine encoder's counts every period are fast).
                let periods = f64::from(self.since_change[i]) + 1.0;
                self.moving_at_change[i] = fast((q[i] - self.last_q[i]) / (periods * dt));
                self.since_change[i] = 0;
            } else if self.has_last_q {
                self.since_change[i] = self.since_change[i].saturating_add(1);
            }
            // The reference, not the filtered measured velocity: that lags, and at a
            // reversal the encoder legitimately repeats while it still reads fast. Or the
            // reading itself was moving fast when it froze.
            let expected = fast(qdot_ref[i]) || self.moving_at_change[i];
            // Once stale, a joint stays stale until its reading changes: the reference may
            // slow down meanwhile (the loop is holding), which must not release the hold.
            let latched = self.stale_steps > 0 && self.identical[i] >= self.stale_steps;
            self.identical[i] = if same && (expected || latched) {
                self.identical[i].saturating_add(1)
            } else {
                0
            };
        }
        self.last_q.copy_from_slice(q);
        self.has_last_q = true;
    }

    /// Writes the safe hold torque (see the type's documentation) into `torque` (values
    /// beyond the joint count are set to zero; missing ones are not written) and records
    /// `fault`. Returns `StepStatus::Fault(fault)`.
    pub fn hold(&mut self, fault: Fault, qdot: &[f64], torque: &mut [f64]) -> StepStatus {
        let n = self.dof();
        self.faults += 1;
        self.last_fault = Some(fault);
        let gravity = if self.gravity_compensation && self.has_hold {
            gravity_torque(&self.model, &mut self.data, &self.q_hold).ok()
        } else {
            None
        };
        for (i, t) in torque.iter_mut().enumerate() {
            if i >= n {
                *t = 0.0;
                continue;
            }
            let g = gravity.map_or(0.0, |g| g[i]);
            let v = if qdot.len() == n && qdot[i].is_finite() {
                qdot[i]
            } else {
                0.0
            };
            let tau = g - self.damping[i] * v;
            *t = clamp_effort(if tau.is_finite() { tau } else { 0.0 }, self.limits[i]);
        }
        StepStatus::Fault(fault)
    }

    /// [`check`](Self::check), and on a fault the [`hold`](Self::hold): returns
    /// `Err(status)` when the hold was written, `Ok(())` when the law may run.
    pub fn guard(
        &mut self,
        input: &ControlInput,
        dt: f64,
        torque: &mut [f64],
    ) -> Result<(), StepStatus> {
        match self.check(input, dt, torque.len()) {
            Ok(()) => Ok(()),
            Err(fault) => Err(self.hold(fault, input.qdot, torque)),
        }
    }

    /// Ends a step whose law wrote `torque` (length already checked): a non-finite entry
    /// replaces the whole output by the hold ([`Fault::NonFiniteOutput`]); otherwise every
    /// entry is clamped to the effort limits and `StepStatus::Ok` is returned.
    pub fn finish(&mut self, qdot: &[f64], torque: &mut [f64]) -> StepStatus {
        if let Some(joint) = first_non_finite(torque) {
            return self.hold(Fault::NonFiniteOutput { joint }, qdot, torque);
        }
        for (t, l) in torque.iter_mut().zip(&self.limits) {
            *t = clamp_effort(*t, *l);
        }
        StepStatus::Ok
    }
}

/// Index of the first non-finite value.
#[inline]
pub(crate) fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}
