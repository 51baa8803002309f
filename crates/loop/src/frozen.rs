//! Frozen encoder readings (issue 34, item 10): a robot's driver that drops packets often
//! repeats the last angle with a fresh time stamp, so the sample times say nothing. A
//! joint's reading is taken as stale once it has stayed bit-identical for at least
//! [`STALE_AFTER_S`] (10 ms) and for three times the interval between its last two changes,
//! after changing at more than [`STALE_SPEED`] rad/s: a joint moving that fast cannot stop
//! in one period, and a quantised reading of a slow joint repeats for far shorter than
//! three of its own change intervals. A joint at rest, or slowing through a reversal
//! (its last changes are slow), is not flagged. The reading's sample time is set back to
//! when it last changed, so every consumer that counts stale samples from their time
//! stamps (the run folder's `stale_measurements`) counts these too.

/// How long a reading must stay identical before it is stale (s).
pub const STALE_AFTER_S: f64 = 0.010;
/// How fast the reading must have been changing when it froze (rad/s or m/s), the safe
/// hold's default `stale_velocity`.
pub const STALE_SPEED: f64 = 0.3;

/// Per joint: the last reading, when it changed and how fast; allocation-free per sample.
#[derive(Clone, Debug)]
pub(crate) struct FrozenReadings {
    last: Vec<f64>,
    changed_at: Vec<f64>,
    interval: Vec<f64>,
    moving: Vec<bool>,
    counted: Vec<bool>,
    seen: Vec<bool>,
    episodes: u64,
}

impl FrozenReadings {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            last: vec![0.0; n],
            changed_at: vec![0.0; n],
            interval: vec![0.0; n],
            moving: vec![false; n],
            counted: vec![false; n],
            seen: vec![false; n],
            episodes: 0,
        }
    }

    pub(crate) fn reset(&mut self) {
        let n = self.last.len();
        *self = Self::new(n);
    }

    /// Frozen episodes so far (each counted once, when it reaches the thresholds).
    pub(crate) fn episodes(&self) -> u64 {
        self.episodes
    }

    /// Joint `i` read `raw` at `time`: `Some(t)` when the reading is stale, `t` being when
    /// it was really taken (its last change).
    pub(crate) fn update(&mut self, i: usize, time: f64, raw: f64) -> Option<f64> {
        if !raw.is_finite() {
            return None;
        }
        if self.seen[i] && raw.to_bits() == self.last[i].to_bits() {
            let frozen = time - self.changed_at[i];
            let long = frozen >= STALE_AFTER_S - 1e-9 && frozen > 3.0 * self.interval[i];
            if self.moving[i] && long {
                if !self.counted[i] {
                    self.counted[i] = true;
                    self.episodes += 1;
                }
                return Some(self.changed_at[i]);
            }
            return None;
        }
        if self.seen[i] {
            let interval = time - self.changed_at[i];
            self.moving[i] = interval > 0.0 && (raw - self.last[i]).abs() / interval > STALE_SPEED;
            self.interval[i] = interval;
        }
        self.last[i] = raw;
        self.changed_at[i] = time;
        self.counted[i] = false;
        self.seen[i] = true;
        None
    }
}

#[cfg(test)]
mod tests {
    use crate::chain::SignalChain;

    /// Samples `q(t)` at 1 kHz for `seconds`, with the reading frozen (the last value
    /// repeated, fresh time stamps) in `dropouts` windows `[start, start + 10 ms)`; returns
    /// the chain and the number of samples dated back.
    fn run(q: impl Fn(f64) -> f64, seconds: f64, dropouts: &[f64]) -> (SignalChain, usize) {
        let mut chain = SignalChain::new(1, 20.0, 1000.0).unwrap();
        let mut last = f64::NAN;
        let mut dated_back = 0;
        for k in 0..(seconds * 1000.0) as usize {
            let t = k as f64 * 1e-3;
            let frozen = dropouts
                .iter()
                .any(|&s| t >= s - 1e-9 && t < s + 0.010 - 1e-9);
            let reading = if frozen && last.is_finite() {
                last
            } else {
                q(t)
            };
            last = reading;
            let m = chain.sample(t, &[reading], &[0.0]).unwrap();
            if t - m.sample_time[0] > 0.5e-3 {
                dated_back += 1;
            }
        }
        (chain, dated_back)
    }

    #[test]
    fn twenty_dropouts_of_10_ms_while_moving_are_counted() {
        let starts: Vec<f64> = (0..20).map(|k| 0.5 + 0.1 * k as f64).collect();
        // 1 rad/s ramp.
        let (chain, dated_back) = run(|t| 1.0 * t, 3.0, &starts);
        assert_eq!(chain.stale_episodes(), 20);
        // The 10th repeated sample of each dropout (10 ms after the last change) is stale.
        assert_eq!(dated_back, 20);
        // A joint whose speed varies between 0.4 and 1.6 rad/s.
        let (chain, _) = run(|t| t + 0.2 * (3.0 * t).sin(), 3.0, &starts);
        assert_eq!(chain.stale_episodes(), 20);
        // Slower than 0.3 rad/s the reading may legitimately repeat: not flagged.
        let (chain, _) = run(|t| 0.2 * t, 3.0, &starts);
        assert_eq!(chain.stale_episodes(), 0);
    }

    #[test]
    fn rest_reversals_and_a_coarse_encoder_are_not_stale() {
        let (chain, n) = run(|_| 0.3, 2.0, &[]);
        assert_eq!((chain.stale_episodes(), n), (0, 0));
        // Reversals every 1.6 s at up to 2 rad/s.
        let (chain, n) = run(|t| (2.0 * t).sin(), 6.0, &[]);
        assert_eq!((chain.stale_episodes(), n), (0, 0));
        // A 12-bit encoder (1.5e-3 rad per count) on a 0.5 rad/s sine: counts repeat for
        // several periods at the reversals and between counts.
        let res = std::f64::consts::TAU / 4096.0;
        let (chain, n) = run(|t| ((0.5 * t.sin()) / res).round() * res, 8.0, &[]);
        assert_eq!((chain.stale_episodes(), n), (0, 0));
        // A joint stopping dead from 1 rad/s (stiction at a reversal, an obstacle) stays
        // identical: that it cannot tell from a dropout, and it counts one episode.
        let (chain, _) = run(|t| t.min(1.0), 2.0, &[]);
        assert_eq!(chain.stale_episodes(), 1);
    }
}
