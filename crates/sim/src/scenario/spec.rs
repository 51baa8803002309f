//! The typed scenario: what a TOML file in `scenarios/` describes.
//!
//! ```toml
//! name = "deadzone"
//! description = "one line for `admittance list`"
//! duration = 30.0            # s
//! evaluation_start = 10.0    # s: metrics use [evaluation_start, duration]
//!
//! [arm]
//! urdf = "../models/baxter_left_arm.urdf"   # relative to the scenario file
//! base = "base"
//! tip = "left_hand"
//!
//! [trajectory]               # q_d(t) = offset + sum of sines
//! offset = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5]
//! [[trajectory.sines]]
//! joint = "left_s0"
//! amplitude = 1.0
//! period = 4.49              # s
//!
//! [plant]                    # admittance_sim::PlantConfig: friction, deadzones, spring, sensors, ...
//! [controller]               # kind = "neural" | "pd" | "computed_torque", with [controller.neural] etc.
//! [admittance]               # optional: admittance model and reference saturation
//! [observer]                 # kind = "none" | "oracle" | "momentum", nominal_inertia_scale, cutoff_hz
//! [record]                   # optional: free_motion_csv = true (free-motion data, docs/outputs.md)
//! [dynamic_nodes]            # optional: discard / grow events (experiment C)
//! [variants.NAME]            # overrides of any of the above, per variant
//! ```

use std::path::{Path, PathBuf};

use admittance_control::{
    AdmittanceConfig, ComputedTorqueConfig, GrowthParams, MomentumObserverConfig,
    NeuralControllerConfig, PdConfig,
};
use serde::{Deserialize, Serialize};

use super::source::Invalid;
use crate::PlantConfig;

/// The chain to load.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmSpec {
    /// URDF file, relative to the scenario file (or absolute).
    pub urdf: PathBuf,
    /// Base link (default: the root link).
    #[serde(default)]
    pub base: Option<String>,
    /// Tip link (default: the single leaf).
    #[serde(default)]
    pub tip: Option<String>,
}

/// One sinusoidal component `amplitude * sin(2 pi t / period + phase)` on a joint.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SineSpec {
    /// Joint name.
    pub joint: String,
    /// Amplitude (rad or m).
    pub amplitude: f64,
    /// Period (s).
    pub period: f64,
    /// Phase (rad).
    #[serde(default)]
    pub phase: f64,
}

/// The desired joint trajectory `q_d(t)`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// Constant part, one value per joint.
    pub offset: Vec<f64>,
    /// Sinusoidal components.
    #[serde(default)]
    pub sines: Vec<SineSpec>,
}

/// Which controller runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// The paper's adaptive neural controller (METHOD.md section 3).
    Neural,
    /// Joint PD (optionally with nominal gravity compensation).
    Pd,
    /// Computed torque with the nominal model.
    ComputedTorque,
}

/// The controller section: a kind and the settings of each kind (only the chosen one is
/// used, so variants can switch kinds).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// The controller that runs.
    pub kind: ControllerKind,
    /// Settings of the neural controller.
    #[serde(default)]
    pub neural: NeuralControllerConfig,
    /// Settings of the PD controllers.
    #[serde(default)]
    pub pd: Option<PdConfig>,
    /// Settings of computed torque.
    #[serde(default)]
    pub computed_torque: Option<ComputedTorqueConfig>,
}

/// Where the external-torque estimate that drives the admittance model comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObserverKind {
    /// No estimate (zeros).
    #[default]
    None,
    /// The true external torque of the plant (an upper bound for any observer).
    Oracle,
    /// The generalised-momentum observer with a nominal model (METHOD.md section 5,
    /// baseline): settings in `[observer.momentum]`, model error in `nominal_inertia_scale`.
    Momentum,
}

/// The observer section (`[observer]`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverSpec {
    /// The estimate's source.
    #[serde(default)]
    pub kind: ObserverKind,
    /// The observer's nominal model is the arm's model with every link mass and inertia
    /// multiplied by this (0.8: a 20% model error). Default 1. Used by `momentum`.
    #[serde(default = "unit")]
    pub nominal_inertia_scale: f64,
    /// Cut-off (Hz) of a first-order low-pass applied to the estimate of every observer
    /// but `oracle` (METHOD.md sections 5 and 7); 0 disables it. Default 0.
    #[serde(default)]
    pub cutoff_hz: f64,
    /// Settings of the momentum observer.
    #[serde(default)]
    pub momentum: MomentumObserverConfig,
}

impl Default for ObserverSpec {
    fn default() -> Self {
        Self {
            kind: ObserverKind::None,
            nominal_inertia_scale: 1.0,
            cutoff_hz: 0.0,
            momentum: MomentumObserverConfig::default(),
        }
    }
}

fn unit() -> f64 {
    1.0
}

/// The admittance section.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdmittanceSpec {
    /// Whether the reference is shaped by the admittance model (otherwise `q_r = q_d`).
    #[serde(default = "yes")]
    pub enabled: bool,
    /// The model and its saturation.
    #[serde(flatten)]
    pub config: AdmittanceConfig,
}

fn yes() -> bool {
    true
}

/// Dynamic-node events of experiment C (METHOD.md section 4).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicNodesSpec {
    /// Time at which nodes whose tracked activation stayed below `upsilon` are discarded (s).
    pub discard_time: f64,
    /// Discard threshold Upsilon.
    pub upsilon: f64,
    /// Time at which growth near the trajectory starts (s).
    pub grow_time: f64,
    /// Nodes to add.
    pub grow_nodes: usize,
    /// Control steps between two additions.
    #[serde(default = "one")]
    pub grow_interval_steps: usize,
    /// Growth test parameters (`m`, `Xi`, spacing).
    pub growth: GrowthParams,
    /// Length of the window at the end of each phase over which the approximation error
    /// of f is measured (s).
    pub approximation_window: f64,
}

fn one() -> usize {
    1
}

/// Extra recordings (`[record]`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordSpec {
    /// Record what the sensors saw at the control rate, in the free-motion data format
    /// (METHOD.md section 5; columns in docs/outputs.md), to `free_motion.csv`.
    #[serde(default)]
    pub free_motion_csv: bool,
}

/// What the run writes.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write one CSV row every `decimation` control steps.
    #[serde(default = "ten")]
    pub decimation: usize,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { decimation: ten() }
    }
}

fn ten() -> usize {
    10
}

/// A whole scenario (one variant, resolved).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Scenario name (the summary's `scenario`).
    pub name: String,
    /// One line for `admittance list`.
    pub description: String,
    /// Simulated time (s).
    pub duration: f64,
    /// Start of the metrics window (s).
    #[serde(default)]
    pub evaluation_start: f64,
    /// Seed of every random draw of the run (sensor noise, node placement seeds are in
    /// their own sections); `--seed` overrides it.
    #[serde(default)]
    pub seed: Option<u64>,
    /// The arm.
    pub arm: ArmSpec,
    /// The desired trajectory.
    pub trajectory: TrajectorySpec,
    /// The plant (true arm, friction, deadzone, environment, sensors, rates).
    #[serde(default)]
    pub plant: PlantConfig,
    /// The controller.
    pub controller: ControllerSpec,
    /// The admittance model (absent: `q_r = q_d`).
    #[serde(default)]
    pub admittance: Option<AdmittanceSpec>,
    /// The external-torque estimate.
    #[serde(default)]
    pub observer: ObserverSpec,
    /// Dynamic-node events (experiment C).
    #[serde(default)]
    pub dynamic_nodes: Option<DynamicNodesSpec>,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Extra recordings.
    #[serde(default)]
    pub record: RecordSpec,
    /// Variant tables (read by [`super::ScenarioSource`], ignored here).
    #[serde(default, skip_serializing)]
    pub variants: Option<toml::Table>,
}

impl Scenario {
    /// The URDF path resolved against the scenario file's directory.
    pub fn urdf_path(&self, scenario_file: &Path) -> PathBuf {
        if self.arm.urdf.is_absolute() {
            self.arm.urdf.clone()
        } else {
            scenario_file
                .parent()
                .unwrap_or(Path::new("."))
                .join(&self.arm.urdf)
        }
    }

    /// Checks what serde cannot: signs, ranges, names. `joints` are the model's joint names.
    pub fn validate(&self, joints: &[String]) -> Vec<Invalid> {
        let mut out = Vec::new();
        if !(self.duration.is_finite() && self.duration > 0.0) {
            out.push(Invalid::new(
                "duration",
                format!("is {}, must be > 0 s", self.duration),
            ));
        }
        if !(self.evaluation_start >= 0.0 && self.evaluation_start < self.duration) {
            out.push(
                Invalid::new(
                    "evaluation_start",
                    format!("is {}, must be in [0, duration)", self.evaluation_start),
                )
                .hint("metrics are computed over [evaluation_start, duration]"),
            );
        }
        if self.trajectory.offset.len() != joints.len() {
            out.push(
                Invalid::new(
                    "trajectory.offset",
                    format!(
                        "has {} values, the arm has {} joints",
                        self.trajectory.offset.len(),
                        joints.len()
                    ),
                )
                .hint(format!("one value per joint: {}", joints.join(", "))),
            );
        }
        if self.trajectory.offset.iter().any(|v| !v.is_finite()) {
            out.push(Invalid::new("trajectory.offset", "must be finite"));
        }
        for (k, s) in self.trajectory.sines.iter().enumerate() {
            let key = format!("trajectory.sines.{k}");
            if !joints.contains(&s.joint) {
                out.push(
                    Invalid::new(
                        format!("{key}.joint"),
                        format!("unknown joint '{}'", s.joint),
                    )
                    .hint(format!("joints of this arm: {}", joints.join(", "))),
                );
            }
            if !(s.period.is_finite() && s.period > 0.0) {
                out.push(Invalid::new(
                    format!("{key}.period"),
                    format!("is {}, must be > 0 s", s.period),
                ));
            }
            if !s.amplitude.is_finite() || !s.phase.is_finite() {
                out.push(Invalid::new(
                    key.clone(),
                    "amplitude and phase must be finite",
                ));
            }
        }
        match self.controller.kind {
            ControllerKind::Pd if self.controller.pd.is_none() => out.push(
                Invalid::new(
                    "controller.pd",
                    "kind = \"pd\" needs a [controller.pd] table",
                )
                .hint("give kp and kd"),
            ),
            ControllerKind::ComputedTorque if self.controller.computed_torque.is_none() => out
                .push(Invalid::new(
                    "controller.computed_torque",
                    "kind = \"computed_torque\" needs a [controller.computed_torque] table",
                )),
            _ => {}
        }
        if let Some(d) = &self.dynamic_nodes {
            if self.controller.kind != ControllerKind::Neural {
                out.push(Invalid::new(
                    "dynamic_nodes",
                    "needs controller.kind = \"neural\"",
                ));
            }
            if !(d.discard_time > 0.0
                && d.discard_time < d.grow_time
                && d.grow_time < self.duration)
            {
                out.push(
                    Invalid::new(
                        "dynamic_nodes.grow_time",
                        "needs 0 < discard_time < grow_time < duration",
                    )
                    .hint("discard first, then grow, before the run ends"),
                );
            }
            if !(d.upsilon > 0.0 && d.upsilon < 1.0) {
                out.push(Invalid::new(
                    "dynamic_nodes.upsilon",
                    format!("is {}, must be in (0, 1)", d.upsilon),
                ));
            }
            if !(d.approximation_window > 0.0 && d.approximation_window <= d.discard_time) {
                out.push(Invalid::new(
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
                    Invalid::new(
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
        if !(self.observer.nominal_inertia_scale.is_finite()
            && self.observer.nominal_inertia_scale > 0.0)
        {
            out.push(Invalid::new(
                "observer.nominal_inertia_scale",
                format!("is {}, must be > 0", self.observer.nominal_inertia_scale),
            ));
        }
        if !(self.observer.cutoff_hz.is_finite() && self.observer.cutoff_hz >= 0.0) {
            out.push(Invalid::new(
                "observer.cutoff_hz",
                format!(
                    "is {}, must be >= 0 (0: no filter)",
                    self.observer.cutoff_hz
                ),
            ));
        }
        if self.output.decimation == 0 {
            out.push(Invalid::new("output.decimation", "must be at least 1"));
        }
        out
    }
}

/// Desired trajectory evaluation: `q_d`, `q_d'`, `q_d''` at `t` into the three slices.
pub(crate) struct Trajectory {
    offset: Vec<f64>,
    /// (joint index, amplitude, angular frequency, phase).
    sines: Vec<(usize, f64, f64, f64)>,
}

impl Trajectory {
    pub(crate) fn new(spec: &TrajectorySpec, joints: &[String]) -> Self {
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

    pub(crate) fn eval(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
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
