//! The derivatives of a free-motion CSV (`free_motion.rs`): taken by backward differences
//! when the file leaves them out ([`DERIVED_NOTE`]), and the recorded velocities checked
//! against the differences of the angles over the time column (a time in milliseconds, a
//! velocity in degrees per second).

#[cfg(doc)]
use super::DERIVED_NOTE;
use super::{FreeMotionData, FreeMotionError};

impl FreeMotionData {
    /// Fills the derivatives named in `derived` (`"qdot"`, `"qddot"`) by backward
    /// differences over `t` and drops the rows that have no earlier sample (one per
    /// derivative taken in turn); the file loader calls it, and so may a caller that built
    /// the data from arrays.
    pub fn take_differences(&mut self) {
        let n = self.dof();
        let (qdot, qddot) = (
            self.derived.iter().any(|d| d == "qdot"),
            self.derived.iter().any(|d| d == "qddot"),
        );
        if qdot {
            self.qdot = backward_differences(&self.t, &self.q, n);
        }
        if qddot {
            self.qddot = backward_differences(&self.t, &self.qdot, n);
        }
        let dropped = match (qdot, qddot) {
            (false, false) => 0,
            (true, true) => 2,
            _ => 1,
        }
        .min(self.len());
        self.t.drain(..dropped);
        for signal in [&mut self.q, &mut self.qdot, &mut self.qddot, &mut self.tau] {
            signal.drain(..dropped * n);
        }
    }
}

/// How far the recorded velocities may be from the angles' differences over the time
/// column (their ratio) before the file is refused: filters and a half-sample lag move it by
/// about 1 % (0.989 to 0.999 on the real Baxter recording's joints), a unit by 1000 or 57.
const VELOCITY_RATIO: std::ops::RangeInclusive<f64> = 0.5..=2.0;
/// ...when the velocities explain the differences at least this well (uncentred
/// correlation; 0.93 to 0.99 on the real Baxter's joints): unrelated columns say nothing.
const VELOCITY_CORRELATION: f64 = 0.8;
/// Fewer rows than this say nothing about units.
const MIN_ROWS: usize = 20;

impl FreeMotionData {
    /// Refuses a file whose recorded `qdot` disagrees in size with the differences of `q`
    /// over `t`, all joints together: the time or the velocity is in another unit.
    /// Also refuses a step of an angle by more than pi between two rows
    /// ([`check_jumps`](Self::check_jumps)).
    pub fn check_velocities(&self, source_name: &str) -> Result<(), FreeMotionError> {
        self.check_jumps(source_name)?;
        if self.derived.iter().any(|d| d == "qdot") || self.len() < MIN_ROWS {
            return Ok(());
        }
        let n = self.dof();
        let (mut dv, mut vv, mut dd) = (0.0, 0.0, 0.0);
        for k in 1..self.len() {
            let dt = self.t[k] - self.t[k - 1];
            for i in 0..n {
                let d = (self.q[k * n + i] - self.q[(k - 1) * n + i]) / dt;
                // The velocity halfway between the two rows, where the difference is taken.
                let v = 0.5 * (self.qdot[k * n + i] + self.qdot[(k - 1) * n + i]);
                (dv, vv, dd) = (dv + d * v, vv + v * v, dd + d * d);
            }
        }
        let ratio = dv / vv;
        let correlation = dv / (dd * vv).sqrt();
        if !(ratio.is_finite() && correlation >= VELOCITY_CORRELATION)
            || VELOCITY_RATIO.contains(&ratio)
        {
            return Ok(());
        }
        Err(FreeMotionError::Units {
            source_name: source_name.to_string(),
            message: format!(
                "the differences of q over t are {} times qdot, all joints together \
                 (1 when t is in seconds and qdot in q's unit per second): t in milliseconds \
                 reads 0.001, qdot in degrees per second of q in radians 0.0175; give t in \
                 seconds and qdot in q's unit per second",
                three_digits(ratio)
            ),
        })
    }
}

/// The rows `k` (with the first joint of each) where `q` steps by more than `limit(dt)`
/// from row `k - 1`.
fn steps_beyond<'a>(
    data: &'a FreeMotionData,
    limit: impl Fn(f64) -> f64 + 'a,
) -> impl Iterator<Item = (usize, usize)> + 'a {
    let n = data.dof();
    (1..data.len()).filter_map(move |k| {
        let bound = limit(data.t[k] - data.t[k - 1]);
        (0..n)
            .find(|&i| (data.q[k * n + i] - data.q[(k - 1) * n + i]).abs() > bound)
            .map(|i| (k, i))
    })
}

/// Speeds (rad/s or m/s) no arm joint reaches: a step of `q` faster than this between two
/// rows is a glitch of the encoder or the logger.
const IMPLAUSIBLE_SPEED: f64 = admittance_dynamics::IMPLAUSIBLE_JOINT_SPEED;

impl FreeMotionData {
    /// Refuses a step of an angle by more than pi between two rows that the loader did not
    /// read as a wrapped angle (`unwrap_turns`): the conditioning would take it for a swing
    /// at thousands of rad/s.
    pub fn check_jumps(&self, source_name: &str) -> Result<(), FreeMotionError> {
        let Some((k, i)) = steps_beyond(self, |_| std::f64::consts::PI).next() else {
            return Ok(());
        };
        let n = self.dof();
        Err(FreeMotionError::Units {
            source_name: source_name.to_string(),
            message: format!(
                "q.{} steps from {:.3} to {:.3} between t = {} and {} s, more than pi and not \
                 a whole turn of an angle read within one turn: repair the rows",
                self.joints[i],
                self.q[(k - 1) * n + i],
                self.q[k * n + i],
                self.t[k - 1],
                self.t[k]
            ),
        })
    }

    /// A warning when `q` steps faster than [`IMPLAUSIBLE_SPEED`] between two rows anywhere
    /// (the first such step and how many rows do): rows a fit would take for motion.
    pub fn implausible_speed(&self) -> Option<String> {
        let mut steps = steps_beyond(self, |dt| IMPLAUSIBLE_SPEED * dt);
        let (k, i) = steps.next()?;
        let rows = 1 + steps.count();
        let n = self.dof();
        let step = self.q[k * n + i] - self.q[(k - 1) * n + i];
        Some(format!(
            "q.{} moves {:.3} between t = {} and {} s ({} per second; no arm joint moves \
             {IMPLAUSIBLE_SPEED} per second), and {rows} step(s) like it: encoder or logger \
             glitches are fitted as motion; repair or remove those rows",
            self.joints[i],
            step,
            self.t[k - 1],
            self.t[k],
            three_digits(step.abs() / (self.t[k] - self.t[k - 1]))
        ))
    }
}

/// Below this many rows per second of `t`, a recording of a robot's joints is more likely
/// timed in other units than seconds (the slowest here, the real Baxter's, is 100).
const SLOWEST_LIKELY_RATE_HZ: f64 = 20.0;

impl FreeMotionData {
    /// A warning when the rows come fewer than [`SLOWEST_LIKELY_RATE_HZ`] per second of `t`:
    /// a time in milliseconds, which a file without `qdot` columns cannot be checked for
    /// ([`check_velocities`](Self::check_velocities)), reads 1000 times slower.
    pub fn unlikely_rate(&self) -> Option<String> {
        let span = self.t.last()? - self.t.first()?;
        let rate = (self.len() - 1) as f64 / span;
        (self.len() > 1 && rate < SLOWEST_LIKELY_RATE_HZ).then(|| {
            format!(
                "its rows come {} per second of t, fewer than a robot's recording holds \
                 ({SLOWEST_LIKELY_RATE_HZ} or more): is t in seconds? (in milliseconds, a 1 kHz \
                 recording reads 1 per second)",
                three_digits(rate)
            )
        })
    }
}

/// `x` with three significant digits (0.00100, 0.0175, 131).
fn three_digits(x: f64) -> String {
    let decimals = (2.0 - x.abs().log10().floor()).clamp(0.0, 12.0) as usize;
    format!("{x:.decimals$}")
}

/// Row `k` of `x` (row-major, `n` per row) minus row `k - 1`, over `t[k] - t[k - 1]`; row 0
/// (no earlier sample) is NaN.
fn backward_differences(t: &[f64], x: &[f64], n: usize) -> Vec<f64> {
    let mut out = vec![f64::NAN; x.len()];
    for k in 1..t.len() {
        let dt = t[k] - t[k - 1];
        for i in 0..n {
            out[k * n + i] = (x[k * n + i] - x[(k - 1) * n + i]) / dt;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::tests::{parse, HEADER};

    #[test]
    fn derivatives_left_out_for_every_joint_are_taken_by_differences() {
        // q = t^2 on joint a and 3 t on b at uneven steps; the derivatives are differences
        // over each step, and the rows without an earlier sample are dropped.
        let t = [0.0, 0.1, 0.3, 0.4, 0.7];
        let body: String = t
            .iter()
            .map(|t| format!("{t},{},{},1,2\n", t * t, 3.0 * t))
            .collect();
        let both = parse(&format!("t,q.a,q.b,tau.a,tau.b\n{body}")).unwrap();
        assert_eq!(both.derived, ["qdot", "qddot"]);
        assert_eq!(both.t, [0.3, 0.4, 0.7]);
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        // qdot: (t_k^2 - t_{k-1}^2) / dt = t_k + t_{k-1}; qddot: its difference over dt.
        assert!(
            close(&both.qdot, &[0.4, 3.0, 0.7, 3.0, 1.1, 3.0]),
            "{:?}",
            both.qdot
        );
        assert!(
            close(&both.qddot, &[1.5, 0.0, 3.0, 0.0, 4.0 / 3.0, 0.0]),
            "{:?}",
            both.qddot
        );
        assert_eq!(both.tau, [1.0, 2.0, 1.0, 2.0, 1.0, 2.0]);
        // Only qddot left out: qdot as recorded, one row dropped.
        let body: String = t
            .iter()
            .map(|t| format!("{t},{},0,{t},0,1,2\n", t * t))
            .collect();
        let one = parse(&format!("t,q.a,q.b,qdot.a,qdot.b,tau.a,tau.b\n{body}")).unwrap();
        assert_eq!(
            (one.derived.as_slice(), one.len()),
            (["qddot".to_string()].as_slice(), 4)
        );
        assert!(
            close(&one.qddot, &[1.0, 0.0, 1.0, 0.0, 1.0, 0.0]),
            "{:?}",
            one.qddot
        );
        // A file with them reads as before.
        let full = parse(&format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n")).unwrap();
        assert!(full.derived.is_empty() && full.len() == 1);
    }

    #[test]
    fn a_time_in_milliseconds_or_velocities_in_degrees_are_refused() {
        // q = sin t on two joints at 100 Hz, qdot = cos t: consistent in seconds.
        let rows = |time_scale: f64, velocity_scale: f64| -> String {
            (0..200)
                .map(|k| {
                    let t = 0.01 * k as f64;
                    let (q, v) = (t.sin(), velocity_scale * t.cos());
                    format!("{},{q},{q},{v},{v},0,0,1,2\n", t * time_scale)
                })
                .collect()
        };
        assert!(parse(&format!("{HEADER}\n{}", rows(1.0, 1.0))).is_ok());
        let err = parse(&format!("{HEADER}\n{}", rows(1000.0, 1.0))).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("x.csv: the differences of q over t are 0.00100 times qdot"),
            "{err}"
        );
        let err = parse(&format!("{HEADER}\n{}", rows(1.0, 57.29577951308232))).unwrap_err();
        assert!(err.to_string().contains("are 0.0175 times qdot"), "{err}");
        // Velocities unrelated to the angles (a column of zeros) say nothing about units.
        assert!(parse(&format!("{HEADER}\n{}", rows(1000.0, 0.0))).is_ok());
    }

    #[test]
    fn a_slow_time_column_is_questioned() {
        let rows = |step: f64| -> String {
            (0..30)
                .map(|k| format!("{},{k},0,1,2\n", step * k as f64))
                .collect()
        };
        let at = |step| parse(&format!("t,q.a,q.b,tau.a,tau.b\n{}", rows(step))).unwrap();
        assert_eq!(at(0.01).unlikely_rate(), None);
        let warning = at(1.0).unlikely_rate().unwrap();
        assert!(
            warning.starts_with("its rows come 1.00 per second of t"),
            "{warning}"
        );
    }

    #[test]
    fn a_wrapped_angle_is_unwrapped_a_jump_refused_and_a_glitch_questioned() {
        // Joint b turns at 2 rad/s through pi at 100 Hz; wrapped to +-pi it steps by 2 pi.
        let rows = |wrap: bool, glitch: f64| -> String {
            (0..100)
                .map(|k| {
                    let t = 0.01 * k as f64;
                    let mut b = 2.5 + 2.0 * t;
                    if wrap && b > std::f64::consts::PI {
                        b -= 2.0 * std::f64::consts::PI;
                    }
                    let a = if k == 40 { 0.3 + glitch } else { 0.3 };
                    format!("{t},{a},{b},0,2,0,0,1,2\n")
                })
                .collect()
        };
        let clean = parse(&format!("{HEADER}\n{}", rows(false, 0.0))).unwrap();
        assert_eq!(clean.implausible_speed(), None);
        assert_eq!(clean.unwrapped_note(), None);
        // Read wrapped, the angle is put back on its first row's branch: the clean recording.
        let wrapped = parse(&format!("{HEADER}\n{}", rows(true, 0.0))).unwrap();
        assert_eq!(wrapped.unwrapped, vec!["b".to_string()]);
        assert!(wrapped
            .unwrapped_note()
            .unwrap()
            .starts_with("q.b read within one turn"));
        for (got, want) in wrapped.q.iter().zip(&clean.q) {
            assert!((got - want).abs() < 1e-12, "{got} against {want}");
        }
        // A step of 4 rad there and back is no turn: refused, named.
        let err = parse(&format!("{HEADER}\n{}", rows(false, 4.0))).unwrap_err();
        assert!(
            err.to_string()
                .contains("q.a steps from 0.300 to 4.300 between t = 0.39 and 0.4 s")
                && err.to_string().contains("not a whole turn"),
            "{err}"
        );
        // One row 1.5 rad off: 150 rad/s there and back.
        let warning = parse(&format!("{HEADER}\n{}", rows(false, 1.5)))
            .unwrap()
            .implausible_speed()
            .unwrap();
        assert!(
            warning.starts_with("q.a moves 1.500 between t = 0.39 and 0.4 s (150 per second")
                && warning.contains("2 step(s)"),
            "{warning}"
        );
    }

    #[test]
    fn derivatives_of_some_joints_only_or_too_few_rows_are_refused() {
        let err = parse("t,q.a,q.b,qdot.a,tau.a,tau.b\n0,1,2,3,4,5\n").unwrap_err();
        assert!(
            err.to_string().contains("x.csv:1: missing column `qdot.b`"),
            "{err}"
        );
        let err = parse("t,q.a,tau.a\n0,1,2\n0.1,1,2\n").unwrap_err();
        assert!(
            err.to_string()
                .contains("x.csv: no qdot and qddot columns and too few rows"),
            "{err}"
        );
    }
}
