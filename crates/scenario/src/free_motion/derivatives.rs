//! The derivatives a free-motion CSV leaves out, taken by backward differences
//! (`free_motion.rs`, [`DERIVED_NOTE`]).

use super::FreeMotionData;
#[cfg(doc)]
use super::DERIVED_NOTE;

impl FreeMotionData {
    /// Fills the derivatives in `derived` by backward differences and drops the rows that
    /// have no earlier sample (one per derivative taken in turn).
    pub(super) fn take_differences(&mut self) {
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
    use super::super::{FreeMotionData, FreeMotionError};

    const HEADER: &str = "t,q.a,q.b,qdot.a,qdot.b,qddot.a,qddot.b,tau.a,tau.b";

    fn parse(body: &str) -> Result<FreeMotionData, FreeMotionError> {
        FreeMotionData::parse(body, "x.csv")
    }

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
