//! Angles reported wrapped at +-pi (or 0-2 pi): a continuous joint's driver may keep its
//! reading within one turn (Kinova Gen3's joints 1, 3, 5 and 7, a PR2's wrist roll), so the
//! reading jumps by a whole turn while the joint moves a little. The dynamics of such a
//! joint repeat every turn, so the loader puts the reading back on one branch, as
//! `RobotLoop` does at run time; any other step of more than pi stays refused
//! (`check_jumps`).

use std::f64::consts::{PI, TAU};

use super::derivatives::IMPLAUSIBLE_SPEED;
use super::FreeMotionData;

/// How much wider than one turn a wrapped angle's values may spread (rad): the driver's
/// rounding at the seam.
const SEAM_SLACK: f64 = 1e-6;

impl FreeMotionData {
    /// Unwraps every joint whose angle reads as wrapped: all its values within one turn, and
    /// every step of more than pi a whole turn plus a step no joint moves faster than
    /// [`IMPLAUSIBLE_SPEED`]. Such a joint's angle is moved by whole turns to the branch of
    /// its first row, and its name is added to `unwrapped`. Before derivatives are taken.
    pub fn unwrap_turns(&mut self) {
        let n = self.dof();
        for i in 0..n {
            if self.reads_wrapped(i) {
                let mut turns = 0.0;
                let mut previous = self.q[i];
                for k in 1..self.len() {
                    let reading = self.q[k * n + i];
                    turns -= ((reading - previous) / TAU).round();
                    previous = reading;
                    self.q[k * n + i] = reading + turns * TAU;
                }
                self.unwrapped.push(self.joints[i].clone());
            }
        }
    }

    /// What the loader did to wrapped angles, for the caller to say (`None`: nothing).
    pub fn unwrapped_note(&self) -> Option<String> {
        (!self.unwrapped.is_empty()).then(|| {
            let columns: Vec<String> = self.unwrapped.iter().map(|j| format!("q.{j}")).collect();
            format!(
                "{} read within one turn (a continuous joint's angle, wrapped): put back on one \
                 branch, as the run-time loop does",
                columns.join(", ")
            )
        })
    }

    /// Whether joint `i`'s angle has steps of more than pi, each a whole turn of a wrapped
    /// reading (see [`unwrap_turns`](Self::unwrap_turns)).
    fn reads_wrapped(&self, i: usize) -> bool {
        let n = self.dof();
        let angle = |k: usize| self.q[k * n + i];
        let (mut lowest, mut highest) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..self.len() {
            lowest = lowest.min(angle(k));
            highest = highest.max(angle(k));
        }
        if !(highest - lowest <= TAU + SEAM_SLACK) {
            return false;
        }
        let mut wraps = 0;
        for k in 1..self.len() {
            let step = angle(k) - angle(k - 1);
            if step.abs() <= PI {
                continue;
            }
            let moved = step - TAU * (step / TAU).round();
            if !(moved.abs() <= IMPLAUSIBLE_SPEED * (self.t[k] - self.t[k - 1])) {
                return false;
            }
            wraps += 1;
        }
        wraps > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(q: Vec<f64>, dt: f64) -> FreeMotionData {
        let rows = q.len();
        FreeMotionData {
            joints: vec!["j".into()],
            t: (0..rows).map(|k| k as f64 * dt).collect(),
            qdot: vec![0.0; rows],
            qddot: vec![0.0; rows],
            tau: vec![1.0; rows],
            q,
            ..FreeMotionData::default()
        }
    }

    fn wrap(a: f64) -> f64 {
        a - TAU * ((a + PI) / TAU).floor()
    }

    #[test]
    fn a_turning_joint_read_within_one_turn_is_put_back_on_one_branch() {
        // Two and a half turns at 2 rad/s, sampled at 100 Hz, read in [-pi, pi).
        let truth: Vec<f64> = (0..800).map(|k| 3.0 + 0.02 * k as f64).collect();
        let mut data = recording(truth.iter().map(|&a| wrap(a)).collect(), 0.01);
        data.unwrap_turns();
        assert_eq!(data.unwrapped, vec!["j".to_string()]);
        let shift = truth[0] - data.q[0];
        for (got, want) in data.q.iter().zip(&truth) {
            assert!(
                (got + shift - want).abs() < 1e-9,
                "{got} + {shift} against {want}"
            );
        }
        assert!(data.check_jumps("x.csv").is_ok());
    }

    #[test]
    fn a_glitch_or_a_joint_spread_over_more_than_a_turn_is_left_for_the_jump_check() {
        // A step of 3.5 rad is not a turn plus motion: refused later, as before.
        let mut glitch = recording(vec![0.0, 0.1, 3.6, 3.7, 3.8], 0.01);
        glitch.unwrap_turns();
        assert!(glitch.unwrapped.is_empty());
        assert!(glitch.check_jumps("x.csv").is_err());
        // Values 7 rad apart cannot be one wrapped reading.
        let mut spread = recording(vec![-3.5, -3.4, 3.0, 3.1, 3.5], 0.01);
        spread.unwrap_turns();
        assert!(spread.unwrapped.is_empty());
        // No step beyond pi: nothing to do.
        let mut smooth = recording(vec![0.0, 0.5, 1.0, 1.5], 0.01);
        smooth.unwrap_turns();
        assert!(smooth.unwrapped.is_empty());
        assert_eq!(smooth.q, vec![0.0, 0.5, 1.0, 1.5]);
    }
}
