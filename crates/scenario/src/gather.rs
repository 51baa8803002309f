//! What a variant's run gathers step by step into its [`VariantMetrics`]: the control
//! step's counts (faults, limits, timing), the evaluation window's statistics and the run's
//! health.

use admittance_dynamics::{outside_training_range, JointKind, Model};
use admittance_loop::{ClosedLoop, LoopStatus, Measurement};
use admittance_sim::StepRecord;

use crate::hand::HandStats;
use crate::metrics::{median, rms, JointStats, ObserverStats, VariantMetrics};
use admittance_loop::HealthMonitor as Health;

/// Controller step times kept for the median (at most; evenly strided over the run).
const MAX_TIMINGS: usize = 200_000;

/// The accumulators of one variant.
pub(crate) struct Gather {
    effort: Vec<f64>,
    steps: usize,
    timing_stride: usize,
    step_times: Vec<f64>,
    faults: usize,
    stale_measurements: usize,
    limit_violations: usize,
    nonfinite_torques: usize,
    observer_faults: usize,
    /// Steps outside the observer's identification's training range and faster than its
    /// training speeds (each `None` while it records none).
    outside_training_range: Option<usize>,
    faster_than_training: Option<usize>,
    /// Per joint, whether it turns without limit (its angle counts on the nearest turn).
    continuous: Vec<bool>,
    tracking: JointStats,
    torque: JointStats,
    estimate_error: JointStats,
    observer: ObserverStats,
    ee_errors: Vec<f64>,
    deadzone_steps: Vec<usize>,
    window_steps: usize,
    /// Minimum and sum of the observer's coverage over the window.
    coverage: Option<(f64, f64)>,
    pub health: Health,
    pub hand: Option<HandStats>,
}

/// One step's values in the evaluation window.
pub(crate) struct WindowSample<'a> {
    pub q_r: &'a [f64],
    pub q: &'a [f64],
    pub torque: &'a [f64],
    pub estimate: &'a [f64],
    pub record: &'a StepRecord,
    pub q_r_oracle: Option<&'a [f64]>,
    pub ee_error: f64,
    pub hand: Option<(&'a [f64; 3], &'a [f64])>,
    pub coverage: Option<f64>,
}

impl Gather {
    /// For `steps` control steps of the arm `model` with (scaled) effort limits `effort`.
    pub fn new(
        model: &Model,
        joints: &[String],
        effort: &[f64],
        steps: usize,
        with_hand: bool,
    ) -> Self {
        let n = joints.len();
        Self {
            effort: effort.to_vec(),
            steps,
            timing_stride: (steps / MAX_TIMINGS).max(1),
            step_times: Vec::with_capacity(steps.min(MAX_TIMINGS)),
            faults: 0,
            stale_measurements: 0,
            limit_violations: 0,
            nonfinite_torques: 0,
            observer_faults: 0,
            outside_training_range: None,
            faster_than_training: None,
            continuous: model
                .joints
                .iter()
                .map(|j| j.kind == JointKind::Continuous)
                .collect(),
            tracking: JointStats::new(n),
            torque: JointStats::new(n),
            estimate_error: JointStats::new(n),
            observer: ObserverStats::new(n),
            ee_errors: Vec::new(),
            deadzone_steps: vec![0; n],
            window_steps: 0,
            coverage: None,
            health: Health::new(model, joints, effort),
            hand: with_hand.then(HandStats::default),
        }
    }

    /// After the loop's step `k` on the measured angles `q`: faults, timing, the command
    /// against the effort limits, where the observer's identification extrapolated.
    pub fn after_control(
        &mut self,
        k: usize,
        status: &LoopStatus,
        lp: &ClosedLoop,
        q: &[f64],
        stale_sample: bool,
    ) {
        if !status.observer_ok {
            self.observer_faults += 1;
        }
        let range = lp.observer_training_range();
        if !range.is_empty() {
            let outside = outside_training_range(range, q, &self.continuous);
            *self.outside_training_range.get_or_insert(0) += usize::from(outside);
        }
        if !lp.observer_training_speed().is_empty() {
            let faster = lp.observer_faster_than_training();
            *self.faster_than_training.get_or_insert(0) += usize::from(faster);
        }
        if k.is_multiple_of(self.timing_stride)
            && self.step_times.len() < self.step_times.capacity()
        {
            self.step_times.push(lp.controller_seconds() * 1e6);
        }
        if !status.controller.is_ok() {
            self.faults += 1;
        }
        let held_stale = matches!(
            status.controller.fault(),
            Some(admittance_control::Fault::StaleMeasurement { .. })
        );
        if held_stale || stale_sample {
            self.stale_measurements += 1;
        }
        for (i, t_i) in lp.torque().iter().enumerate() {
            if !t_i.is_finite() {
                self.nonfinite_torques += 1;
            } else if t_i.abs() > self.effort[i] * (1.0 + 1e-12) {
                self.limit_violations += 1;
            }
        }
        if let Some(sat) = lp.admittance().and_then(|a| a.saturation()) {
            for (i, r) in lp.q_r().iter().enumerate() {
                let (c, h) = (sat.centre()[i], sat.half_range()[i]);
                if !(*r > c - h && *r < c + h) {
                    self.observer.bound_violations += 1;
                }
            }
        }
    }

    /// After the plant's step: the health check (true when the variant must stop there).
    pub fn diverged(
        &mut self,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        m: &Measurement,
        lp: &ClosedLoop,
    ) -> bool {
        self.health
            .add(t, q, qdot, m, lp.torque(), lp.external_torque_estimate())
            .is_some()
    }

    /// A step inside the evaluation window.
    pub fn in_window(&mut self, s: &WindowSample<'_>) {
        self.tracking.add(s.q_r.iter().zip(s.q).map(|(r, q)| r - q));
        self.torque.add(s.torque.iter().copied());
        self.estimate_error
            .add(s.estimate.iter().zip(&s.record.tau_ext).map(|(e, t)| e - t));
        self.observer
            .add(s.estimate, &s.record.tau_ext, s.q_r, s.q_r_oracle);
        self.ee_errors.push(s.ee_error);
        if let (Some(h), Some((f, f_hat))) = (self.hand.as_mut(), s.hand) {
            h.add(f, f_hat);
        }
        self.window_steps += 1;
        if let Some(c) = s.coverage {
            let (min, sum) = self.coverage.get_or_insert((f64::INFINITY, 0.0));
            *min = min.min(c);
            *sum += c;
        }
        for (c, dz) in self.deadzone_steps.iter_mut().zip(&s.record.in_deadzone) {
            *c += *dz as usize;
        }
    }

    /// The metrics (without those of the observer's training and of the networks).
    pub fn finish(mut self, with_oracle_reference: bool) -> (VariantMetrics, Health) {
        let [q_limit_violation_fraction, torque_saturation_fraction, estimate_saturation_fraction] =
            self.health.fractions_all();
        let mut metrics = VariantMetrics {
            diverged: self.health.divergence.is_some(),
            diverged_at: self.health.divergence.as_ref().map(|d| d.time),
            q_limit_violation_fraction,
            torque_saturation_fraction,
            estimate_saturation_fraction,
            tracking_rmse: self.tracking.rms(),
            tracking_max_abs: self.tracking.max_abs.clone(),
            ee_error_rms: rms(&self.ee_errors),
            ee_error_max: self.ee_errors.iter().cloned().fold(0.0, f64::max),
            torque_rms: self.torque.rms(),
            torque_max_abs: self.torque.max_abs.clone(),
            deadzone_time_fraction: self
                .deadzone_steps
                .iter()
                .map(|c| *c as f64 / self.window_steps.max(1) as f64)
                .collect(),
            controller_step_median_us: median(&mut self.step_times),
            faults: self.faults,
            stale_measurements: self.stale_measurements,
            torque_limit_violations: self.limit_violations,
            nonfinite_torques: self.nonfinite_torques,
            steps: self.steps,
            external_torque_rmse: self.estimate_error.rms(),
            observer_faults: self.observer_faults,
            steps_outside_training_range: self.outside_training_range,
            steps_faster_than_training: self.faster_than_training,
            estimate_coverage_min: self.coverage.map(|(min, _)| min),
            estimate_coverage_mean: self
                .coverage
                .map(|(_, sum)| sum / self.window_steps.max(1) as f64),
            ..VariantMetrics::default()
        };
        self.observer.finish(&mut metrics, with_oracle_reference);
        metrics.hand = self.hand.map(|h| h.finish());
        (metrics, self.health)
    }
}
