//! `settings.json`: the settings of every variant as the run resolved and applied them, so
//! that the report draws the plant's deadzone, the environment windows, the evaluation
//! window and the saturation bounds the run used, and tells a deadzone comparison, an
//! observer comparison or a hand contact from what the variants contain, without parsing
//! `scenario.toml` again (docs/outputs.md, "settings.json").
//!
//! ```json
//! {"format": "admittance-run-settings", "format_version": 1,
//!  "duration": 40.0, "evaluation_start": 20.0,
//!  "variants": [{"name": "nn_compensated", "controller": "neural",
//!                "deadzone_compensation": true, "observer": "none", "admittance": "none",
//!                "deadzones": [{"joint": "left_s0", "d_left": -0.49, "d_right": 0.49,
//!                               "slope_left": 1.0, "slope_right": 1.0}], ...}]}
//! ```
//!
//! Written beside `summary.json` (before it: the summary marks a complete folder); a run
//! folder written before this file existed has none, and readers fall back on
//! `scenario.toml`. An open window end (`t_end = inf`) is `null`: JSON has no infinity.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// The `format` of `settings.json`.
pub const FORMAT: &str = "admittance-run-settings";
/// The `format_version` this build writes.
pub const FORMAT_VERSION: u64 = 1;
/// The `format_version`s this build reads.
pub const SUPPORTED_VERSIONS: &[u64] = &[1];

/// The file name inside a run folder.
pub const FILE: &str = crate::files::SETTINGS;

/// [`VariantSettings::controller`] of the adaptive neural controller.
pub const CONTROLLER_NEURAL: &str = "neural";
/// [`VariantSettings::controller`] of the PD controller.
pub const CONTROLLER_PD: &str = "pd";
/// [`VariantSettings::observer`] without an estimate.
pub const OBSERVER_NONE: &str = "none";
/// [`VariantSettings::observer`] of the true external torque.
pub const OBSERVER_ORACLE: &str = "oracle";
/// [`VariantSettings::admittance`] without an admittance model (`q_r = q_d`).
pub const ADMITTANCE_NONE: &str = "none";
/// [`VariantSettings::admittance`] of a joint-space admittance model.
pub const ADMITTANCE_JOINT: &str = "joint";
/// [`VariantSettings::admittance`] of a task-space admittance at the hand.
pub const ADMITTANCE_TASK: &str = "task";
/// [`Environment::kind`] of a Cartesian wall (the other kinds act in joint space or push
/// the hand for their whole window).
pub const ENVIRONMENT_WALLS: &str = "walls";

/// The whole file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    /// [`FORMAT`].
    pub format: String,
    /// [`FORMAT_VERSION`].
    pub format_version: u64,
    /// Simulated time (s).
    pub duration: f64,
    /// Start of the evaluation window of the metrics (s).
    pub evaluation_start: f64,
    /// The variants in the order they ran.
    pub variants: Vec<VariantSettings>,
}

/// One variant's settings as the run applied them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct VariantSettings {
    /// The variant (`VARIANT.csv`).
    pub name: String,
    /// The controller kind (`neural`, `pd`, `computed_torque`).
    pub controller: String,
    /// The neural controller compensates the deadzone (its deadzone network); false for
    /// every other controller.
    pub deadzone_compensation: bool,
    /// The observer kind (`none`, `oracle`, `momentum`, `learned`, `hybrid`).
    pub observer: String,
    /// The admittance model: `none`, `joint` or `task`.
    pub admittance: String,
    /// Every joint whose actuator has a deadzone, as the plant applies it (after wildcards
    /// and later entries), in chain order; joints without one are left out.
    pub deadzones: Vec<Deadzone>,
    /// The bounds of `q_r` per joint when the joint-space admittance saturates it (joints
    /// with an infinite half-range are left out).
    pub saturation: Vec<Bound>,
    /// The environments in the order of the scenario.
    pub environments: Vec<Environment>,
    /// The walls (`kind = "walls"` of `environments`, with their plane).
    pub walls: Vec<Wall>,
    /// Dynamic-node events (experiment C), when the variant has them.
    pub dynamic_nodes: Option<DynamicNodes>,
    /// The run records free-motion data (`free_motion*.csv`).
    pub free_motion: bool,
}

/// One joint's deadzone: `D(tau) = m_r (tau - d_r)` above `d_r`, 0 inside, `m_l (tau - d_l)`
/// below `d_l`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Deadzone {
    /// Joint name.
    pub joint: String,
    /// Left edge (N m, <= 0).
    pub d_left: f64,
    /// Right edge (N m, >= 0).
    pub d_right: f64,
    /// Slope below the left edge.
    pub slope_left: f64,
    /// Slope above the right edge.
    pub slope_right: f64,
}

/// The saturation interval of one joint's compliant reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bound {
    /// Joint name.
    pub joint: String,
    /// `centre - half_range` (rad).
    pub lower: f64,
    /// `centre + half_range` (rad).
    pub upper: f64,
}

/// When an environment acts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Environment {
    /// `joint_springs`, `walls`, `joint_torque_profiles`, `tip_force_profiles`, or a
    /// co-simulation's own (`push`).
    pub kind: String,
    /// The joints it acts on directly (joint springs and torque profiles); empty for forces
    /// at a frame.
    pub joints: Vec<String>,
    /// Window start (s).
    pub t_start: f64,
    /// Window end (s); `None` when open.
    pub t_end: Option<f64>,
}

/// A wall: the plane through `point` with unit `normal` into free space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// A point of the plane, base frame (m).
    pub point: [f64; 3],
    /// Unit normal into free space.
    pub normal: [f64; 3],
    /// Window start (s).
    pub t_start: f64,
    /// Window end (s); `None` when open.
    pub t_end: Option<f64>,
}

/// The times of experiment C's events.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DynamicNodes {
    /// The discard (s).
    pub discard_time: f64,
    /// The start of growth (s).
    pub grow_time: f64,
    /// The window at the end of each phase the approximation error is measured over (s).
    pub approximation_window: f64,
}

/// A window end for [`Environment::t_end`] and [`Wall::t_end`]: `None` for an open one.
pub fn window_end(t_end: f64) -> Option<f64> {
    t_end.is_finite().then_some(t_end)
}

impl RunSettings {
    /// Settings of this format and version.
    pub fn new(duration: f64, evaluation_start: f64, variants: Vec<VariantSettings>) -> Self {
        Self {
            format: FORMAT.into(),
            format_version: FORMAT_VERSION,
            duration,
            evaluation_start,
            variants,
        }
    }

    /// The file's text (pretty JSON, one trailing newline).
    pub fn to_text(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Parses the file's text, checking the format and version; the error says what is
    /// wrong and what to do.
    pub fn parse(text: &str) -> Result<Self, String> {
        let value: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| format!("not valid JSON ({e}); rerun the scenario to rewrite it"))?;
        let format = value.get("format").and_then(serde_json::Value::as_str);
        if format != Some(FORMAT) {
            return Err(format!(
                "`format` is {}, expected \"{FORMAT}\"",
                format.map_or("missing".to_string(), |f| format!("\"{f}\""))
            ));
        }
        match value.get("format_version").and_then(serde_json::Value::as_u64) {
            Some(v) if SUPPORTED_VERSIONS.contains(&v) => {}
            Some(v) => {
                return Err(format!(
                    "format_version {v} is not supported by this build (it reads {SUPPORTED_VERSIONS:?}); rerun the scenario with this build"
                ))
            }
            None => return Err("`format_version` is missing or not a whole number".into()),
        }
        serde_json::from_value(value)
            .map_err(|e| format!("malformed ({e}); rerun the scenario to rewrite it"))
    }

    /// Reads `DIR/settings.json`: `Ok(None)` when the folder has none (written before it
    /// existed), an error naming the problem when it is unreadable or malformed.
    pub fn read(dir: &Path) -> Result<Option<Self>, String> {
        let path = dir.join(FILE);
        match admittance_files::read_regular_text(&path, admittance_files::TEXT_LIMIT) {
            Ok(text) => Self::parse(&text).map(Some),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(format!("cannot read ({e})")),
        }
    }

    /// The variant `name`.
    pub fn variant(&self, name: &str) -> Option<&VariantSettings> {
        self.variants.iter().find(|v| v.name == name)
    }
}

impl VariantSettings {
    /// The deadzone of `joint`, when it has one.
    pub fn deadzone(&self, joint: &str) -> Option<&Deadzone> {
        self.deadzones.iter().find(|d| d.joint == joint)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> RunSettings {
        RunSettings::new(
            40.0,
            20.0,
            vec![VariantSettings {
                name: "a".into(),
                controller: CONTROLLER_NEURAL.into(),
                deadzone_compensation: true,
                observer: OBSERVER_NONE.into(),
                admittance: ADMITTANCE_JOINT.into(),
                deadzones: vec![Deadzone {
                    joint: "j1".into(),
                    d_left: -0.49,
                    d_right: 0.49,
                    slope_left: 1.0,
                    slope_right: 1.0,
                }],
                saturation: vec![],
                environments: vec![Environment {
                    kind: "joint_springs".into(),
                    joints: vec!["j1".into()],
                    t_start: 12.0,
                    t_end: window_end(f64::INFINITY),
                }],
                walls: vec![],
                dynamic_nodes: None,
                free_motion: false,
            }],
        )
    }

    #[test]
    fn round_trips_with_open_windows_as_null() {
        let s = sample();
        let text = s.to_text();
        assert!(text.contains("\"t_end\": null"), "{text}");
        assert_eq!(RunSettings::parse(&text).unwrap(), s);
        assert_eq!(s.variants[0].deadzone("j1").unwrap().d_right, 0.49);
    }

    #[test]
    fn refuses_other_formats_and_versions() {
        let text = sample().to_text();
        let e = RunSettings::parse(&text.replace("\"format_version\": 1", "\"format_version\": 9"))
            .unwrap_err();
        assert!(e.contains("format_version 9 is not supported"), "{e}");
        let e = RunSettings::parse("{\"format\": \"x\"}").unwrap_err();
        assert!(e.contains("expected \"admittance-run-settings\""), "{e}");
        let e = RunSettings::parse("{").unwrap_err();
        assert!(e.contains("not valid JSON"), "{e}");
        let e = RunSettings::parse(&text.replace("\"duration\": 40.0,", "")).unwrap_err();
        assert!(e.contains("malformed") && e.contains("duration"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(RunSettings::read(dir.path()), Ok(None));
    }
}
