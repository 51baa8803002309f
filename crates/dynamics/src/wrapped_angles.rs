//! A continuous joint's angle read within one turn: some drivers keep the reading in
//! `(-pi, pi]` or `[0, 2 pi)` (Kinova Gen3's joints 1, 3, 5 and 7, a PR2's wrist roll), so
//! it jumps by a whole turn while the joint moves a little. The dynamics of such a joint
//! repeat every turn; a recording of it is put back on one branch before anything is
//! interpolated or differentiated (`RobotLoop` does the same at run time).

use std::f64::consts::{PI, TAU};

/// A speed no arm joint reaches (rad/s or m/s): a step faster than this between two samples
/// is a glitch of the encoder or the logger, and a step of more than pi is a wrapped angle
/// only when a whole turn less than it is slower than this.
pub const IMPLAUSIBLE_JOINT_SPEED: f64 = 100.0;

/// Unwraps column `column` of the row-major `values` (`stride` per row) when it reads as a
/// wrapped angle: all its values within one turn, and every step of more than pi a whole
/// turn plus a step slower than [`IMPLAUSIBLE_JOINT_SPEED`] (`seconds(k)`: the time from
/// row `k - 1` to row `k`). Its rows are then moved by whole turns to the first row's
/// branch and `true` returned; otherwise nothing changes (another step beyond pi is a
/// glitch, for the caller to refuse).
pub fn unwrap_turns(
    values: &mut [f64],
    stride: usize,
    column: usize,
    seconds: impl Fn(usize) -> f64,
) -> bool {
    if stride == 0 || column >= stride {
        return false;
    }
    let rows = values.len() / stride;
    let angle = |values: &[f64], k: usize| values[k * stride + column];
    let (mut lowest, mut highest) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..rows {
        lowest = lowest.min(angle(values, k));
        highest = highest.max(angle(values, k));
    }
    // The driver's rounding at the seam may spread the values a little over one turn.
    if !(highest - lowest <= TAU + 1e-6) {
        return false;
    }
    let mut wraps = 0;
    for k in 1..rows {
        let step = angle(values, k) - angle(values, k - 1);
        if step.abs() <= PI {
            continue;
        }
        let moved = step - TAU * (step / TAU).round();
        if !(moved.abs() <= IMPLAUSIBLE_JOINT_SPEED * seconds(k)) {
            return false;
        }
        wraps += 1;
    }
    if wraps == 0 {
        return false;
    }
    let (mut turns, mut previous) = (0.0, angle(values, 0));
    for k in 1..rows {
        let reading = angle(values, k);
        turns -= ((reading - previous) / TAU).round();
        previous = reading;
        values[k * stride + column] = reading + turns * TAU;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wrap(a: f64) -> f64 {
        a - TAU * ((a + PI) / TAU).floor()
    }

    #[test]
    fn a_turning_joint_read_within_one_turn_is_put_back_on_one_branch() {
        // Two and a half turns at 2 rad/s, sampled at 100 Hz, read in [-pi, pi), beside a
        // joint that does not turn.
        let truth: Vec<f64> = (0..800).map(|k| 3.0 + 0.02 * k as f64).collect();
        let mut values: Vec<f64> = truth.iter().flat_map(|&a| [0.5, wrap(a)]).collect();
        assert!(!unwrap_turns(&mut values, 2, 0, |_| 0.01));
        assert!(unwrap_turns(&mut values, 2, 1, |_| 0.01));
        let shift = truth[0] - values[1];
        for (k, want) in truth.iter().enumerate() {
            assert_eq!(values[2 * k], 0.5);
            let got = values[2 * k + 1];
            assert!(
                (got + shift - want).abs() < 1e-9,
                "{got} + {shift} against {want}"
            );
        }
    }

    #[test]
    fn a_glitch_or_values_spread_over_more_than_a_turn_are_left_as_they_are() {
        // A step of 3.5 rad is not a turn plus motion.
        let mut glitch = vec![0.0, 0.1, 3.6, 3.7, 3.8];
        assert!(!unwrap_turns(&mut glitch, 1, 0, |_| 0.01));
        assert_eq!(glitch, vec![0.0, 0.1, 3.6, 3.7, 3.8]);
        // Values 7 rad apart cannot be one wrapped reading.
        let mut spread = vec![-3.5, -3.4, 3.0, 3.1, 3.5];
        assert!(!unwrap_turns(&mut spread, 1, 0, |_| 0.01));
        // No step beyond pi: nothing to do; no column: nothing.
        let mut smooth = vec![0.0, 0.5, 1.0, 1.5];
        assert!(!unwrap_turns(&mut smooth, 1, 0, |_| 0.01));
        assert!(!unwrap_turns(&mut smooth, 1, 1, |_| 0.01));
        assert!(!unwrap_turns(&mut smooth, 0, 0, |_| 0.01));
    }
}
