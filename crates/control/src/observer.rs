//! External-torque observers (docs/method.md section 5): the interface, and the two trivial
//! sources used before the learned observer exists (issue 3: "none, or the true value for
//! now").

use crate::error::{Fault, StepStatus};
use crate::safe_hold::first_non_finite;

/// What an observer is given at each step. All slices have one value per joint; `qddot` is
/// the filtered numerical acceleration (never the plant's true one, docs/method.md section 1).
#[derive(Clone, Copy, Debug)]
pub struct ObserverInput<'a> {
    /// Time of the sample (s).
    pub time: f64,
    /// Measured positions.
    pub q: &'a [f64],
    /// Measured velocities.
    pub qdot: &'a [f64],
    /// Estimated accelerations.
    pub qddot: &'a [f64],
    /// The torque the controller commanded.
    pub tau_commanded: &'a [f64],
}

/// A source of `tau_ext_hat` (docs/method.md section 0 sign: the torque the environment applies to
/// the robot).
pub trait Observer {
    /// A short identifier.
    fn name(&self) -> &str;
    /// Number of joints.
    fn dof(&self) -> usize;
    /// Writes the estimate (always finite) into `estimate`; on a fault writes zeros and
    /// reports it. Never panics, never allocates.
    fn update(&mut self, input: &ObserverInput, dt: f64, estimate: &mut [f64]) -> StepStatus;
    /// Back to the state just after construction.
    fn reset(&mut self);
    /// How well the last input lies inside the data a learned part was trained on, in
    /// [0, 1] (1 inside; docs/method.md section 8); `None` for an observer without one.
    fn coverage(&self) -> Option<f64> {
        None
    }
}

fn check_lengths(n: usize, estimate: &[f64]) -> Result<(), Fault> {
    if estimate.len() != n {
        return Err(Fault::WrongLength {
            argument: "estimate",
            expected: n,
            found: estimate.len(),
        });
    }
    Ok(())
}

/// No observer: the estimate is always zero.
#[derive(Clone, Debug)]
pub struct NoObserver {
    n: usize,
}

impl NoObserver {
    /// For `n` joints.
    pub fn new(n: usize) -> Self {
        NoObserver { n }
    }
}

impl Observer for NoObserver {
    fn name(&self) -> &str {
        "none"
    }
    fn dof(&self) -> usize {
        self.n
    }
    fn update(&mut self, _input: &ObserverInput, _dt: f64, estimate: &mut [f64]) -> StepStatus {
        estimate.fill(0.0);
        check_lengths(self.n, estimate).into()
    }
    fn reset(&mut self) {}
}

/// The oracle: the harness feeds it the true external torque with
/// [`set_true_value`](OracleObserver::set_true_value) before each update, and it returns
/// it unchanged.
#[derive(Clone, Debug)]
pub struct OracleObserver {
    value: Vec<f64>,
}

impl OracleObserver {
    /// For `n` joints, initially zero.
    pub fn new(n: usize) -> Self {
        OracleObserver {
            value: vec![0.0; n],
        }
    }

    /// Sets the true external torque. Values beyond the joint count are ignored, missing
    /// ones keep their previous value; non-finite values are stored and reported as a fault
    /// by the next update.
    pub fn set_true_value(&mut self, tau_ext: &[f64]) {
        let k = tau_ext.len().min(self.value.len());
        self.value[..k].copy_from_slice(&tau_ext[..k]);
    }

    /// The stored value.
    pub fn value(&self) -> &[f64] {
        &self.value
    }
}

impl Observer for OracleObserver {
    fn name(&self) -> &str {
        "oracle"
    }
    fn dof(&self) -> usize {
        self.value.len()
    }
    fn update(&mut self, _input: &ObserverInput, _dt: f64, estimate: &mut [f64]) -> StepStatus {
        if let Err(f) = check_lengths(self.value.len(), estimate) {
            estimate.fill(0.0);
            return StepStatus::Fault(f);
        }
        if let Some(joint) = first_non_finite(&self.value) {
            estimate.fill(0.0);
            return StepStatus::Fault(Fault::NonFiniteEstimate { joint });
        }
        estimate.copy_from_slice(&self.value);
        StepStatus::Ok
    }
    fn reset(&mut self) {
        self.value.fill(0.0);
    }
}
