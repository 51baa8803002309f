//! The signals of the real chain (docs/method.md sections 1 and 7): a causal 2nd-order
//! Butterworth low-pass ([`LowPass`]) and what the controller receives each period
//! ([`Measurement`]), the same on a robot and in the simulator.

use crate::error::LoopError;

/// A causal 2nd-order Butterworth low-pass on several channels (direct form I biquad,
/// bilinear transform with the cut-off pre-warped). Each channel starts at steady state
/// on its first sample. A cut-off of 0 makes it the identity.
#[derive(Clone, Debug)]
pub struct LowPass {
    b: [f64; 3],
    a: [f64; 2],
    passthrough: bool,
    x1: Vec<f64>,
    x2: Vec<f64>,
    y1: Vec<f64>,
    y2: Vec<f64>,
    started: Vec<bool>,
}

impl LowPass {
    /// A Butterworth low-pass at `cutoff_hz` for samples at `sample_rate_hz` (0 < cutoff <
    /// sample_rate / 2; a cut-off of 0 gives the identity).
    pub fn butterworth2(
        cutoff_hz: f64,
        sample_rate_hz: f64,
        channels: usize,
    ) -> Result<Self, LoopError> {
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(LoopError::invalid(
                "sample_rate_hz",
                format!("the sample rate must be > 0, got {sample_rate_hz}"),
            ));
        }
        if !(cutoff_hz.is_finite() && cutoff_hz >= 0.0 && cutoff_hz < 0.5 * sample_rate_hz) {
            return Err(LoopError::invalid(
                "filter_cutoff_hz",
                format!(
                    "must be in [0, {}) Hz, got {cutoff_hz}",
                    0.5 * sample_rate_hz
                ),
            ));
        }
        let passthrough = cutoff_hz == 0.0;
        let (b, a) = if passthrough {
            ([1.0, 0.0, 0.0], [0.0, 0.0])
        } else {
            let k = (std::f64::consts::PI * cutoff_hz / sample_rate_hz).tan();
            let k2 = k * k;
            let sqrt2 = std::f64::consts::SQRT_2;
            let norm = 1.0 / (1.0 + sqrt2 * k + k2);
            let b0 = k2 * norm;
            (
                [b0, 2.0 * b0, b0],
                [2.0 * (k2 - 1.0) * norm, (1.0 - sqrt2 * k + k2) * norm],
            )
        };
        Ok(Self {
            b,
            a,
            passthrough,
            x1: vec![0.0; channels],
            x2: vec![0.0; channels],
            y1: vec![0.0; channels],
            y2: vec![0.0; channels],
            started: vec![false; channels],
        })
    }

    /// Filters one sample of channel `ch`.
    #[inline]
    pub fn update(&mut self, ch: usize, x: f64) -> f64 {
        if self.passthrough {
            return x;
        }
        if !self.started[ch] {
            self.started[ch] = true;
            self.x1[ch] = x;
            self.x2[ch] = x;
            self.y1[ch] = x;
            self.y2[ch] = x;
            return x;
        }
        let y = self.b[0] * x + self.b[1] * self.x1[ch] + self.b[2] * self.x2[ch]
            - self.a[0] * self.y1[ch]
            - self.a[1] * self.y2[ch];
        self.x2[ch] = self.x1[ch];
        self.x1[ch] = x;
        self.y2[ch] = self.y1[ch];
        self.y1[ch] = y;
        y
    }

    /// Forgets the history of every channel.
    pub fn reset(&mut self) {
        self.started.fill(false);
    }

    /// Forgets the history of channel `ch`: its next sample starts it at steady state.
    pub fn restart(&mut self, ch: usize) {
        if let Some(s) = self.started.get_mut(ch) {
            *s = false;
        }
    }

    /// Numerator `[b0, b1, b2]` and denominator `[a1, a2]` (with `a0 = 1`).
    pub fn coefficients(&self) -> ([f64; 3], [f64; 2]) {
        (self.b, self.a)
    }

    /// Group delay at zero frequency, in samples.
    pub fn dc_group_delay(&self) -> f64 {
        if self.passthrough {
            return 0.0;
        }
        let (b, a) = (self.b, self.a);
        let num = (b[1] + 2.0 * b[2]) / (b[0] + b[1] + b[2]);
        let den = (a[0] + 2.0 * a[1]) / (1.0 + a[0] + a[1]);
        num - den
    }
}

/// One sample of the sensors, as the controller receives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// When the sample was delivered (s).
    pub time: f64,
    /// When each joint's sample was taken: older than `time` for a stale sample.
    pub sample_time: Vec<f64>,
    /// Encoder angles, quantised and noisy, unfiltered (NaN on an injected NaN fault).
    pub q: Vec<f64>,
    /// Low-pass filtered angles.
    pub q_filtered: Vec<f64>,
    /// Backward difference of `q_filtered`.
    pub qdot: Vec<f64>,
    /// Backward difference of `qdot`.
    pub qddot: Vec<f64>,
    /// The command (or measured torque) passed in; a non-finite value holds the last one.
    pub tau_commanded: Vec<f64>,
    /// `tau_commanded` through the same low-pass as `q_filtered`.
    pub tau_filtered: Vec<f64>,
    /// Ground truth of a simulator's fault injection: this joint's sample was replaced by
    /// NaN (always false on a robot).
    pub injected_nan: Vec<bool>,
    /// Ground truth of a simulator's fault injection: this joint's sample repeats the
    /// previous one (always false on a robot).
    pub injected_stale: Vec<bool>,
}

impl Measurement {
    /// A measurement of `n` joints, every signal zero.
    pub fn new(n: usize) -> Self {
        Self {
            time: 0.0,
            sample_time: vec![0.0; n],
            q: vec![0.0; n],
            q_filtered: vec![0.0; n],
            qdot: vec![0.0; n],
            qddot: vec![0.0; n],
            tau_commanded: vec![0.0; n],
            tau_filtered: vec![0.0; n],
            injected_nan: vec![false; n],
            injected_stale: vec![false; n],
        }
    }

    /// Whether every signal the controller would use is finite.
    pub fn is_finite(&self) -> bool {
        [&self.q, &self.q_filtered, &self.qdot, &self.qddot]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn butterworth_has_unit_dc_gain_and_half_power_at_cutoff() {
        let (fs, fc) = (1000.0, 20.0);
        let lp = LowPass::butterworth2(fc, fs, 1).unwrap();
        let (b, a) = lp.coefficients();
        assert!(((b[0] + b[1] + b[2]) / (1.0 + a[0] + a[1]) - 1.0).abs() < 1e-12);
        // |H(e^{jw})| at the cut-off = 1/sqrt(2) (pre-warped bilinear transform).
        let w = std::f64::consts::TAU * fc / fs;
        let z = |k: f64| nalgebra::Complex::new((k * w).cos(), -(k * w).sin());
        let num = z(0.0) * b[0] + z(1.0) * b[1] + z(2.0) * b[2];
        let den = z(0.0) + z(1.0) * a[0] + z(2.0) * a[1];
        assert!(((num / den).norm() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-9);
        assert!(lp.dc_group_delay() > 0.0);
    }

    #[test]
    fn filter_starts_at_steady_state() {
        let mut lp = LowPass::butterworth2(10.0, 1000.0, 1).unwrap();
        for _ in 0..10 {
            assert!((lp.update(0, 3.0) - 3.0).abs() < 1e-12);
        }
    }
}
