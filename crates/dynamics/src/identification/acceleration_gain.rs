//! The share of the measured acceleration a prediction trusts, per joint and sample.
//!
//! Held-out stretches of the training motion choose one gain `g` (docs/method.md section 8):
//! a Wiener gain `S / (S + N)` for that motion's acceleration power `S` and the noise power
//! `N` that the conditioning leaves in `q''`. The noise does not change with the motion, the
//! signal does: a gain chosen on slow motion, where `q''` is mostly noise, leaves most of the
//! inertial torque of faster motion out (on slow recordings of simulated arms with a link-side
//! torque sensor, 1.5 to 8.6 times the error of the whole acceleration at 10 Hz;
//! docs/experiments.md, "A joint torque sensor on the link side"). So each joint's noise power
//! is taken from the training motion, `N = (1 - g) P` with `P` its mean square of `q''` there,
//! and on a stretch of motion whose local mean square `S` (an exponential mean over
//! [`ACCELERATION_POWER_S`]) stands well above it, the gain rises toward 1:
//! `max(g, 1 - NOISE_MARGIN N / S)`. On motion like the training's it stays `g`.

use crate::identification::IdentificationSummary;

/// Time constant (s) of the local mean square of `q''`.
pub const ACCELERATION_POWER_S: f64 = 0.5;

/// How far above the noise power the local mean square must be before the gain rises above
/// the one chosen on held-out motion: at 4 the real Baxter recording's predictions (raw, 4
/// and 10 Hz, five splits) stay within 0.7 % of the fixed gain's, at 1 and 2 up to 25 % and
/// 2.4 % worse on raw signals (docs/experiments.md).
pub const NOISE_MARGIN: f64 = 4.0;

/// Per joint, the gain on the measured `q''` of each sample of one motion, in time order.
/// Allocation-free after construction.
#[derive(Clone, Debug)]
pub struct AccelerationGains {
    chosen: f64,
    /// `NOISE_MARGIN N` per joint; empty: the chosen gain everywhere.
    noise: Vec<f64>,
    /// The local mean square of `q''` per joint.
    power: Vec<f64>,
    training_power: Vec<f64>,
    /// Weight of a new sample in the local mean square.
    weight: f64,
}

impl AccelerationGains {
    /// For `summary`'s identification on samples at `rate_hz` (`None` or not positive: the
    /// identification's own rate; unknown, or a file without `acceleration_power`: the chosen
    /// gain everywhere). The local mean square starts at the training's.
    pub fn new(summary: &IdentificationSummary, rate_hz: Option<f64>) -> Self {
        let chosen = summary.acceleration_gain;
        let rate = rate_hz.filter(|r| r.is_finite() && *r > 0.0).or(summary
            .settings
            .sample_rate_hz
            .filter(|r| r.is_finite() && *r > 0.0));
        let adapts = chosen < 1.0 && rate.is_some() && !summary.acceleration_power.is_empty();
        let training_power = if adapts {
            summary.acceleration_power.clone()
        } else {
            Vec::new()
        };
        AccelerationGains {
            chosen,
            noise: training_power
                .iter()
                .map(|p| NOISE_MARGIN * (1.0 - chosen) * p)
                .collect(),
            power: training_power.clone(),
            training_power,
            weight: rate.map_or(1.0, |r| (1.0 / (r * ACCELERATION_POWER_S)).min(1.0)),
        }
    }

    /// Starts a new motion: the local mean square back at the training's.
    pub fn reset(&mut self) {
        self.power.copy_from_slice(&self.training_power);
    }

    /// The gains of the next sample, whose measured acceleration is `qddot`, into `gains`
    /// (both of the joints' count).
    pub fn update(&mut self, qddot: &[f64], gains: &mut [f64]) {
        if self.noise.is_empty() || qddot.len() != self.noise.len() {
            gains.fill(self.chosen);
            return;
        }
        for (j, g) in gains.iter_mut().enumerate() {
            let a = qddot[j];
            if a.is_finite() {
                self.power[j] += self.weight * (a * a - self.power[j]);
            }
            let rise = if self.power[j] > 0.0 {
                (1.0 - self.noise[j] / self.power[j]).clamp(0.0, 1.0)
            } else {
                0.0
            };
            *g = self.chosen.max(rise);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(gain: f64, power: Vec<f64>) -> IdentificationSummary {
        let mut s = IdentificationSummary::empty(power.len().max(1));
        s.acceleration_gain = gain;
        s.acceleration_power = power;
        s.settings.sample_rate_hz = Some(100.0);
        s
    }

    #[test]
    fn stays_at_the_chosen_gain_on_motion_like_the_training() {
        let mut gains = AccelerationGains::new(&summary(0.3, vec![2.0, 0.5]), None);
        let mut g = [0.0; 2];
        // Samples whose mean square is the training's: the chosen gain, never less.
        for k in 0..500 {
            let s = if k % 2 == 0 { 1.0 } else { -1.0 };
            gains.update(&[s * 2f64.sqrt(), s * 0.5f64.sqrt()], &mut g);
            assert!(g.iter().all(|&v| v == 0.3), "{g:?}");
        }
    }

    #[test]
    fn rises_toward_one_on_faster_motion_and_back() {
        let mut gains = AccelerationGains::new(&summary(0.3, vec![1.0]), None);
        let mut g = [0.0];
        // 100 times the training's mean square for 5 s: 1 - 4 * 0.7 / 100 once settled.
        for _ in 0..500 {
            gains.update(&[10.0], &mut g);
        }
        assert!((g[0] - (1.0 - 4.0 * 0.7 / 100.0)).abs() < 1e-4, "{g:?}");
        // Slow again: back to the chosen gain within a few time constants.
        for _ in 0..300 {
            gains.update(&[0.1], &mut g);
        }
        assert_eq!(g[0], 0.3);
        gains.reset();
        gains.update(&[1.0], &mut g);
        assert_eq!(g[0], 0.3);
    }

    #[test]
    fn the_chosen_gain_without_a_rate_or_training_power() {
        let mut g = [0.0];
        let mut s = summary(0.3, vec![1.0]);
        s.settings.sample_rate_hz = None;
        let mut gains = AccelerationGains::new(&s, None);
        gains.update(&[100.0], &mut g);
        assert_eq!(g[0], 0.3);
        let mut gains = AccelerationGains::new(&summary(0.3, Vec::new()), None);
        gains.update(&[100.0], &mut g);
        assert_eq!(g[0], 0.3);
        let mut gains = AccelerationGains::new(&summary(1.0, vec![1.0]), None);
        gains.update(&[0.0], &mut g);
        assert_eq!(g[0], 1.0);
        // A non-finite sample does not poison the mean square.
        let mut gains = AccelerationGains::new(&summary(0.3, vec![1.0]), None);
        gains.update(&[f64::NAN], &mut g);
        assert_eq!(g[0], 0.3);
    }
}
