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
//! # The loop (admittance_loop::LoopConfig, at plant.control_rate_hz):
//! [controller]               # kind = "neural" | "pd" | "computed_torque", with [controller.neural] etc.
//! [admittance]               # optional: admittance model and reference saturation
//! [task_admittance]          # optional, instead: the hand's admittance (linear, angular, axes, IK)
//! [observer]                 # kind = "none" | "oracle" | "momentum" | "learned" | "hybrid", nominal_inertia_scale, cutoff_hz, input_filter_hz, warmup
//! [observer.training]        # learned / hybrid (the scenario's): free-motion data, validation data, nodes, friction inputs, cache; identify (momentum and hybrid on the identified arm)
//! [record]                   # optional: free_motion_csv = true (free-motion data, docs/outputs.md)
//! [contact]                  # optional: contact floor (calibration = free motion, or floor = FILE), deadband
//! [gates]                    # optional: plausibility gates on the readings (enabled, angle_margin, jump_factor, torque_factor)
//! [dynamic_nodes]            # optional: discard / grow events (experiment C)
//! [health]                   # optional: thresholds of the run's health rules (max_hand_error = 0.04 m, ...)
//! [variants.NAME]            # overrides of any of the above, per variant
//! ```

mod arm_fit;
pub use arm_fit::mid_range;
mod contact;
pub use contact::ContactSpec;
mod validate;
pub(crate) use validate::loop_problem;

use std::path::{Path, PathBuf};

use admittance_control::{GrowthParams, TaskSpaceAdmittanceConfig};
use admittance_loop::{ControllerConfig, JointAdmittanceConfig, LoopConfig, ObserverConfig};
use serde::{Deserialize, Serialize};

use admittance_sim::PlantConfig;

/// The chain to load.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmSpec {
    /// URDF file, relative to the scenario file (or absolute).
    pub urdf: PathBuf,
    /// Base link (default: the root link).
    #[serde(default)]
    pub base: Option<String>,
    /// Tip link (default: the arm's hand, the loader's rule: `admittance model` shows it).
    #[serde(default)]
    pub tip: Option<String>,
    /// Refuse physically impossible inertias on the chain (default: load them with a
    /// warning, which the run prints and `summary.json` lists).
    #[serde(default)]
    pub strict: bool,
    /// Positions (rad or m) at which joints of branches off the chain are held (a gripper's
    /// opening); the others are held at 0: `[arm.lock] finger_joint1 = 0.04`.
    #[serde(default)]
    pub lock: std::collections::BTreeMap<String, f64>,
    /// Joints whose branch is left out of the model, mass and all, instead of locked.
    #[serde(default)]
    pub drop: Vec<String>,
}

impl ArmSpec {
    /// The loader's options for this arm.
    pub fn urdf_options(&self) -> admittance_dynamics::UrdfOptions {
        admittance_dynamics::UrdfOptions {
            base: self.base.clone(),
            tip: self.tip.clone(),
            strict: self.strict,
            lock: self.lock.iter().map(|(j, v)| (j.clone(), *v)).collect(),
            drop: self.drop.clone(),
        }
    }
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

/// The desired joint trajectory `q_d(t)`: a pose (`offset`, or `waypoints` to move between
/// poses) plus sines; or, alone, an `excitation` designed for identification.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// Constant part, one value per joint. Default: the middle of each joint's limits (0
    /// for a joint without limits), a pose that fits whatever arm the scenario names.
    #[serde(default)]
    pub offset: Option<Vec<f64>>,
    /// Poses to move between, instead of `offset`: `[[t, q_1, ..., q_n], ...]`, times
    /// strictly increasing. Before the first the pose is held, between two the joints move
    /// with a quintic blend (zero velocity and acceleration at each waypoint), after the
    /// last it is held.
    #[serde(default)]
    pub waypoints: Vec<Vec<f64>>,
    /// Sinusoidal components.
    #[serde(default)]
    pub sines: Vec<SineSpec>,
    /// An excitation for identification (docs/method.md section 8; `admittance excite`): a
    /// finite Fourier series per joint, periodic, from rest, inside the arm's position,
    /// velocity and acceleration limits, optimised for the condition number of the base
    /// regressor; designed when the scenario is assembled. Its table takes
    /// `ExcitationSettings` (`period`, `harmonics`, `acceleration_limit`,
    /// `position_margin`, `seed`, `iterations`, and `duration`/`rate_hz` of the samples the
    /// design is scored on). Exclusive with `offset`, `waypoints` and `sines`. Default:
    /// absent.
    #[serde(default)]
    pub excitation: Option<admittance_dynamics::ExcitationSettings>,
}

/// Where the training of a learned observer comes from (`[observer.training]`).
///
/// The training data are free-motion samples (docs/outputs.md, "Free-motion data"): `data`
/// names either a scenario file (`.toml`) that records them, simulated at the start of the
/// run (e.g. `free_motion.toml`), or a CSV file a user recorded on a real arm. The
/// validation data, a different excitation, come the same way (`validation`): the ridge
/// parameter lambda is chosen on them and `validation_nrmse` is measured on them. Paths are
/// relative to the scenario file. A trained network is cached in `cache_dir` under a key
/// of the data's identity (file contents; for a data scenario also its URDF and the program
/// version) and every training setting; a matching entry is loaded instead of training.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TrainingSpec {
    /// Training data: a data scenario (`.toml`, with `[record] free_motion_csv = true`) or
    /// a free-motion CSV file.
    pub data: PathBuf,
    /// Validation data (a different excitation): a data scenario or a CSV file.
    pub validation: PathBuf,
    /// Enhancement (Gaussian) nodes; the paper uses 1000.
    #[serde(default = "default_nodes")]
    pub nodes: usize,
    /// Friction-shaped inputs `tanh(qdot / v)` beside the Gaussian nodes (docs/method.md
    /// section 7).
    #[serde(default)]
    pub friction_features: bool,
    /// The scales `v` (rad/s) of the friction-shaped inputs.
    #[serde(default = "default_friction_scales")]
    pub friction_scales: Vec<f64>,
    /// Seed of the centre placement.
    #[serde(default = "default_training_seed")]
    pub seed: u64,
    /// Node widths: `eta_j = width_scale * (mean distance from centre j to its
    /// `width_neighbours` nearest centres)`, in standardised units (the broad module's kNN
    /// rule). Defaults 2 and 8.
    #[serde(default = "default_width_scale")]
    pub width_scale: f64,
    /// See `width_scale`.
    #[serde(default = "default_width_neighbours")]
    pub width_neighbours: usize,
    /// Folder of cached networks, relative to the scenario file; the environment variable
    /// `ADMITTANCE_CACHE_DIR` overrides it. Default `../.admittance-cache`.
    #[serde(default = "default_cache_dir")]
    pub cache_dir: PathBuf,
    /// Whether to use and fill the cache.
    #[serde(default = "default_true")]
    pub cache: bool,
    /// Identify the arm on the training data (docs/method.md section 8; settings chosen on
    /// the validation data) and run `momentum` and `hybrid` on the identification: the
    /// momentum observer's nominal model is the identified one with its joint terms, and
    /// the hybrid's network learns what the identification misses. The file is written to
    /// the cache folder. Default false: the nominal model is the URDF with
    /// `observer.nominal_inertia_scale`.
    #[serde(default)]
    pub identify: bool,
}

fn default_nodes() -> usize {
    admittance_learning::broad::DEFAULT_NODES
}
fn default_friction_scales() -> Vec<f64> {
    admittance_learning::broad::DEFAULT_FRICTION_SCALES.to_vec()
}
fn default_training_seed() -> u64 {
    admittance_learning::broad::BroadConfig::default().seed
}
fn default_width_scale() -> f64 {
    2.0
}
fn default_width_neighbours() -> usize {
    8
}
fn default_cache_dir() -> PathBuf {
    PathBuf::from("../.admittance-cache")
}
fn default_true() -> bool {
    true
}

/// Dynamic-node events of experiment C (docs/method.md section 4).
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
    /// (docs/method.md section 5; columns in docs/outputs.md), to `free_motion.csv`.
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
    /// The desired trajectory (default: hold the middle of the joint limits).
    #[serde(default)]
    pub trajectory: TrajectorySpec,
    /// The plant (true arm, friction, deadzone, environment, sensors, rates).
    #[serde(default)]
    pub plant: PlantConfig,
    /// The controller ([`LoopConfig::controller`]).
    pub controller: ControllerConfig,
    /// The joint-space admittance model ([`LoopConfig::admittance`]; absent: `q_r = q_d`).
    #[serde(default)]
    pub admittance: Option<JointAdmittanceConfig>,
    /// The task-space admittance model at the hand ([`LoopConfig::task_admittance`],
    /// exclusive with `[admittance]`).
    #[serde(default)]
    pub task_admittance: Option<TaskSpaceAdmittanceConfig>,
    /// The external-torque estimate ([`LoopConfig::observer`]), with the training of the
    /// learned observers' network.
    #[serde(default = "ObserverConfig::default")]
    pub observer: ObserverConfig<TrainingSpec>,
    /// Contact and collision detection on the estimate (issue 31).
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// The robot program's plausibility gates on the sensors' readings (issue 34;
    /// `admittance_loop::GateConfig`, a robot loop file's `[signals.gates]`). Default: on,
    /// with a robot's defaults.
    #[serde(default)]
    pub gates: admittance_loop::GateConfig,
    /// Dynamic-node events (experiment C).
    #[serde(default)]
    pub dynamic_nodes: Option<DynamicNodesSpec>,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Extra recordings.
    #[serde(default)]
    pub record: RecordSpec,
    /// The thresholds the finished run is judged by (`[health]`, docs/outputs.md "Health":
    /// hand error, effort saturation, estimate beyond the effort limit, stale data, joint
    /// limits).
    #[serde(default)]
    pub health: admittance_runfolder::health::HealthSettings,
    /// Variant tables (read by [`super::ScenarioSource`], ignored here).
    #[serde(default, skip_serializing)]
    pub variants: Option<toml::Table>,
}

impl Scenario {
    /// The loop's settings: the scenario's `[controller]`, `[admittance]`,
    /// `[task_admittance]` and `[observer]` tables, at the plant's control rate.
    ///
    /// These tables are [`LoopConfig`]'s own types, listed here one by one rather than
    /// through `#[serde(flatten)]`: flattening buffers the values and would lose the file
    /// position of every error inside them.
    pub fn loop_config(&self) -> LoopConfig<TrainingSpec> {
        LoopConfig {
            control_rate_hz: self.plant.control_rate_hz,
            controller: self.controller.clone(),
            admittance: self.admittance.clone(),
            task_admittance: self.task_admittance.clone(),
            observer: self.observer.clone(),
        }
    }

    /// [`Scenario::loop_config`] with the files it names (`observer.identification`)
    /// resolved against the scenario file's folder.
    pub fn loop_config_for(&self, scenario_file: &Path) -> LoopConfig<TrainingSpec> {
        let mut config = self.loop_config();
        let observer = &mut config.observer;
        for p in [&mut observer.identification, &mut observer.network]
            .into_iter()
            .flatten()
        {
            if p.is_relative() {
                *p = scenario_file.parent().unwrap_or(Path::new(".")).join(&*p);
            }
        }
        config
    }

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
}
