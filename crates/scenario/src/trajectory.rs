//! The desired joint trajectory `q_d(t)`: an offset plus sines (`[trajectory]`).

use crate::spec::TrajectorySpec;

/// Desired trajectory evaluation: `q_d`, `q_d'`, `q_d''` at `t` into the three slices.
pub struct Trajectory {
    offset: Vec<f64>,
    /// (joint index, amplitude, angular frequency, phase).
    sines: Vec<(usize, f64, f64, f64)>,
}

impl Trajectory {
    /// The trajectory of `spec` on the arm whose joints are `joints` (sines on unknown
    /// joints are left out: validation reports them).
    pub fn new(spec: &TrajectorySpec, joints: &[String]) -> Self {
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
            offset: spec.offset.clone(),
            sines,
        }
    }

    /// `q_d`, `q_d'`, `q_d''` at time `t`.
    pub fn eval(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        q.copy_from_slice(&self.offset);
        qd.fill(0.0);
        qdd.fill(0.0);
        for &(j, a, w, phi) in &self.sines {
            let (s, c) = (w * t + phi).sin_cos();
            q[j] += a * s;
            qd[j] += a * w * c;
            qdd[j] -= a * w * w * s;
        }
    }
}
