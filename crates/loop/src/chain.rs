//! The encoder side of the real signal chain (docs/method.md sections 1 and 7): velocities and
//! accelerations only by numerical differentiation of the low-pass-filtered angles, and the
//! commanded torque through the same filter, so that an observer can pair signals with
//! matching delays.
//!
//! Per sample (one per control period) and joint:
//!
//! 1. `q_filtered = LP(q)`, with `LP` a causal 2nd-order Butterworth low-pass
//!    ([`LowPass`], bilinear transform with pre-warping) at the cut-off, started at steady
//!    state on the first sample. `qdot = (q_filtered[k] - q_filtered[k-1]) / dt`,
//!    `qddot = (qdot[k] - qdot[k-1]) / dt` (zero until there are enough samples).
//! 2. `tau_filtered = LP(tau_commanded)` with the same filter.
//!
//! Delays at low frequency: `q_filtered` and `tau_filtered` lag by the filter's group
//! delay ([`LowPass::dc_group_delay`]); `qdot` by half a sample more, `qddot` by one
//! sample more. An observer that pairs `qddot` with torque should delay `tau_filtered`
//! by one sample.
//!
//! A non-finite angle reaches [`Measurement::q`] as it is; the joint's filter, velocity and
//! acceleration hold their previous values, so the derived signals stay finite (NaN only
//! before the joint's first valid sample: nothing to hold).

use crate::error::{check_len, LoopError};
use crate::frozen::FrozenReadings;
use crate::signal::{LowPass, Measurement};

/// Filtered differentiation of encoder angles, and the command through the same filter;
/// allocation-free per sample.
#[derive(Clone, Debug)]
pub struct SignalChain {
    n: usize,
    dt: f64,
    q_filter: LowPass,
    tau_filter: LowPass,
    /// Valid samples seen per joint (saturates at 2).
    valid: Vec<u8>,
    prev_qf: Vec<f64>,
    prev_qdot: Vec<f64>,
    measurement: Measurement,
    /// Readings repeated while the joint was moving (`crate::frozen`).
    frozen: FrozenReadings,
}

impl SignalChain {
    /// For `n` joints sampled at `sample_rate_hz` (normally the control rate), the low-pass
    /// at `filter_cutoff_hz` (0: none; below half the sample rate).
    pub fn new(n: usize, filter_cutoff_hz: f64, sample_rate_hz: f64) -> Result<Self, LoopError> {
        Ok(Self {
            n,
            dt: 1.0 / sample_rate_hz,
            q_filter: LowPass::butterworth2(filter_cutoff_hz, sample_rate_hz, n)?,
            tau_filter: LowPass::butterworth2(filter_cutoff_hz, sample_rate_hz, n)?,
            valid: vec![0; n],
            prev_qf: vec![0.0; n],
            prev_qdot: vec![0.0; n],
            measurement: Measurement::new(n),
            frozen: FrozenReadings::new(n),
        })
    }

    /// Back to the state before the first sample.
    pub fn reset(&mut self) {
        self.q_filter.reset();
        self.tau_filter.reset();
        self.valid.fill(0);
        self.prev_qf.fill(0.0);
        self.prev_qdot.fill(0.0);
        self.measurement = Measurement::new(self.n);
        self.frozen.reset();
    }

    /// Frozen readings so far: episodes in which a joint's angle, given by [`Self::sample`],
    /// stayed bit-identical for at least 10 ms after changing at more than 0.3 rad/s (a
    /// driver repeating its last packet; see `frozen.rs`). During such an episode the
    /// joint's [`Measurement::sample_time`] is when the reading last changed.
    pub fn stale_episodes(&self) -> u64 {
        self.frozen.episodes()
    }

    /// Sample period (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The filter applied to q and tau (for its delay).
    pub fn filter(&self) -> &LowPass {
        &self.q_filter
    }

    /// The last measurement.
    pub fn measurement(&self) -> &Measurement {
        &self.measurement
    }

    /// The last measurement, for a simulator to record the ground truth of the faults it
    /// injected ([`Measurement::injected_nan`], [`Measurement::injected_stale`]).
    pub fn measurement_mut(&mut self) -> &mut Measurement {
        &mut self.measurement
    }

    /// Takes the encoder angles `q` read at `time`, with `tau_commanded` the command held
    /// over the period that just ended, or the measured torque (a non-finite value holds
    /// the joint's last torque, zero before the first).
    pub fn sample(
        &mut self,
        time: f64,
        q: &[f64],
        tau_commanded: &[f64],
    ) -> Result<&Measurement, LoopError> {
        check_len("q", q, self.n)?;
        check_len("tau_commanded", tau_commanded, self.n)?;
        self.measurement.sample_time.fill(time);
        // Without sample times from the caller, a reading repeated while moving is dated
        // back to when it last changed.
        for (i, &raw) in q.iter().enumerate() {
            if let Some(taken) = self.frozen.update(i, time, raw) {
                self.measurement.sample_time[i] = taken;
            }
        }
        self.filter_sample(time, q, tau_commanded);
        Ok(&self.measurement)
    }

    /// As [`SignalChain::sample`], with each joint's own sample time (older than `time`
    /// for a stale reading).
    pub fn sample_at(
        &mut self,
        time: f64,
        q: &[f64],
        sample_time: &[f64],
        tau_commanded: &[f64],
    ) -> Result<&Measurement, LoopError> {
        check_len("q", q, self.n)?;
        check_len("sample_time", sample_time, self.n)?;
        check_len("tau_commanded", tau_commanded, self.n)?;
        self.measurement.sample_time.copy_from_slice(sample_time);
        self.filter_sample(time, q, tau_commanded);
        Ok(&self.measurement)
    }

    fn filter_sample(&mut self, time: f64, q: &[f64], tau_commanded: &[f64]) {
        self.measurement.time = time;
        for i in 0..self.n {
            self.filter_angle(i, q[i]);
            // A non-finite torque (a robot's dropped or refused reading) never enters the
            // filter: the last values are held (zero before the first).
            let tau = tau_commanded[i];
            if tau.is_finite() {
                let m = &mut self.measurement;
                m.tau_commanded[i] = tau;
                m.tau_filtered[i] = self.tau_filter.update(i, tau);
            }
        }
    }

    fn filter_angle(&mut self, i: usize, raw: f64) {
        let dt = self.dt;
        let m = &mut self.measurement;
        m.q[i] = raw;
        if raw.is_finite() {
            let qf = self.q_filter.update(i, raw);
            match self.valid[i] {
                0 => {
                    m.qdot[i] = 0.0;
                    m.qddot[i] = 0.0;
                }
                1 => {
                    m.qdot[i] = (qf - self.prev_qf[i]) / dt;
                    m.qddot[i] = 0.0;
                }
                _ => {
                    m.qdot[i] = (qf - self.prev_qf[i]) / dt;
                    m.qddot[i] = (m.qdot[i] - self.prev_qdot[i]) / dt;
                }
            }
            m.q_filtered[i] = qf;
            self.prev_qf[i] = qf;
            self.prev_qdot[i] = m.qdot[i];
            self.valid[i] = (self.valid[i] + 1).min(2);
        } else if self.valid[i] == 0 {
            // Nothing valid yet: no filtered angle to hold.
            m.q_filtered[i] = f64::NAN;
            m.qdot[i] = 0.0;
            m.qddot[i] = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_gives_its_slope_and_no_acceleration() {
        let mut chain = SignalChain::new(1, 20.0, 1000.0).unwrap();
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            chain.sample(t, &[0.5 * t], &[1.0]).unwrap();
        }
        let m = chain.measurement();
        assert!((m.qdot[0] - 0.5).abs() < 1e-9, "{}", m.qdot[0]);
        assert!(m.qddot[0].abs() < 1e-6, "{}", m.qddot[0]);
        assert!((m.tau_filtered[0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_nan_reading_holds_the_derived_signals() {
        let mut chain = SignalChain::new(1, 20.0, 1000.0).unwrap();
        let m = chain.sample(0.0, &[f64::NAN], &[f64::NAN]).unwrap();
        assert!(m.q_filtered[0].is_nan() && m.qdot[0] == 0.0 && m.tau_commanded[0] == 0.0);
        chain.sample(1e-3, &[1.0], &[0.0]).unwrap();
        let m = chain.sample(2e-3, &[1.1], &[0.0]).unwrap();
        let held = (m.q_filtered[0], m.qdot[0], m.qddot[0]);
        let m = chain.sample(3e-3, &[f64::NAN], &[0.0]).unwrap();
        assert!(m.q[0].is_nan() && !m.is_finite());
        assert_eq!((m.q_filtered[0], m.qdot[0], m.qddot[0]), held);
        assert!(chain.sample(0.0, &[1.0, 2.0], &[0.0]).is_err());
    }
}
