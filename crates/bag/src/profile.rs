//! Profiles: which topic and field of a bag give the joint angles `q`, velocities `qdot`,
//! torques `tau` and an optional label (a vendor's external torque or wrench estimate).
//! They are data: TOML files, the built-in ones under `crates/bag/profiles/` embedded in
//! the binary, or a user's own file of the same form.

use std::path::Path;

use serde::Deserialize;

use crate::error::BagError;

/// The built-in profiles: name and TOML text.
const BUILTIN: &[(&str, &str)] = &[
    ("franka", include_str!("../profiles/franka.toml")),
    ("ur", include_str!("../profiles/ur.toml")),
    ("lbr", include_str!("../profiles/lbr.toml")),
];

/// `sensor_msgs/msg/JointState`.
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
/// `geometry_msgs/msg/WrenchStamped`.
pub const WRENCH_STAMPED: &str = "geometry_msgs/msg/WrenchStamped";
/// `std_msgs/msg/Float64MultiArray`.
pub const FLOAT64_MULTI_ARRAY: &str = "std_msgs/msg/Float64MultiArray";

/// Where one signal comes from.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignalSource {
    /// The topic.
    pub topic: String,
    /// The message type, as rosbag2 names it (`sensor_msgs/msg/JointState`).
    #[serde(rename = "type")]
    pub type_name: String,
    /// The field: `position`, `velocity`, `effort` of a JointState; `data` of a
    /// Float64MultiArray; `wrench` of a WrenchStamped (label only); a top-level numeric
    /// array field of another type (read from the embedded definition).
    pub field: String,
    /// For a type without a header: the two integer fields (seconds, nanoseconds) of its
    /// own stamp. Absent: the header stamp (JointState, WrenchStamped) or the log time.
    #[serde(default)]
    pub stamp: Option<[String; 2]>,
    /// Unit of the values, for `tau` only: `Nm` (default) or `A` (motor current, which
    /// needs `torque_constant`).
    #[serde(default)]
    pub unit: Option<String>,
    /// Per joint (Nm/A, gear ratio included): tau = torque_constant * current. Required
    /// when `unit = "A"`.
    #[serde(default)]
    pub torque_constant: Option<Vec<f64>>,
}

/// A profile: the mapping from a bag's topics to the free-motion columns.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// Its name.
    pub name: String,
    /// One line on the robot and driver it is for.
    pub description: String,
    /// Joint names in the output's order. Required for sources without names (arrays);
    /// for JointState sources, absent means the names and order of the first `q` message.
    #[serde(default)]
    pub joints: Option<Vec<String>>,
    /// Joint angles (rad).
    pub q: SignalSource,
    /// Joint velocities (rad/s); absent: the backward difference of `q`.
    #[serde(default)]
    pub qdot: Option<SignalSource>,
    /// Joint torques (Nm).
    pub tau: SignalSource,
    /// A vendor's estimate of the external torque (per joint) or wrench (6 values).
    #[serde(default)]
    pub label: Option<SignalSource>,
}

impl Profile {
    /// The names of the built-in profiles.
    pub fn builtin_names() -> Vec<&'static str> {
        BUILTIN.iter().map(|(n, _)| *n).collect()
    }

    /// A built-in profile by name.
    pub fn builtin(name: &str) -> Option<Result<Self, BagError>> {
        BUILTIN
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(n, text)| Self::parse(text, &format!("{n} (built in)")))
    }

    /// A built-in name, or else a TOML file.
    pub fn resolve(arg: &str) -> Result<Self, BagError> {
        if let Some(p) = Self::builtin(arg) {
            return p;
        }
        let path = Path::new(arg);
        if !path.exists() {
            return Err(BagError::Profile {
                profile: arg.to_string(),
                message: format!(
                    "neither a built-in profile ({}) nor an existing TOML file",
                    Self::builtin_names().join(", ")
                ),
            });
        }
        match std::fs::metadata(path) {
            Ok(m) if !m.is_file() => {
                return Err(BagError::Profile {
                    profile: arg.to_string(),
                    message: format!(
                        "is {}, not a TOML file",
                        crate::source::special_kind(&m.file_type())
                    ),
                })
            }
            _ => {}
        }
        let text = std::fs::read_to_string(path).map_err(|e| BagError::Profile {
            profile: arg.to_string(),
            message: format!("cannot read it: {e}"),
        })?;
        Self::parse(&text, arg)
    }

    /// Parses and checks a profile's TOML text; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<Self, BagError> {
        let err = |message: String| BagError::Profile {
            profile: source.to_string(),
            message,
        };
        let p: Profile = toml::from_str(text).map_err(|e| err(e.to_string().trim().to_string()))?;
        p.check().map_err(err)?;
        Ok(p)
    }

    /// The signals with their roles: `q`, `qdot`, `tau`, `label`.
    pub fn signals(&self) -> Vec<(&'static str, &SignalSource)> {
        let mut v = vec![("q", &self.q)];
        if let Some(s) = &self.qdot {
            v.push(("qdot", s));
        }
        v.push(("tau", &self.tau));
        if let Some(s) = &self.label {
            v.push(("label", s));
        }
        v
    }

    fn check(&self) -> Result<(), String> {
        if let Some(j) = &self.joints {
            if j.is_empty() {
                return Err("`joints` is empty".into());
            }
            let mut sorted = j.clone();
            sorted.sort();
            if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
                return Err(format!("joint `{}` is listed twice in `joints`", w[0]));
            }
        }
        for (role, s) in self.signals() {
            check_source(role, s, self.joints.is_some())?;
        }
        self.check_torque_unit()
    }

    fn check_torque_unit(&self) -> Result<(), String> {
        match self.tau.unit.as_deref() {
            None | Some("Nm") => Ok(()),
            Some("A") => match &self.tau.torque_constant {
                None => Err(format!(
                    "[tau] unit = \"A\": `{}` field `{}` is motor current, not torque; set `torque_constant = [k1, ..., kn]` (Nm/A per joint, gear ratio included, from the robot's documentation) in [tau] of a copy of this profile and pass that file to --profile",
                    self.tau.topic, self.tau.field
                )),
                Some(k) => {
                    if let Some(bad) = k.iter().find(|k| !k.is_finite() || **k == 0.0) {
                        return Err(format!("[tau] torque_constant {bad} is not a finite non-zero number"));
                    }
                    match &self.joints {
                        Some(j) if j.len() != k.len() => Err(format!(
                            "[tau] torque_constant has {} values for {} joints",
                            k.len(),
                            j.len()
                        )),
                        _ => Ok(()),
                    }
                }
            },
            Some(other) => Err(format!("[tau] unit `{other}`: use \"Nm\" or \"A\"")),
        }
    }
}

fn check_source(role: &str, s: &SignalSource, have_joints: bool) -> Result<(), String> {
    let bad_field = |allowed: &str| {
        Err(format!(
            "[{role}] field `{}` of {}: use {allowed}",
            s.field, s.type_name
        ))
    };
    match s.type_name.as_str() {
        JOINT_STATE => {
            if !["position", "velocity", "effort"].contains(&s.field.as_str()) {
                return bad_field("position, velocity or effort");
            }
        }
        FLOAT64_MULTI_ARRAY if s.field != "data" => return bad_field("data"),
        WRENCH_STAMPED if role != "label" => {
            return Err(format!("[{role}] a WrenchStamped can only be the label"))
        }
        WRENCH_STAMPED if s.field != "wrench" => return bad_field("wrench"),
        t if !t.contains("/msg/") => {
            return Err(format!(
            "[{role}] type `{t}`: give the full rosbag2 name, such as sensor_msgs/msg/JointState"
        ))
        }
        _ => {
            if !have_joints && s.type_name != WRENCH_STAMPED {
                return Err(format!(
                    "[{role}] {} carries no joint names: list them in `joints`",
                    s.type_name
                ));
            }
        }
    }
    if role != "tau" && (s.unit.is_some() || s.torque_constant.is_some()) {
        return Err(format!(
            "[{role}] `unit` and `torque_constant` belong in [tau]"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_parse_except_ur_which_asks_for_torque_constants() {
        for name in ["franka", "lbr"] {
            let p = Profile::builtin(name).unwrap().unwrap();
            assert_eq!(p.name, name);
        }
        let e = Profile::builtin("ur").unwrap().unwrap_err().to_string();
        assert!(
            e.contains("torque_constant") && e.contains("/joint_states"),
            "{e}"
        );
    }

    #[test]
    fn ur_with_torque_constants_parses() {
        let text = include_str!("../profiles/ur.toml").replace(
            "unit = \"A\"",
            "unit = \"A\"\ntorque_constant = [1.0, 1.0, 1.0, 0.5, 0.5, 0.5]",
        );
        let p = Profile::parse(&text, "ur-copy").unwrap();
        assert_eq!(p.tau.torque_constant.as_ref().unwrap().len(), 6);
    }

    #[test]
    fn bad_profiles_are_named() {
        let base = include_str!("../profiles/franka.toml");
        let typo = base.replace("field = \"position\"", "fiedl = \"position\"");
        let e = Profile::parse(&typo, "mine.toml").unwrap_err().to_string();
        assert!(
            e.starts_with("profile mine.toml:") && e.contains("fiedl"),
            "{e}"
        );
        let field = base.replace("field = \"position\"", "field = \"positions\"");
        let e = Profile::parse(&field, "mine.toml").unwrap_err().to_string();
        assert!(e.contains("[q] field `positions`"), "{e}");
        let e = Profile::resolve("/no/such/profile.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("franka, ur, lbr"), "{e}");
    }
}
