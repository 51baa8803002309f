//! The desired joint trajectory `q_d(t)` (`[trajectory]`): a pose (the offset, or a quintic
//! blend between waypoints) plus sines, or an excitation's Fourier series.

use admittance_dynamics::FourierSeries;

use crate::spec::TrajectorySpec;

/// Evaluates `q_d`, `q_d'`, `q_d''`; allocation-free after construction.
#[derive(Clone, Debug)]
pub struct Trajectory {
    offset: Vec<f64>,
    /// `[t, q_1..q_n]` rows.
    waypoints: Vec<Vec<f64>>,
    /// (joint index, amplitude, angular frequency, phase).
    sines: Vec<(usize, f64, f64, f64)>,
    /// An excitation: base frequency (rad/s) and one series per joint, added to the rest
    /// (the offset is then zero).
    fourier: Option<(f64, Vec<FourierSeries>)>,
}

/// The quintic blend `s(u) = 10u^3 - 15u^4 + 6u^5` and its first two derivatives in `u`.
fn blend(u: f64) -> (f64, f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (
        u3 * (10.0 - 15.0 * u + 6.0 * u2),
        30.0 * u2 * (1.0 - 2.0 * u + u2),
        60.0 * u * (1.0 - 3.0 * u + 2.0 * u2),
    )
}

impl Trajectory {
    /// The trajectory of `spec` on the arm whose joints are `joints`; `default_offset` is
    /// the pose without `offset` and `waypoints` (the middle of the limits). Sines on unknown
    /// joints are left out: validation reports them.
    pub fn new(spec: &TrajectorySpec, joints: &[String], default_offset: &[f64]) -> Self {
        let sines = spec
            .sines
            .iter()
            .filter_map(|s| {
                let j = joints.iter().position(|n| n == &s.joint)?;
                Some((
                    j,
                    s.amplitude,
                    2.0 * std::f64::consts::PI / s.period,
                    s.phase,
                ))
            })
            .collect();
        Self {
            offset: spec
                .offset
                .clone()
                .unwrap_or_else(|| default_offset.to_vec()),
            waypoints: spec.waypoints.clone(),
            sines,
            fourier: None,
        }
    }

    /// The excitation's series (base frequency `w` in rad/s, one series per joint) as the
    /// whole trajectory: `q_d(t) = sum of the series`, periodic.
    pub fn excitation(w: f64, series: Vec<FourierSeries>) -> Self {
        Self {
            offset: vec![0.0; series.len()],
            waypoints: Vec::new(),
            sines: Vec::new(),
            fourier: Some((w, series)),
        }
    }

    /// `q_d`, `q_d'`, `q_d''` at time `t`.
    pub fn eval(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        qd.fill(0.0);
        qdd.fill(0.0);
        match self.segment(t) {
            None => q.copy_from_slice(&self.offset),
            Some((a, b)) if a == b => q.copy_from_slice(&self.waypoints[a][1..]),
            Some((a, b)) => {
                let (wa, wb) = (&self.waypoints[a], &self.waypoints[b]);
                let span = wb[0] - wa[0];
                let (s, ds, dds) = blend((t - wa[0]) / span);
                for j in 0..q.len() {
                    let delta = wb[j + 1] - wa[j + 1];
                    q[j] = wa[j + 1] + s * delta;
                    qd[j] = ds * delta / span;
                    qdd[j] = dds * delta / (span * span);
                }
            }
        }
        for &(j, a, w, phi) in &self.sines {
            let (s, c) = (w * t + phi).sin_cos();
            q[j] += a * s;
            qd[j] += a * w * c;
            qdd[j] -= a * w * w * s;
        }
        if let Some((w, series)) = &self.fourier {
            for (j, s) in series.iter().enumerate() {
                let [p, v, a] = s.evaluate(*w, t);
                q[j] += p;
                qd[j] += v;
                qdd[j] += a;
            }
        }
    }

    /// The waypoints around `t` (equal indices: hold that one); `None` without waypoints.
    fn segment(&self, t: f64) -> Option<(usize, usize)> {
        let last = self.waypoints.len().checked_sub(1)?;
        if t <= self.waypoints[0][0] {
            return Some((0, 0));
        }
        if t >= self.waypoints[last][0] {
            return Some((last, last));
        }
        let b = self.waypoints.iter().position(|w| w[0] > t).unwrap_or(last);
        Some((b - 1, b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waypoints_blend_with_zero_velocity_at_each_and_derivatives_that_match() {
        let spec = TrajectorySpec {
            offset: None,
            waypoints: vec![vec![1.0, 0.0], vec![3.0, 2.0], vec![4.0, -1.0]],
            sines: Vec::new(),
            excitation: None,
        };
        let tr = Trajectory::new(&spec, &["j".into()], &[9.0]);
        let at = |t: f64| {
            let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
            tr.eval(t, &mut q, &mut qd, &mut qdd);
            (q[0], qd[0], qdd[0])
        };
        assert_eq!(at(0.0), (0.0, 0.0, 0.0));
        assert_eq!(at(3.0).0, 2.0);
        assert_eq!(at(9.0), (-1.0, 0.0, 0.0));
        assert!(
            (at(2.0).0 - 1.0).abs() < 1e-12,
            "the middle of a blend is half-way"
        );
        for t in [1.3, 2.2, 3.5] {
            let h = 1e-6;
            let (q0, v0, a0) = at(t);
            let (q1, v1, _) = at(t + h);
            assert!(((q1 - q0) / h - v0).abs() < 1e-4, "velocity at {t}");
            assert!(((v1 - v0) / h - a0).abs() < 1e-3, "acceleration at {t}");
        }
        assert!(at(1.0).1.abs() < 1e-12 && at(3.0).1.abs() < 1e-12);
    }
}
