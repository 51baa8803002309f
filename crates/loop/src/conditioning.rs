//! A second filtering stage for the inputs of the learned observers
//! (`observer.input_filter_hz`), applied identically to the free-motion training data and
//! at run time.
//!
//! Why: the sensors' differentiation filter (40 Hz in the experiment B scenarios) is sized
//! for the controller, and the acceleration it yields is mostly noise (docs/method.md section 7:
//! in the free-motion data of `scenarios/free_motion.toml` the part of `qddot` above 5 Hz
//! has a standard deviation of about 2 rad/s^2 on every joint, larger than the true
//! accelerations), so a network on `[q, qdot, qddot]` cannot learn the inertial torque.
//! The observer can afford a slower filter than the controller: the external torques it
//! estimates change slowly. The stage passes the (already filtered) angles and torques
//! through one more 2nd-order Butterworth low-pass, the same for both so that their delays
//! match, and differentiates the filtered angles again:
//!
//! ```text
//!     q2 = LP(q),  qdot2[k] = (q2[k] - q2[k-1]) / dt,  qddot2[k] = (qdot2[k] - qdot2[k-1]) / dt,
//!     tau2 = LP(tau)
//! ```
//!
//! (zero derivatives until there are enough samples, as in [`crate::SignalChain`]).
//!
//! Invalid samples (NaN or infinite) never enter the filters: a channel that receives one
//! holds its last outputs, and its filter restarts at the next valid sample (steady state at
//! that value, derivatives from zero), so a burst of bad data costs the observer only the
//! burst. A channel that has had no valid sample yet outputs NaN (nothing to hold), which
//! the observers report as a fault.

use crate::error::LoopError;
use crate::signal::LowPass;

/// The conditioning stage; allocation-free per update.
#[derive(Clone, Debug)]
pub struct InputConditioner {
    q_filter: LowPass,
    tau_filter: LowPass,
    dt: f64,
    /// Per joint: valid angle samples since the filter (re)started, up to 2.
    valid: Vec<u8>,
    /// Per joint: the angle (resp. torque) channel has had an invalid sample since its
    /// last valid one, and its filter must restart.
    q_lost: Vec<bool>,
    tau_lost: Vec<bool>,
    /// Conditioned angles.
    pub q: Vec<f64>,
    /// Their backward difference.
    pub qdot: Vec<f64>,
    /// The backward difference of `qdot`.
    pub qddot: Vec<f64>,
    /// Conditioned torques.
    pub tau: Vec<f64>,
    q_prev: Vec<f64>,
    qdot_prev: Vec<f64>,
}

impl InputConditioner {
    /// For `n` joints sampled at `sample_rate_hz`, cut-off `cutoff_hz` (0 < cutoff <
    /// sample_rate / 2).
    pub fn new(n: usize, cutoff_hz: f64, sample_rate_hz: f64) -> Result<Self, LoopError> {
        Ok(Self {
            q_filter: LowPass::butterworth2(cutoff_hz, sample_rate_hz, n)?,
            tau_filter: LowPass::butterworth2(cutoff_hz, sample_rate_hz, n)?,
            dt: 1.0 / sample_rate_hz,
            valid: vec![0; n],
            q_lost: vec![false; n],
            tau_lost: vec![false; n],
            // NaN until a channel's first valid sample: nothing to hold before it.
            q: vec![f64::NAN; n],
            qdot: vec![0.0; n],
            qddot: vec![0.0; n],
            tau: vec![f64::NAN; n],
            q_prev: vec![0.0; n],
            qdot_prev: vec![0.0; n],
        })
    }

    /// Takes one sample of angles and torques (each `n` long; extra values are ignored,
    /// missing ones leave their channels unchanged). Non-finite values are skipped (see the
    /// module documentation).
    pub fn update(&mut self, q: &[f64], tau: &[f64]) {
        let n = self.q.len().min(q.len()).min(tau.len());
        for i in 0..n {
            self.update_angle(i, q[i]);
            if tau[i].is_finite() {
                if self.tau_lost[i] {
                    self.tau_filter.restart(i);
                    self.tau_lost[i] = false;
                }
                self.tau[i] = self.tau_filter.update(i, tau[i]);
            } else {
                // Hold the last output (NaN when there has been none).
                self.tau_lost[i] = true;
            }
        }
    }

    fn update_angle(&mut self, i: usize, q: f64) {
        if !q.is_finite() {
            // Hold the last outputs (NaN when there has been none).
            self.q_lost[i] = true;
            return;
        }
        if self.q_lost[i] {
            self.q_filter.restart(i);
            self.valid[i] = 0;
            self.q_lost[i] = false;
        }
        let qf = self.q_filter.update(i, q);
        let v = if self.valid[i] >= 1 {
            (qf - self.q_prev[i]) / self.dt
        } else {
            0.0
        };
        let a = if self.valid[i] >= 2 {
            (v - self.qdot_prev[i]) / self.dt
        } else {
            0.0
        };
        self.q[i] = qf;
        self.qdot[i] = v;
        self.qddot[i] = a;
        self.q_prev[i] = qf;
        self.qdot_prev[i] = v;
        self.valid[i] = (self.valid[i] + 1).min(2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    #[test]
    fn slow_signals_pass_with_matching_delays() {
        let fs = 1000.0;
        let mut c = InputConditioner::new(1, 5.0, fs).unwrap();
        let w = 2.0 * std::f64::consts::PI * 0.2;
        // DC group delay of the 2nd-order Butterworth, sqrt(2) / omega_c, plus one sample
        // for the two backward differences.
        let delay = std::f64::consts::SQRT_2 / (2.0 * std::f64::consts::PI * 5.0);
        let (mut err_acc, mut err_pair): (f64, f64) = (0.0, 0.0);
        for k in 0..20_000 {
            let t = k as f64 / fs;
            // A torque that is a linear function of the acceleration.
            c.update(&[(w * t).sin()], &[-3.0 * w * w * (w * t).sin()]);
            if t > 5.0 {
                let truth = -w * w * (w * (t - delay - 1e-3)).sin();
                err_acc = err_acc.max((c.qddot[0] - truth).abs());
                err_pair = err_pair.max((3.0 * c.qddot[0] - c.tau[0]).abs());
            }
        }
        // 1.6 rad/s^2 amplitude: a fraction of a percent.
        assert!(err_acc < 5e-3, "acceleration error {err_acc}");
        // The torque is one sample ahead of the acceleration (no second difference).
        assert!(err_pair < 1e-2, "pairing error {err_pair}");
    }

    /// Issue 14: NaN samples at start-up (a sensor fault over 0-0.5 s) used to enter the
    /// filter state and keep every output NaN for the rest of the run.
    #[test]
    fn channels_restart_after_invalid_samples() {
        let fs = 1000.0;
        let mut c = InputConditioner::new(2, 10.0, fs).unwrap();
        for k in 0..500 {
            let t = k as f64 / fs;
            c.update(&[f64::NAN, 0.3 + 0.1 * t], &[f64::NAN, 1.0]);
            assert!(c.q[0].is_nan(), "no valid angle yet: nothing to hold");
            assert!(c.q[1].is_finite() && c.tau[1].is_finite());
        }
        for k in 500..1000 {
            let t = k as f64 / fs;
            c.update(&[0.5 + 0.2 * t, 0.3 + 0.1 * t], &[2.0, 1.0]);
        }
        // Restarted at steady state: the ramp's slope comes through (less the filter's lag,
        // which a ramp does not change in slope).
        assert!((c.qdot[0] - 0.2).abs() < 1e-6, "qdot {}", c.qdot[0]);
        assert!(c.qddot[0].abs() < 1e-6, "qddot {}", c.qddot[0]);
        assert!((c.tau[0] - 2.0).abs() < 1e-12, "tau {}", c.tau[0]);
        // A NaN burst later: outputs held, then a clean restart.
        let held = (c.q[0], c.qdot[0], c.tau[0]);
        for _ in 0..10 {
            c.update(&[f64::INFINITY, 0.4], &[f64::NAN, 1.0]);
            assert_eq!((c.q[0], c.qdot[0], c.tau[0]), held);
        }
        for _ in 0..2000 {
            c.update(&[1.0, 0.4], &[3.0, 1.0]);
        }
        assert!((c.q[0] - 1.0).abs() < 1e-12 && c.qdot[0].abs() < 1e-9);
        assert!((c.tau[0] - 3.0).abs() < 1e-12);
    }

    #[test]
    fn acceleration_noise_is_reduced() {
        let fs = 1000.0;
        let mut slow = InputConditioner::new(1, 10.0, fs).unwrap();
        let mut fast = InputConditioner::new(1, 40.0, fs).unwrap();
        let mut state = 7u64;
        let (mut sum_slow, mut sum_fast) = (0.0, 0.0);
        for k in 0..20_000 {
            let q = 1e-4 * lcg(&mut state);
            slow.update(&[q], &[0.0]);
            fast.update(&[q], &[0.0]);
            if k > 1000 {
                sum_slow += slow.qddot[0] * slow.qddot[0];
                sum_fast += fast.qddot[0] * fast.qddot[0];
            }
        }
        // Above the cut-off the 2nd-order roll-off (f^-4 in power) cancels the double
        // differentiation (f^4), so the acceleration noise's standard deviation grows about
        // as the cut-off squared: 4x the cut-off, about 16x the noise.
        let ratio = (sum_fast / sum_slow).sqrt();
        eprintln!("acceleration noise ratio 40 Hz / 10 Hz: {ratio}");
        assert!(ratio > 10.0, "noise ratio {ratio}");
    }
}
