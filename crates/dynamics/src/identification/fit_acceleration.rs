//! The acceleration the fit regresses the inertial torque on (docs/method.md section 8): the
//! measured `q''` through a zero-phase low-pass. A differentiated acceleration carries noise
//! far above the motion's band; in a regressor that noise biases every parameter it is
//! correlated with (errors in variables), and a physically consistent fit, which cannot shrink
//! its inertias to absorb it as a free least squares does with negative rotor inertias,
//! moves gravity and friction parameters instead. Filtered forward and backward, the
//! acceleration keeps its timing against the torque. Only the fit sees it: predictions, the
//! acceleration gain and every held-out error use the acceleration as measured, as a
//! consumer will.

use crate::identification::samples::Samples;

/// The fit's acceleration cut-off when none is given (Hz): above the band of an arm's
/// motion (excitations and tasks move below a few Hz), below the differentiation noise of
/// a 100 Hz recording. On eight splits of the real Baxter's recording, raw signals, cut-offs
/// of 5, 10 and 20 Hz scored within 2 % of each other (docs/experiments.md, "The fit's
/// acceleration").
pub const FIT_ACCELERATION_HZ: f64 = 10.0;

/// `samples`' accelerations through a second-order Butterworth low-pass at `cutoff_hz`, run
/// forward then backward (zero phase, fourth-order magnitude), each joint on its own, each
/// pass started at rest at its first value (no start-up transient for a signal that starts
/// steady). `None` when the cut-off is not below 0.45 times the sample rate (the filter
/// would pass everything) or there are fewer than 3 samples.
pub(super) fn smoothed_acceleration(
    samples: &Samples,
    rate_hz: f64,
    cutoff_hz: f64,
) -> Option<Vec<f64>> {
    let n = samples.dof;
    let len = samples.len();
    if !(cutoff_hz > 0.0 && rate_hz.is_finite() && cutoff_hz < 0.45 * rate_hz) || len < 3 {
        return None;
    }
    Some(zero_phase(samples.qddot, n, rate_hz, cutoff_hz))
}

/// Each of the `n` interleaved columns of `values` through the zero-phase low-pass.
fn zero_phase(values: &[f64], n: usize, rate_hz: f64, cutoff_hz: f64) -> Vec<f64> {
    let len = values.len() / n.max(1);
    let section = Biquad::low_pass(cutoff_hz, rate_hz);
    let mut out = values.to_vec();
    let mut column = vec![0.0; len];
    for i in 0..n {
        for (k, c) in column.iter_mut().enumerate() {
            *c = out[k * n + i];
        }
        section.run(column.iter_mut());
        section.run(column.iter_mut().rev());
        for (k, c) in column.iter().enumerate() {
            out[k * n + i] = *c;
        }
    }
    out
}

/// A second-order low-pass section (bilinear transform, cut-off prewarped), direct form II
/// transposed.
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
}

impl Biquad {
    fn low_pass(cutoff_hz: f64, rate_hz: f64) -> Self {
        let k = (std::f64::consts::PI * cutoff_hz / rate_hz).tan();
        let q = std::f64::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Biquad {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
        }
    }

    /// Filters the values in place, in the order given, from rest at the first value (unit
    /// DC gain: the states that hold a constant input).
    fn run<'v>(&self, values: impl Iterator<Item = &'v mut f64>) {
        let [b0, b1, b2] = self.b;
        let [a1, a2] = self.a;
        let mut state: Option<[f64; 2]> = None;
        for v in values {
            let x = *v;
            // At rest at x: y = x, s2 = (b2 - a2) x, s1 = y - b0 x.
            let [s1, s2] = state.unwrap_or([x - b0 * x, (b2 - a2) * x]);
            let y = b0 * x + s1;
            state = Some([b1 * x - a1 * y + s2, b2 * x - a2 * y]);
            *v = y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples_of(qddot: &[f64]) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; qddot.len()], qddot.to_vec())
    }

    #[test]
    fn a_constant_passes_unchanged_and_noise_is_removed() {
        let rate = 100.0;
        let len = 2000;
        // Joint 0: constant; joint 1: a 1 Hz sine plus alternating noise at Nyquist.
        let mut qddot = Vec::with_capacity(2 * len);
        for k in 0..len {
            let t = k as f64 / rate;
            qddot.push(3.0);
            qddot
                .push((2.0 * std::f64::consts::PI * t).sin() + if k % 2 == 0 { 0.5 } else { -0.5 });
        }
        let (zeros, qdd) = samples_of(&qddot);
        let s = Samples {
            q: &zeros,
            qdot: &zeros,
            qddot: &qdd,
            tau: &zeros,
            dof: 2,
        };
        let out = smoothed_acceleration(&s, rate, 10.0).unwrap();
        for k in 0..len {
            assert!(
                (out[2 * k] - 3.0).abs() < 1e-12,
                "constant at {k}: {}",
                out[2 * k]
            );
        }
        // Away from the ends the sine is kept in phase and the noise is gone.
        for k in 200..len - 200 {
            let t = k as f64 / rate;
            let want = (2.0 * std::f64::consts::PI * t).sin();
            assert!(
                (out[2 * k + 1] - want).abs() < 0.01,
                "at {k}: {} against {want}",
                out[2 * k + 1]
            );
        }
    }

    #[test]
    fn no_filter_at_or_above_the_band_the_samples_hold() {
        let (zeros, qdd) = samples_of(&[0.0; 20]);
        let s = Samples {
            q: &zeros,
            qdot: &zeros,
            qddot: &qdd,
            tau: &zeros,
            dof: 1,
        };
        assert!(smoothed_acceleration(&s, 20.0, 10.0).is_none());
        assert!(smoothed_acceleration(&s, 100.0, 0.0).is_none());
        assert!(smoothed_acceleration(&s, f64::NAN, 10.0).is_none());
        assert!(smoothed_acceleration(&s, 100.0, 10.0).is_some());
    }
}
