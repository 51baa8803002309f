//! Baseline controllers in the same harness as the paper's controller (issue 3, item 3):
//! joint-space PD, PD with nominal gravity compensation, and computed torque with the
//! nominal model. All clamp to the effort limits and use [`SafeHold`] on faults. None of
//! them uses the external-torque estimate.

use std::sync::Arc;

use admittance_dynamics::{gravity_torque, rnea, Data, Model};
use serde::{Deserialize, Serialize};

use crate::config::{Bound, JointValues};
use crate::controller::{ControlInput, Controller};
use crate::error::{ConfigError, Fault, StepStatus};
use crate::safe_hold::{SafeHold, SafeHoldConfig};

/// Configuration of [`PdController`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PdConfig {
    /// Proportional gains `Kp >= 0` (N m/rad).
    pub kp: JointValues,
    /// Derivative gains `Kd >= 0` (N m s/rad).
    pub kd: JointValues,
    /// Add the nominal gravity `G(q)` (the `pd_gravity` baseline).
    #[serde(default)]
    pub gravity_compensation: bool,
    /// The safe hold used on faults.
    #[serde(default)]
    pub safe_hold: SafeHoldConfig,
}

/// Joint-space PD: `tau = Kp (q_r - q) + Kd (q_r' - q')` (+ `G_nominal(q)` with
/// `gravity_compensation`), clamped. Name `"pd"` or `"pd_gravity"`.
#[derive(Clone, Debug)]
pub struct PdController {
    kp: Vec<f64>,
    kd: Vec<f64>,
    gravity: bool,
    data: Data,
    hold: SafeHold,
}

impl PdController {
    /// A PD controller on the nominal `model`.
    pub fn new(model: Arc<Model>, config: &PdConfig) -> Result<Self, ConfigError> {
        let n = model.nq();
        let kp = config.kp.resolve("kp", n, Bound::NonNegative)?;
        let kd = config.kd.resolve("kd", n, Bound::NonNegative)?;
        let data = Data::new(&model);
        let hold = SafeHold::new(model, &config.safe_hold).map_err(|e| e.within("safe_hold"))?;
        Ok(PdController {
            kp,
            kd,
            gravity: config.gravity_compensation,
            data,
            hold,
        })
    }

    /// The safe hold (effort limits, fault counters).
    pub fn safe_hold(&self) -> &SafeHold {
        &self.hold
    }
}

impl Controller for PdController {
    fn name(&self) -> &str {
        if self.gravity {
            "pd_gravity"
        } else {
            "pd"
        }
    }

    fn dof(&self) -> usize {
        self.kp.len()
    }

    fn step(&mut self, input: &ControlInput, dt: f64, torque: &mut [f64]) -> StepStatus {
        if let Err(status) = self.hold.guard(input, dt, torque) {
            return status;
        }
        for (i, t) in torque.iter_mut().enumerate() {
            *t = self.kp[i] * (input.q_ref[i] - input.q[i])
                + self.kd[i] * (input.qdot_ref[i] - input.qdot[i]);
        }
        if self.gravity {
            match gravity_torque(self.hold.model(), &mut self.data, input.q) {
                Ok(g) => torque.iter_mut().zip(g.iter()).for_each(|(t, g)| *t += g),
                Err(_) => {
                    return self
                        .hold
                        .hold(Fault::Internal("gravity_torque"), input.qdot, torque)
                }
            }
        }
        self.hold.finish(input.qdot, torque)
    }

    fn reset(&mut self) {
        self.hold.reset();
    }
}

/// Configuration of [`ComputedTorqueController`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComputedTorqueConfig {
    /// `Kp >= 0` (1/s^2).
    pub kp: JointValues,
    /// `Kd >= 0` (1/s).
    pub kd: JointValues,
    /// The safe hold used on faults.
    #[serde(default)]
    pub safe_hold: SafeHoldConfig,
}

/// Computed torque with the nominal model:
/// `tau = M(q) (q_r'' + Kd (q_r' - q') + Kp (q_r - q)) + C(q, q') q' + G(q)`, evaluated as one
/// RNEA call `rnea(q, q', a)`, clamped. Name `"computed_torque"`.
#[derive(Clone, Debug)]
pub struct ComputedTorqueController {
    kp: Vec<f64>,
    kd: Vec<f64>,
    acc: Vec<f64>,
    data: Data,
    hold: SafeHold,
}

impl ComputedTorqueController {
    /// A computed-torque controller on the nominal `model`.
    pub fn new(model: Arc<Model>, config: &ComputedTorqueConfig) -> Result<Self, ConfigError> {
        let n = model.nq();
        let kp = config.kp.resolve("kp", n, Bound::NonNegative)?;
        let kd = config.kd.resolve("kd", n, Bound::NonNegative)?;
        let data = Data::new(&model);
        let hold = SafeHold::new(model, &config.safe_hold).map_err(|e| e.within("safe_hold"))?;
        Ok(ComputedTorqueController {
            kp,
            kd,
            acc: vec![0.0; n],
            data,
            hold,
        })
    }

    /// The safe hold (effort limits, fault counters).
    pub fn safe_hold(&self) -> &SafeHold {
        &self.hold
    }
}

impl Controller for ComputedTorqueController {
    fn name(&self) -> &str {
        "computed_torque"
    }

    fn dof(&self) -> usize {
        self.kp.len()
    }

    fn step(&mut self, input: &ControlInput, dt: f64, torque: &mut [f64]) -> StepStatus {
        if let Err(status) = self.hold.guard(input, dt, torque) {
            return status;
        }
        for i in 0..self.acc.len() {
            self.acc[i] = input.qddot_ref[i]
                + self.kd[i] * (input.qdot_ref[i] - input.qdot[i])
                + self.kp[i] * (input.q_ref[i] - input.q[i]);
        }
        match rnea(
            self.hold.model(),
            &mut self.data,
            input.q,
            input.qdot,
            &self.acc,
        ) {
            Ok(tau) => torque.copy_from_slice(tau.as_slice()),
            Err(_) => return self.hold.hold(Fault::Internal("rnea"), input.qdot, torque),
        }
        self.hold.finish(input.qdot, torque)
    }

    fn reset(&mut self) {
        self.hold.reset();
    }
}
