//! Checks of a scenario against the arm it names: the desired trajectory inside the joints'
//! position and velocity limits, the reference saturation inside the position limits. A
//! scenario written for another arm (Baxter's pose on a Panda) is refused with a hint
//! instead of being run into the limits.

use admittance_control::{ConfigError, JointValues};
use admittance_dynamics::Model;

use super::Scenario;

/// Slack on the limits (rad): values written with a few decimals that round onto a limit.
const SLACK: f64 = 1e-6;

/// The middle of each joint's limits (0 where a limit is infinite): the default pose.
pub fn mid_range(model: &Model) -> Vec<f64> {
    model
        .position_limits()
        .map(|(lo, hi)| {
            if lo.is_finite() && hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                0.0
            }
        })
        .collect()
}

fn per_joint(v: &JointValues, n: usize) -> Option<Vec<f64>> {
    match v {
        JointValues::Uniform(x) => Some(vec![*x; n]),
        JointValues::PerJoint(xs) if xs.len() == n => Some(xs.clone()),
        JointValues::PerJoint(_) => None,
    }
}

fn fmt_pose(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.3}")).collect();
    format!("[{}]", parts.join(", "))
}

impl Scenario {
    /// Checks the scenario against `model`'s joint limits (after [`Scenario::validate`]).
    pub fn validate_for_arm(&self, model: &Model) -> Vec<ConfigError> {
        let mut out = Vec::new();
        let n = model.nq();
        let names: Vec<&str> = model.joint_names().collect();
        let mid = mid_range(model);
        let hint = format!(
            "the desired motion must stay inside this arm's limits; its mid-range pose is {} (leave `trajectory.offset` out to use it) -- values written for another arm do not fit this one",
            fmt_pose(&mid)
        );
        let tr = &self.trajectory;
        // Per joint: the range of the pose part and where it is written.
        let mut low = vec![f64::INFINITY; n];
        let mut high = vec![f64::NEG_INFINITY; n];
        let mut speed = vec![0.0f64; n];
        let pose_key;
        if !tr.waypoints.is_empty() {
            pose_key = "trajectory.waypoints";
            for pair in tr.waypoints.windows(2) {
                let dt = pair[1][0] - pair[0][0];
                for j in 0..n {
                    // The quintic blend's peak speed is 15/8 of the mean.
                    speed[j] = speed[j].max(1.875 * (pair[1][j + 1] - pair[0][j + 1]).abs() / dt);
                }
            }
            for w in &tr.waypoints {
                for j in 0..n {
                    low[j] = low[j].min(w[j + 1]);
                    high[j] = high[j].max(w[j + 1]);
                }
            }
        } else {
            pose_key = "trajectory.offset";
            let pose = tr.offset.clone().unwrap_or_else(|| mid.clone());
            low.copy_from_slice(&pose);
            high.copy_from_slice(&pose);
        }
        let mut sine_key: Vec<Option<String>> = vec![None; n];
        for (k, s) in tr.sines.iter().enumerate() {
            if let Some(j) = names.iter().position(|nm| *nm == s.joint) {
                let a = s.amplitude.abs();
                low[j] -= a;
                high[j] += a;
                speed[j] += a * 2.0 * std::f64::consts::PI / s.period;
                sine_key[j].get_or_insert_with(|| format!("trajectory.sines.{k}.amplitude"));
            }
        }
        for (j, joint) in model.joints.iter().enumerate() {
            let (lo, hi, v) = (
                joint.limits.lower,
                joint.limits.upper,
                joint.limits.velocity,
            );
            if low[j] < lo - SLACK || high[j] > hi + SLACK {
                // Blame the sine when the pose itself is inside the limits.
                let centre = 0.5 * (low[j] + high[j]);
                let key = match &sine_key[j] {
                    Some(k) if centre >= lo - SLACK && centre <= hi + SLACK => k.clone(),
                    _ => pose_key.to_string(),
                };
                out.push(
                    ConfigError::new(
                        key,
                        format!(
                            "q_d of {} spans [{:.3}, {:.3}] rad, outside its limits [{lo:.3}, {hi:.3}] rad",
                            joint.name, low[j], high[j]
                        ),
                    )
                    .hint(hint.clone()),
                );
            }
            if v.is_finite() && v > 0.0 && speed[j] > v * (1.0 + 1e-9) {
                out.push(
                    ConfigError::new(
                        sine_key[j].clone().unwrap_or_else(|| pose_key.to_string()),
                        format!(
                            "q_d of {} moves at up to {:.3} rad/s, beyond its velocity limit {v} rad/s",
                            joint.name, speed[j]
                        ),
                    )
                    .hint("lower the amplitude or lengthen the period (or the time between waypoints)"),
                );
            }
        }
        if let Some(q0) = self.plant.initial_q.get(..n).filter(|q| q.len() == n) {
            for (j, (lo, hi)) in model.position_limits().enumerate() {
                if !(q0[j] >= lo - SLACK && q0[j] <= hi + SLACK) {
                    out.push(
                        ConfigError::new(
                            "plant.initial_q",
                            format!(
                                "{} starts at {:.3} rad, outside its limits [{lo:.3}, {hi:.3}] rad",
                                names[j], q0[j]
                            ),
                        )
                        .hint(hint.clone()),
                    );
                }
            }
        }
        if let Some(sat) = self
            .admittance
            .as_ref()
            .filter(|a| a.enabled)
            .and_then(|a| a.config.saturation.as_ref())
        {
            if let (Some(c), Some(h)) = (per_joint(&sat.centre, n), per_joint(&sat.half_range, n)) {
                for (j, (lo, hi)) in model.position_limits().enumerate() {
                    if h[j].is_finite() && (c[j] - h[j] < lo - SLACK || c[j] + h[j] > hi + SLACK) {
                        out.push(
                            ConfigError::new(
                                "admittance.saturation.half_range",
                                format!(
                                    "keeps q_r of {} inside ({:.3}, {:.3}) rad, which leaves its limits [{lo:.3}, {hi:.3}] rad",
                                    names[j],
                                    c[j] - h[j],
                                    c[j] + h[j]
                                ),
                            )
                            .hint("choose centre and half_range inside the joint's limits (the interval the reference may use)"),
                        );
                    }
                }
            }
        }
        out
    }
}

impl Scenario {
    /// The gain rules of `admittance_control::gains` on this scenario's controller and
    /// admittance, for `model` moving through `poses` (the desired motion, sampled) with the
    /// plant's viscous friction `damping` per joint: one warning per joint and rule, at the
    /// key to change, with the suggested value (after [`Scenario::validate`]).
    pub fn gain_warnings(
        &self,
        model: &Model,
        poses: &[Vec<f64>],
        damping: &[f64],
    ) -> Vec<ConfigError> {
        use admittance_control::gains;
        use admittance_loop::{ControllerKind, ObserverKind};
        let n = model.nq();
        let joints: Vec<String> = model.joint_names().map(String::from).collect();
        let inertia = gains::JointInertia::over(model, poses.iter().map(Vec::as_slice));
        let limits = gains::LoopLimits {
            control_rate_hz: self.plant.control_rate_hz,
            velocity_filter_hz: self.plant.sensors.filter_cutoff_hz,
            damping: damping.to_vec(),
        };
        let mut advice = Vec::new();
        if self.controller.kind == ControllerKind::Neural {
            let nn = &self.controller.neural;
            if let (Some(k1), Some(k2)) = (per_joint(&nn.k1, n), per_joint(&nn.k2, n)) {
                advice.extend(gains::check_feedback(
                    "controller.neural.k2",
                    &joints,
                    &k1,
                    &k2,
                    &inertia,
                    &limits,
                ));
            }
        }
        let estimating = !matches!(
            self.observer.kind,
            ObserverKind::None | ObserverKind::Oracle
        );
        if let Some(a) = self.admittance.as_ref().filter(|a| a.enabled && estimating) {
            let c = &a.config;
            if let (Some(d), Some(s)) = (per_joint(&c.damping, n), per_joint(&c.stiffness, n)) {
                let m = c.inertia.as_ref().and_then(|m| per_joint(m, n));
                advice.extend(gains::check_admittance(
                    "admittance",
                    &joints,
                    &d,
                    &s,
                    m.as_deref(),
                    self.observer.cutoff_hz,
                ));
            }
        }
        advice
            .into_iter()
            .map(|a| {
                ConfigError::new(a.key.clone(), a.message.clone()).hint(format!(
                    "set {}[{}] ({}) to {} (`admittance gains --urdf FILE` prints a starting set for the arm)",
                    a.key, a.index, a.joint, a.suggested
                ))
            })
            .collect()
    }
}
