//! The torque's delay behind the motion, applied at run time (issue 30; docs/method.md
//! section 8): an identification fitted each joint's torque `d` later than the motion
//! (`IdentificationSummary::delay_s`), so the observer is fed this period's torque with the
//! motion `d` older (or, for a negative `d`, the motion with the torque `|d|` older). A ring
//! of past inputs, read between samples by linear interpolation; its memory is taken at
//! construction, nothing is allocated per period.

use crate::error::LoopError;

/// Longest delay accepted (s): `identify` scans up to 30 ms.
const MAX_DELAY_S: f64 = 1.0;

/// The observer's inputs `[q, q', q'', tau]` (4 n channels), each channel read a fixed
/// number of samples in the past.
pub struct InputDelay {
    /// Per channel: how many samples back it is read (>= 0, fractional).
    shift: Vec<f64>,
    /// `depth` rows of 4 n channels, the newest at `head`.
    ring: Vec<f64>,
    depth: usize,
    head: usize,
    /// Rows written so far (up to `depth`): before the ring is full the oldest row stands
    /// in for older ones.
    filled: usize,
    /// The delayed inputs of the last update.
    out: Vec<f64>,
}

impl InputDelay {
    /// For per-joint delays `delay_s` (s; positive: the torque was later than the motion)
    /// at `rate_hz`; `None` when every delay is zero.
    pub fn new(delay_s: &[f64], rate_hz: f64) -> Result<Option<Self>, LoopError> {
        let n = delay_s.len();
        if delay_s.iter().all(|d| *d == 0.0) {
            return Ok(None);
        }
        if let Some(bad) = delay_s
            .iter()
            .find(|d| !(d.is_finite() && d.abs() <= MAX_DELAY_S))
        {
            return Err(LoopError::invalid(
                "observer.identification",
                format!(
                    "its torque delay is {bad} s; a delay of at most {MAX_DELAY_S} s either way is \
                     expected (identify the arm again)"
                ),
            ));
        }
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(LoopError::invalid(
                "control_rate_hz",
                format!("is {rate_hz}, must be a positive number of Hz"),
            ));
        }
        let mut shift = vec![0.0; 4 * n];
        for (i, d) in delay_s.iter().enumerate() {
            let samples = d.abs() * rate_hz;
            if *d > 0.0 {
                // Motion older: q, q', q''.
                for part in 0..3 {
                    shift[part * n + i] = samples;
                }
            } else {
                shift[3 * n + i] = samples;
            }
        }
        let depth = shift.iter().copied().fold(0.0, f64::max).ceil() as usize + 2;
        Ok(Some(Self {
            shift,
            ring: vec![0.0; depth * 4 * n],
            depth,
            head: 0,
            filled: 0,
            out: vec![0.0; 4 * n],
        }))
    }

    /// Pushes this period's inputs (`n` values each) and returns them delayed, as
    /// `[q, q', q'', tau]`.
    pub fn update(&mut self, q: &[f64], qdot: &[f64], qddot: &[f64], tau: &[f64]) -> &[f64] {
        let width = self.out.len();
        let n = width / 4;
        self.head = (self.head + 1) % self.depth;
        let row = &mut self.ring[self.head * width..(self.head + 1) * width];
        // Slices shorter than the joint count leave the rest as it was (never a panic).
        for (part, values) in [q, qdot, qddot, tau].iter().enumerate() {
            for (slot, v) in row[part * n..(part + 1) * n].iter_mut().zip(values.iter()) {
                *slot = *v;
            }
        }
        self.filled = (self.filled + 1).min(self.depth);
        let oldest = (self.filled - 1) as f64;
        for c in 0..width {
            let back = self.shift[c].min(oldest);
            let whole = back.floor();
            let frac = back - whole;
            let at = |k: usize| {
                let r = (self.head + self.depth - k) % self.depth;
                self.ring[r * width + c]
            };
            let newer = at(whole as usize);
            let older = at((whole as usize + 1).min(self.filled - 1));
            self.out[c] = newer * (1.0 - frac) + older * frac;
        }
        &self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_comes_out_delayed_by_the_fractional_shift() {
        // 2 joints at 1 kHz: joint 0's torque 2.5 ms later than its motion (motion read
        // 2.5 samples back), joint 1's torque 1 ms earlier (its torque read 1 sample back).
        let mut d = InputDelay::new(&[0.0025, -0.001], 1000.0).unwrap().unwrap();
        for k in 0..20 {
            let v = k as f64;
            let out = d.update(&[v, v], &[v, v], &[v, v], &[v, v]).to_vec();
            let held = |back: f64| (v - back).max(0.0);
            assert_eq!(out[0], held(2.5), "q0 at {k}");
            assert_eq!(out[1], v, "q1 at {k}");
            assert_eq!(out[6], v, "tau0 at {k}");
            assert_eq!(out[7], held(1.0), "tau1 at {k}");
        }
    }

    #[test]
    fn no_delay_is_no_stage_and_absurd_delays_are_refused() {
        assert!(InputDelay::new(&[0.0, 0.0], 1000.0).unwrap().is_none());
        assert!(InputDelay::new(&[5.0], 1000.0).is_err());
        assert!(InputDelay::new(&[f64::NAN], 1000.0).is_err());
    }
}
