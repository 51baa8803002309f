//! Checks of a resolved scenario that serde cannot make: signs, ranges, names, and the
//! combinations of sections.

use admittance_control::ConfigError;
use admittance_loop::{ControllerKind, LoopError};

use super::Scenario;

impl Scenario {
    /// Checks what serde cannot: signs, ranges, names. `joints` are the model's joint names.
    /// Every problem is returned, each at its key.
    pub fn validate(&self, joints: &[String]) -> Vec<ConfigError> {
        let mut out = Vec::new();
        self.validate_times(&mut out);
        self.validate_trajectory(joints, &mut out);
        out.extend(self.loop_config().problems().into_iter().map(loop_problem));
        self.validate_dynamic_nodes(&mut out);
        self.validate_training(&mut out);
        self.validate_contact(&mut out);
        out.extend(self.gates.problems("gates").into_iter().map(loop_problem));
        for (key, problem) in self.health.problems() {
            out.push(
                ConfigError::new(format!("health.{key}"), problem)
                    .hint("a threshold of the run's health rules (docs/outputs.md, \"Health\")"),
            );
        }
        if self.output.decimation == 0 {
            out.push(ConfigError::new("output.decimation", "must be at least 1"));
        }
        out
    }

    fn validate_times(&self, out: &mut Vec<ConfigError>) {
        if !(self.duration.is_finite() && self.duration > 0.0) {
            out.push(ConfigError::new(
                "duration",
                format!("is {}, must be > 0 s", self.duration),
            ));
        }
        if !(self.evaluation_start >= 0.0 && self.evaluation_start < self.duration) {
            out.push(
                ConfigError::new(
                    "evaluation_start",
                    format!("is {}, must be in [0, duration)", self.evaluation_start),
                )
                .hint("metrics are computed over [evaluation_start, duration]"),
            );
        }
    }

    fn validate_trajectory(&self, joints: &[String], out: &mut Vec<ConfigError>) {
        let t = &self.trajectory;
        if t.excitation.is_some()
            && (t.offset.is_some() || !t.waypoints.is_empty() || !t.sines.is_empty())
        {
            out.push(
                ConfigError::new(
                    "trajectory.excitation",
                    "is the whole trajectory: it does not go with offset, waypoints or sines",
                )
                .hint("keep either the excitation table or the pose and sines"),
            );
        }
        if let Some(Err(e)) = t.excitation.as_ref().map(|e| e.validate()) {
            out.push(ConfigError::new("trajectory.excitation", e.to_string()));
        }
        let n = joints.len();
        if let Some(offset) = &self.trajectory.offset {
            if offset.len() != n {
                out.push(
                    ConfigError::new(
                        "trajectory.offset",
                        format!("has {} values, the arm has {n} joints", offset.len()),
                    )
                    .hint(format!("one value per joint: {}; or leave `offset` out for the middle of the joint limits", joints.join(", "))),
                );
            }
            if offset.iter().any(|v| !v.is_finite()) {
                out.push(ConfigError::new("trajectory.offset", "must be finite"));
            }
            if !self.trajectory.waypoints.is_empty() {
                out.push(ConfigError::new(
                    "trajectory.waypoints",
                    "give either `offset` or `waypoints`, not both",
                ));
            }
        }
        let mut previous = f64::NEG_INFINITY;
        for (k, w) in self.trajectory.waypoints.iter().enumerate() {
            let key = format!("trajectory.waypoints.{k}");
            if w.len() != n + 1 {
                out.push(
                    ConfigError::new(&key, format!("has {} values; a waypoint is [t, then one angle per joint] ({} values)", w.len(), n + 1))
                        .hint(format!("joints: {}", joints.join(", "))),
                );
                continue;
            }
            if w.iter().any(|v| !v.is_finite()) {
                out.push(ConfigError::new(&key, "must be finite"));
            } else if w[0] <= previous {
                out.push(ConfigError::new(
                    &key,
                    format!(
                        "its time {} s is not after the previous waypoint's ({previous} s)",
                        w[0]
                    ),
                ));
            }
            previous = w[0];
        }
        for (k, s) in self.trajectory.sines.iter().enumerate() {
            let key = format!("trajectory.sines.{k}");
            if !joints.contains(&s.joint) {
                out.push(
                    ConfigError::new(
                        format!("{key}.joint"),
                        format!("unknown joint '{}'", s.joint),
                    )
                    .hint(format!("joints of this arm: {}", joints.join(", "))),
                );
            }
            if !(s.period.is_finite() && s.period > 0.0) {
                out.push(ConfigError::new(
                    format!("{key}.period"),
                    format!("is {}, must be > 0 s", s.period),
                ));
            }
            if !s.amplitude.is_finite() || !s.phase.is_finite() {
                out.push(ConfigError::new(
                    key.clone(),
                    "amplitude and phase must be finite",
                ));
            }
        }
    }

    fn validate_dynamic_nodes(&self, out: &mut Vec<ConfigError>) {
        if let Some(d) = &self.dynamic_nodes {
            if self.controller.kind != ControllerKind::Neural {
                out.push(ConfigError::new(
                    "dynamic_nodes",
                    "needs controller.kind = \"neural\"",
                ));
            }
            if !(d.discard_time > 0.0
                && d.discard_time < d.grow_time
                && d.grow_time < self.duration)
            {
                out.push(
                    ConfigError::new(
                        "dynamic_nodes.grow_time",
                        "needs 0 < discard_time < grow_time < duration",
                    )
                    .hint("discard first, then grow, before the run ends"),
                );
            }
            if !(d.upsilon > 0.0 && d.upsilon < 1.0) {
                out.push(ConfigError::new(
                    "dynamic_nodes.upsilon",
                    format!("is {}, must be in (0, 1)", d.upsilon),
                ));
            }
            if !(d.approximation_window > 0.0 && d.approximation_window <= d.discard_time) {
                out.push(ConfigError::new(
                    "dynamic_nodes.approximation_window",
                    "must be > 0 and at most discard_time",
                ));
            }
            // Each phase's window must lie inside that phase, or the "after discard" error
            // would mix in samples from before the discard (and likewise for growth).
            if d.approximation_window > d.grow_time - d.discard_time
                || d.approximation_window > self.duration - d.grow_time
            {
                out.push(
                    ConfigError::new(
                        "dynamic_nodes.approximation_window",
                        format!(
                            "is {} s, longer than a phase (grow_time - discard_time = {} s, duration - grow_time = {} s)",
                            d.approximation_window,
                            d.grow_time - d.discard_time,
                            self.duration - d.grow_time
                        ),
                    )
                    .hint("each phase's error is measured over the last approximation_window seconds of that phase"),
                );
            }
        }
    }

    /// The scenario's own part of `[observer]`: the training of the learned observers.
    fn validate_training(&self, out: &mut Vec<ConfigError>) {
        self.validate_identify(out);
        if self.observer.kind.is_learned() {
            match &self.observer.training {
                None => out.push(
                    ConfigError::new(
                        "observer.kind",
                        "needs an [observer.training] table (the free-motion data to learn from)",
                    )
                    .hint("add [observer.training] with data = \"free_motion.toml\" (or a recorded FILE.csv) and validation = ..."),
                ),
                Some(t) => {
                    if t.nodes == 0 {
                        out.push(ConfigError::new("observer.training.nodes", "must be at least 1"));
                    }
                    if !(t.width_scale.is_finite() && t.width_scale > 0.0) {
                        out.push(ConfigError::new(
                            "observer.training.width_scale",
                            format!("is {}, must be finite and > 0", t.width_scale),
                        ));
                    }
                    if t.width_neighbours == 0 {
                        out.push(ConfigError::new(
                            "observer.training.width_neighbours",
                            "must be at least 1",
                        ));
                    }
                    if t.friction_features
                        && (t.friction_scales.is_empty()
                            || t.friction_scales.iter().any(|v| !(v.is_finite() && *v > 0.0)))
                    {
                        out.push(ConfigError::new(
                            "observer.training.friction_scales",
                            format!(
                                "is {:?}, must be a non-empty list of finite values > 0 (rad/s)",
                                t.friction_scales
                            ),
                        ));
                    }
                }
            }
        }
    }
}

impl Scenario {
    /// `[observer.training] identify = true`: the identified model replaces the URDF, so
    /// neither a given identification file nor a scaled URDF goes with it.
    fn validate_identify(&self, out: &mut Vec<ConfigError>) {
        let o = &self.observer;
        if !o.training.as_ref().is_some_and(|t| t.identify) {
            return;
        }
        if o.identification.is_some() {
            out.push(
                ConfigError::new(
                    "observer.training.identify",
                    "and observer.identification both give the nominal model",
                )
                .hint("keep one: identify = true fits it on the training data, identification = FILE reads it"),
            );
        }
        if o.nominal_inertia_scale != 1.0 {
            out.push(
                ConfigError::new(
                    "observer.nominal_inertia_scale",
                    format!(
                        "is {}; with observer.training.identify = true the nominal model is the identified one",
                        o.nominal_inertia_scale
                    ),
                )
                .hint("remove nominal_inertia_scale (default 1)"),
            );
        }
    }
}

/// A problem of the loop's settings as a scenario problem at the same key (the control
/// rate is the plant's in a scenario file, the gates a table of their own).
pub(crate) fn loop_problem(e: LoopError) -> ConfigError {
    let mut setting = e.into_setting();
    if setting.key == "control_rate_hz" {
        setting.key = "plant.control_rate_hz".into();
    } else if let Some(rest) = setting.key.strip_prefix("signals.gates") {
        setting.key = format!("gates{rest}");
    }
    setting
}
