//! The observer stage of a loop (docs/method.md sections 5 and 7): the observer fed the
//! sensors' signals, optionally through a second conditioning stage, its estimate
//! low-passed and held at zero during a warm-up.

use admittance_control::{Observer, ObserverInput};

use crate::conditioning::InputConditioner;
use crate::delay::InputDelay;
use crate::error::LoopError;
use crate::estimate_filter::EstimateLowPass;
use crate::signal::Measurement;

/// An observer with what it is fed: the sensors' signals, optionally through a second
/// conditioning stage (`observer.input_filter_hz`), its estimate low-passed and held at
/// zero during a warm-up.
pub struct ObserverStage {
    observer: Box<dyn Observer + Send>,
    conditioner: Option<InputConditioner>,
    /// The identification's torque delay behind the motion, applied after the conditioning.
    delay: Option<InputDelay>,
    delayed_torque: bool,
    previous_filtered_torque: Vec<f64>,
    raw: Vec<f64>,
    alpha: f64,
    warmup: f64,
    /// Per joint, the positions `[min, max]` the observer's identification was fitted on
    /// (empty without an identification that records them).
    training_range: Vec<[f64; 2]>,
    /// Per joint, the highest speed the identification was fitted at (empty: none).
    training_speed: Vec<f64>,
    /// Whether the last input's velocity exceeded `training_speed` (beyond its margin).
    faster_than_training: bool,
}

/// How an [`ObserverStage`] feeds its observer and shapes its estimate (the `[observer]`
/// settings of a [`crate::LoopConfig`], resolved).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObserverStageSettings {
    /// Cut-off (Hz) of the second 2nd-order low-pass on the observer's inputs
    /// ([`InputConditioner`]); 0: the sensors' signals as they are.
    pub input_filter_hz: f64,
    /// Cut-off (Hz) of the first-order low-pass of the estimate; 0: not filtered.
    pub cutoff_hz: f64,
    /// Warm-up (s): the estimate is zero before this time.
    pub warmup: f64,
    /// Feed the filtered command one sample late (the pairing with `q''` of the
    /// free-motion data the learned networks were trained on, docs/outputs.md).
    pub delayed_torque: bool,
    /// Control rate (Hz): one update per period `1 / rate_hz`.
    pub rate_hz: f64,
}

impl ObserverStage {
    /// `observer` fed and filtered as `settings` say; an error (at
    /// `observer.input_filter_hz`) when the input filter does not fit the rate.
    pub fn new(
        observer: Box<dyn Observer + Send>,
        settings: &ObserverStageSettings,
    ) -> Result<Self, LoopError> {
        let n = observer.dof();
        let conditioner = if settings.input_filter_hz > 0.0 {
            let c = InputConditioner::new(n, settings.input_filter_hz, settings.rate_hz)
                .map_err(|e| e.at("observer.input_filter_hz"))?;
            Some(c)
        } else {
            None
        };
        // First-order low-pass of the estimate: alpha = dt / (dt + 1 / (2 pi f_c)).
        let alpha = EstimateLowPass::alpha(settings.cutoff_hz, settings.rate_hz);
        Ok(Self {
            observer,
            conditioner,
            delay: None,
            delayed_torque: settings.delayed_torque,
            previous_filtered_torque: vec![0.0; n],
            raw: vec![0.0; n],
            alpha,
            warmup: settings.warmup,
            training_range: Vec::new(),
            training_speed: Vec::new(),
            faster_than_training: false,
        })
    }

    /// Feeds the observer each joint's torque with the motion `delay_s[i]` older (negative:
    /// the torque older), as an identification with those delays was fitted
    /// (`IdentificationSummary::delay_s`); an error (at `observer.identification`) for a
    /// delay that is not a number of at most 1 s.
    pub fn with_torque_delay(mut self, delay_s: &[f64], rate_hz: f64) -> Result<Self, LoopError> {
        if delay_s.len() != self.raw.len() && !delay_s.is_empty() {
            return Err(LoopError::invalid(
                "observer.identification",
                format!(
                    "holds {} torque delays for {} joints (identify the arm again)",
                    delay_s.len(),
                    self.raw.len()
                ),
            ));
        }
        self.delay = InputDelay::new(delay_s, rate_hz)?;
        Ok(self)
    }

    /// The stage with the training range of its observer's identification
    /// (`IdentificationSummary::training_range`; empty: none recorded).
    pub fn with_training_range(mut self, range: Vec<[f64; 2]>) -> Self {
        self.training_range = range;
        self
    }

    /// Per joint, the positions the observer's identification was fitted on (empty when
    /// it records none, or the observer runs on no identification).
    pub(crate) fn training_range(&self) -> &[[f64; 2]] {
        &self.training_range
    }

    /// The stage with the training speeds of its observer's identification
    /// (`IdentificationSummary::training_speed`; empty: none recorded).
    pub fn with_training_speed(mut self, highest: Vec<f64>) -> Self {
        self.training_speed = highest;
        self
    }

    /// Whether the velocity of the last input the observer was fed (conditioned and delayed
    /// as its identification was fitted) exceeded the identification's training speeds by
    /// more than their margin ([`admittance_dynamics::faster_than_training`]).
    pub(crate) fn faster_than_training(&self) -> bool {
        self.faster_than_training
    }

    /// Per joint, the highest speed the observer's identification was fitted at (empty
    /// when it records none, or the observer runs on no identification).
    pub(crate) fn training_speed(&self) -> &[f64] {
        &self.training_speed
    }

    /// Updates `estimate` from the measurement at `time`; false when the observer
    /// reported a fault.
    pub(crate) fn update(
        &mut self,
        time: f64,
        m: &Measurement,
        dt: f64,
        estimate: &mut [f64],
    ) -> bool {
        let tau_in: &[f64] = if self.delayed_torque {
            &self.previous_filtered_torque
        } else {
            &m.tau_filtered
        };
        let input = match self.conditioner.as_mut() {
            Some(c) => {
                c.update(&m.q_filtered, tau_in);
                ObserverInput {
                    time,
                    q: &c.q,
                    qdot: &c.qdot,
                    qddot: &c.qddot,
                    tau_commanded: &c.tau,
                }
            }
            None => ObserverInput {
                time,
                q: &m.q_filtered,
                qdot: &m.qdot,
                qddot: &m.qddot,
                tau_commanded: tau_in,
            },
        };
        let input = match self.delay.as_mut() {
            Some(delay) => {
                let n = input.q.len();
                let d = delay.update(input.q, input.qdot, input.qddot, input.tau_commanded);
                ObserverInput {
                    time,
                    q: &d[..n],
                    qdot: &d[n..2 * n],
                    qddot: &d[2 * n..3 * n],
                    tau_commanded: &d[3 * n..],
                }
            }
            None => input,
        };
        self.faster_than_training =
            admittance_dynamics::faster_than_training(&self.training_speed, input.qdot);
        let ok = self.observer.update(&input, dt, &mut self.raw).is_ok();
        if time < self.warmup {
            self.raw.fill(0.0);
        }
        EstimateLowPass::step(self.alpha, &self.raw, estimate);
        self.previous_filtered_torque
            .copy_from_slice(&m.tau_filtered);
        ok
    }

    /// The observer's coverage of its last input ([`Observer::coverage`]).
    pub(crate) fn coverage(&self) -> Option<f64> {
        self.observer.coverage()
    }
}
