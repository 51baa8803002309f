//! The checks of a [`LoopConfig`] that serde cannot make (signs, ranges, combinations),
//! made once, each problem at its dotted key.

use crate::config::{ControllerKind, LoopConfig, ObserverKind};
use crate::error::LoopError;

/// The fastest control rate a loop accepts (Hz): a 10 us period, beyond any robot's bus.
const MAX_CONTROL_RATE_HZ: f64 = 100_000.0;

impl<Training> LoopConfig<Training> {
    /// Every problem of the settings, each at its key (empty: valid). The components
    /// check their own tables again when they are built ([`crate::ClosedLoop::from_config`]).
    pub fn problems(&self) -> Vec<LoopError> {
        let mut out = Vec::new();
        if !(self.control_rate_hz > 0.0 && self.control_rate_hz <= MAX_CONTROL_RATE_HZ) {
            out.push(LoopError::invalid(
                "control_rate_hz",
                format!(
                    "is {}, must be in (0, {MAX_CONTROL_RATE_HZ}] Hz",
                    self.control_rate_hz
                ),
            ));
        }
        self.controller_problems(&mut out);
        self.observer_problems(&mut out);
        if self.task_admittance.is_some() && self.admittance.as_ref().is_some_and(|a| a.enabled) {
            out.push(
                LoopError::invalid("task_admittance", "a loop has one admittance model: [admittance] (joint space) or [task_admittance] (the hand), not both")
                    .hint("remove one of the two tables, or set admittance.enabled = false"),
            );
        }
        out
    }

    /// The first of [`LoopConfig::problems`], if any.
    pub fn validate(&self) -> Result<(), LoopError> {
        match self.problems().into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn controller_problems(&self, out: &mut Vec<LoopError>) {
        match self.controller.kind {
            ControllerKind::Pd if self.controller.pd.is_none() => out.push(
                LoopError::invalid(
                    "controller.pd",
                    "kind = \"pd\" needs a [controller.pd] table",
                )
                .hint("give kp and kd"),
            ),
            ControllerKind::ComputedTorque if self.controller.computed_torque.is_none() => out
                .push(LoopError::invalid(
                    "controller.computed_torque",
                    "kind = \"computed_torque\" needs a [controller.computed_torque] table",
                )),
            _ => {}
        }
    }

    fn observer_problems(&self, out: &mut Vec<LoopError>) {
        let o = &self.observer;
        if !(o.nominal_inertia_scale.is_finite() && o.nominal_inertia_scale > 0.0) {
            out.push(LoopError::invalid(
                "observer.nominal_inertia_scale",
                format!("is {}, must be > 0", o.nominal_inertia_scale),
            ));
        }
        if o.identification.is_some() {
            if !matches!(o.kind, ObserverKind::Momentum | ObserverKind::Hybrid) {
                out.push(LoopError::invalid(
                    "observer.identification",
                    format!(
                        "is used by kind = \"momentum\" and \"hybrid\" only, not {:?}",
                        o.kind
                    ),
                ));
            }
            if o.nominal_inertia_scale != 1.0 {
                out.push(LoopError::invalid(
                    "observer.nominal_inertia_scale",
                    "must be 1 with observer.identification (the identified model is the nominal one)",
                ));
            }
        }
        if !(o.cutoff_hz.is_finite() && o.cutoff_hz >= 0.0) {
            out.push(LoopError::invalid(
                "observer.cutoff_hz",
                format!("is {}, must be >= 0 (0: no filter)", o.cutoff_hz),
            ));
        }
        if !(o.warmup.is_finite() && o.warmup >= 0.0) {
            out.push(LoopError::invalid(
                "observer.warmup",
                format!("is {}, must be >= 0 s", o.warmup),
            ));
        }
        let nyquist = 0.5 * self.control_rate_hz;
        if !(o.input_filter_hz.is_finite()
            && o.input_filter_hz >= 0.0
            && o.input_filter_hz < nyquist)
        {
            out.push(LoopError::invalid(
                "observer.input_filter_hz",
                format!(
                    "is {}, must be in [0, {nyquist}) Hz (0: no second filter)",
                    o.input_filter_hz
                ),
            ));
        }
    }
}
