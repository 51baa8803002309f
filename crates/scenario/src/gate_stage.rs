//! The robot program's plausibility gates (issue 34) in a simulated run: the same
//! [`PlausibilityGates`] as `admittance_loop::RobotLoop`, with the same defaults, run on
//! the simulated sensors' raw readings before the signal chain sees them. A refused angle
//! or torque becomes NaN and takes the NaN path (the chain holds its filtered signals, the
//! controller commands its safe hold for that period), so that neither the observer nor the
//! admittance model integrates it; both go on from the next plausible sample. Refused
//! samples are counted by gate (`gated_samples`, docs/outputs.md).

use std::collections::BTreeMap;

use admittance_dynamics::Model;
use admittance_loop::{GateConfig, Implausible, LoopError, Measurement, PlausibilityGates};
use admittance_sim::{Sensors, SimError};

/// The gates between the simulated sensors and the signal chain, with their counts.
pub(crate) struct GateStage {
    gates: PlausibilityGates,
    /// Refused samples by the gate of their first refused value: angle, jump, torque.
    counts: [u64; 4],
}

impl GateStage {
    /// The gates of `model`'s joints with the scenario's settings (`[gates]`, a robot's
    /// defaults unless set), for samples `dt` seconds apart.
    pub fn new(model: &Model, config: &GateConfig, dt: f64) -> Result<Self, LoopError> {
        Ok(Self {
            gates: PlausibilityGates::new(model, config, dt)?,
            counts: [0; 4],
        })
    }

    /// `sensors`' sample at `time` of the true angles `q_true` with the torque reading
    /// `tau`, gated. Does not allocate.
    pub fn sample<'s>(
        &mut self,
        sensors: &'s mut Sensors,
        time: f64,
        q_true: &[f64],
        tau: &[f64],
    ) -> Result<&'s Measurement, SimError> {
        let gates = &mut self.gates;
        let mut refused = None;
        let m = sensors.sample_screened(time, q_true, tau, |t, q, tau| {
            refused = gates.check(t, q, Some(tau));
        })?;
        if let Some(fault) = refused {
            self.counts[match fault.gate {
                Implausible::Angle => 0,
                Implausible::Jump => 1,
                Implausible::Torque => 2,
                Implausible::Velocity => 3,
            }] += 1;
        }
        Ok(m)
    }

    /// `gated_samples`: refused samples by the gate of their first refused value.
    pub fn counts(&self) -> BTreeMap<String, u64> {
        ["angle", "jump", "torque", "velocity"]
            .iter()
            .zip(self.counts)
            .map(|(k, c)| (k.to_string(), c))
            .collect()
    }
}
