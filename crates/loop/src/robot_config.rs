//! A robot's loop file (`loop.toml` of a deployment folder, docs/your_robot.md), in the
//! loop's own vocabulary: nothing simulated, no trajectory (the caller sends the desired
//! motion, or the loop holds the first measured pose).
//!
//! ```toml
//! format = "admittance-loop"
//! version = 1
//! control_rate_hz = 1000.0       # Hz, one step per period
//! [arm]                          # the URDF, relative to this file
//! urdf = "arm.urdf"
//! base = "base"
//! tip = "left_hand"
//! [signals]
//! filter_cutoff_hz = 20.0        # Hz, low-pass before differentiation; 0: none
//! [signals.gates]                # plausibility gates (issue 34)
//! angle_margin = 0.2             # rad beyond the URDF limits
//! jump_factor = 3.0              # x velocity limit
//! torque_factor = 3.0            # x effort limit
//! [controller]                   # as a LoopConfig's
//! [admittance]                   # or [task_admittance]
//! [observer]                     # kind, identification = FILE, network = FILE, ...
//! [contact]
//! floor = "contact_floor.json"   # a ContactFloor file (admittance calibrate-contact)
//! deadband = false               # the admittance ignores an estimate inside the floor
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use admittance_control::{ConfigError, TaskSpaceAdmittanceConfig};
use admittance_dynamics::UrdfOptions;
use serde::{Deserialize, Serialize};

use crate::config::{
    ControllerConfig, JointAdmittanceConfig, LoopConfig, ObserverConfig, DEFAULT_CONTROL_RATE_HZ,
};
use crate::error::LoopError;
use crate::gates::GateConfig;

/// `format` of a robot's loop file.
pub const LOOP_FILE_FORMAT: &str = "admittance-loop";
/// `version` of a robot's loop file this library reads.
pub const LOOP_FILE_VERSION: u32 = 1;
/// The cut-off of the signal chain's low-pass before differentiation (Hz), the one default
/// of every front end (a robot's loop, the simulator's sensors, Python).
pub const DEFAULT_SIGNAL_CUTOFF_HZ: f64 = 20.0;

/// What a robot's loop is built from (`loop.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotConfig {
    /// Must be [`LOOP_FILE_FORMAT`].
    pub format: String,
    /// Must be [`LOOP_FILE_VERSION`].
    pub version: u32,
    /// Control rate (Hz). Default 1000.
    #[serde(default = "default_rate")]
    pub control_rate_hz: f64,
    /// The arm.
    pub arm: ArmFile,
    /// The signal chain. Default: [`SignalsConfig::default`].
    #[serde(default)]
    pub signals: SignalsConfig,
    /// The controller (`[controller]`).
    pub controller: ControllerConfig,
    /// The joint-space admittance model; absent: `q_r = q_d`.
    #[serde(default)]
    pub admittance: Option<JointAdmittanceConfig>,
    /// The task-space admittance model at the hand.
    #[serde(default)]
    pub task_admittance: Option<TaskSpaceAdmittanceConfig>,
    /// The external-torque estimate. Default: none.
    #[serde(default)]
    pub observer: ObserverConfig,
    /// Contact detection on the estimate (issue 31). Default: absent (no flags).
    #[serde(default)]
    pub contact: Option<ContactSection>,
}

fn default_rate() -> f64 {
    DEFAULT_CONTROL_RATE_HZ
}

/// The arm's URDF and how its chain is cut (`[arm]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmFile {
    /// The URDF file, relative to the loop file.
    pub urdf: PathBuf,
    /// The base link (default: the root).
    #[serde(default)]
    pub base: Option<String>,
    /// The tip link (default: the loader's rule).
    #[serde(default)]
    pub tip: Option<String>,
    /// Inertia warnings are errors. Default false.
    #[serde(default)]
    pub strict: bool,
    /// Positions of joints locked off the chain. Default: none.
    #[serde(default)]
    pub lock: BTreeMap<String, f64>,
    /// Joints whose subtree is left out. Default: none.
    #[serde(default)]
    pub drop: Vec<String>,
}

impl ArmFile {
    /// The URDF loader's options.
    pub fn urdf_options(&self) -> UrdfOptions {
        UrdfOptions {
            base: self.base.clone(),
            tip: self.tip.clone(),
            strict: self.strict,
            lock: self.lock.iter().map(|(j, v)| (j.clone(), *v)).collect(),
            drop: self.drop.clone(),
        }
    }
}

/// The signal chain (`[signals]`): low-pass and differentiation of the encoder angles, the
/// torque through the same filter, and the plausibility gates before both.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignalsConfig {
    /// Cut-off (Hz) of the 2nd-order low-pass before differentiation; 0: none. Below half
    /// the control rate. Default [`DEFAULT_SIGNAL_CUTOFF_HZ`].
    #[serde(default = "default_cutoff")]
    pub filter_cutoff_hz: f64,
    /// The plausibility gates. Default: [`GateConfig::default`].
    #[serde(default)]
    pub gates: GateConfig,
}

fn default_cutoff() -> f64 {
    DEFAULT_SIGNAL_CUTOFF_HZ
}

impl Default for SignalsConfig {
    fn default() -> Self {
        Self {
            filter_cutoff_hz: DEFAULT_SIGNAL_CUTOFF_HZ,
            gates: GateConfig::default(),
        }
    }
}

impl SignalsConfig {
    /// Every problem at its key (`signals.*`) for the control rate `rate_hz`.
    pub fn problems(&self, rate_hz: f64) -> Vec<LoopError> {
        let mut out = self.gates.problems("signals.gates");
        let f = self.filter_cutoff_hz;
        if !(f.is_finite() && f >= 0.0 && f < 0.5 * rate_hz) {
            out.push(
                LoopError::invalid(
                    "signals.filter_cutoff_hz",
                    format!(
                        "is {f}, must be in [0, {}) Hz (half the control rate)",
                        0.5 * rate_hz
                    ),
                )
                .hint("0 disables the filter; 20 Hz is the default"),
            );
        }
        out
    }
}

/// Contact detection (`[contact]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSection {
    /// The contact-floor file (`admittance_control::ContactFloor`), relative to the loop
    /// file.
    pub floor: PathBuf,
    /// The admittance takes the floor's contact thresholds as a deadband on the estimate
    /// (issue 31, item 3: an untouched arm stays on its reference; a push moves it by its
    /// excess over the floor). Default false.
    #[serde(default)]
    pub deadband: bool,
}

impl RobotConfig {
    /// Parses a loop file's text; `file` names it in errors.
    pub fn from_toml(text: &str, file: &Path) -> Result<Self, LoopError> {
        Self::from_toml_with(text, file, &[])
    }

    /// As [`RobotConfig::from_toml`], with `KEY=VALUE` overrides applied in order (the
    /// value is TOML: `3.0`, `[1, 2]`, `"text"`; a bare word is taken as a string).
    pub fn from_toml_with(text: &str, file: &Path, overrides: &[&str]) -> Result<Self, LoopError> {
        let mut table: toml::Table =
            toml::from_str(text).map_err(|e| LoopError::file(file, e.to_string().trim()))?;
        for o in overrides {
            set_key(&mut table, o)?;
        }
        let config: RobotConfig = table
            .try_into()
            .map_err(|e: toml::de::Error| unreadable(e).located(file))?;
        if config.format != LOOP_FILE_FORMAT || config.version != LOOP_FILE_VERSION {
            return Err(LoopError::invalid(
                "format",
                format!(
                    "format {:?} version {}, this library reads {LOOP_FILE_FORMAT:?} version {LOOP_FILE_VERSION}",
                    config.format, config.version
                ),
            )
            .hint("write it again with `admittance deploy`")
            .located(file));
        }
        Ok(config)
    }

    /// The text of this loop file.
    pub fn to_toml(&self) -> Result<String, LoopError> {
        toml::to_string(self).map_err(|e| LoopError::invalid("loop.toml", e.to_string()))
    }

    /// The closed loop's settings, the file paths taken from `folder`.
    pub fn loop_config(&self, folder: &Path) -> LoopConfig {
        let mut observer = self.observer.clone();
        for p in [&mut observer.identification, &mut observer.network]
            .into_iter()
            .flatten()
        {
            if p.is_relative() {
                *p = folder.join(&*p);
            }
        }
        LoopConfig {
            control_rate_hz: self.control_rate_hz,
            controller: self.controller.clone(),
            admittance: self.admittance.clone(),
            task_admittance: self.task_admittance.clone(),
            observer,
        }
    }

    /// Every problem of the settings at its key (empty: valid).
    pub fn problems(&self) -> Vec<LoopError> {
        let mut out = self.signals.problems(self.control_rate_hz);
        out.extend(self.loop_config(Path::new(".")).problems());
        out
    }
}

/// A deserialisation error of the loop file's table at its key: toml names the table path
/// only in its text (`in `a.b``), and an unknown field only in its message; the key is
/// the field's, as a scenario file's or a Python dict's would be.
fn unreadable(e: toml::de::Error) -> LoopError {
    let text = e.to_string();
    let table = text
        .lines()
        .filter_map(|l| l.strip_prefix("in `")?.strip_suffix('`'))
        .next_back()
        .unwrap_or("");
    let unknown = e
        .message()
        .strip_prefix("unknown field `")
        .and_then(|rest| rest.split('`').next());
    let key = match unknown {
        Some(field) if table.is_empty() => field.to_string(),
        Some(field) => format!("{table}.{field}"),
        None => table.to_string(),
    };
    ConfigError::unreadable(key, e.message()).into()
}

/// Sets `KEY=VALUE` (a dotted key) in `table`.
fn set_key(table: &mut toml::Table, assignment: &str) -> Result<(), LoopError> {
    let Some((key, value)) = assignment.split_once('=') else {
        return Err(LoopError::invalid(
            assignment.to_string(),
            "an override is KEY=VALUE (`signals.filter_cutoff_hz=10`)",
        ));
    };
    let key = key.trim();
    let value = value.trim();
    let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.to_string()));
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().filter(|s| !s.is_empty());
    let mut node = table;
    for part in parts {
        let entry = node
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        node = entry.as_table_mut().ok_or_else(|| {
            LoopError::invalid(key.to_string(), format!("`{part}` is not a table"))
        })?;
    }
    let last = last.ok_or_else(|| LoopError::invalid(key.to_string(), "empty key"))?;
    node.insert(last.to_string(), parsed);
    Ok(())
}
