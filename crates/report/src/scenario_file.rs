//! The settings the figures and the report draw: the evaluation window, deadzone bands,
//! saturation bounds, environment windows, walls, and the kinds of controller, observer
//! and admittance of every variant. They come from the run folder's `settings.json`,
//! written by the run from what the plant and the loop applied
//! (`admittance_runfolder::settings`); a folder written before that file existed falls
//! back on `scenario.toml` (the scenario as run), read by the plant's rules, and the report
//! says so.

use std::borrow::Cow;

use admittance_runfolder::settings::{self as rs, RunSettings, VariantSettings};

use crate::folder::RunFolder;

/// A number of the scenario file (integers too).
pub fn number(value: &toml::Value) -> Option<f64> {
    value.as_float().or(value.as_integer().map(|i| i as f64))
}

/// A number, or the `index`-th of a list of numbers.
pub fn number_at(value: Option<&toml::Value>, index: usize) -> Option<f64> {
    let v = value?;
    match v.as_array() {
        Some(a) => a.get(index).and_then(number),
        None => number(v),
    }
}

/// When an environment acts.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentWindow {
    /// Start (s).
    pub from: f64,
    /// End (s); infinite when open.
    pub to: f64,
    /// The kind of environment (`joint_springs`, `walls`, ...).
    pub kind: String,
    /// The joints it acts on directly (empty for forces at a frame).
    pub joints: Vec<String>,
}

/// A wall: a plane through `point` with unit `normal` pointing into free space.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// A point of the plane, base frame (m).
    pub point: [f64; 3],
    /// Unit normal into free space.
    pub normal: [f64; 3],
    /// Window start (s).
    pub from: f64,
    /// Window end (s).
    pub to: f64,
}

impl Wall {
    /// Signed distance of `p` from the plane, positive in free space (m).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        (0..3)
            .map(|a| (p[a] - self.point[a]) * self.normal[a])
            .sum()
    }
}

/// The kinds of `[plant.environment]`, each a list of tables with `t_start`, `t_end`.
const ENVIRONMENTS: [&str; 4] = [
    "joint_springs",
    "walls",
    "joint_torque_profiles",
    "tip_force_profiles",
];

fn vec3(value: Option<&toml::Value>) -> Option<[f64; 3]> {
    let a = value?.as_array()?;
    if a.len() != 3 {
        return None;
    }
    Some([number(&a[0])?, number(&a[1])?, number(&a[2])?])
}

fn window(table: &toml::Table) -> (f64, Option<f64>) {
    let get = |k: &str, default: f64| table.get(k).and_then(number).unwrap_or(default);
    (
        get("t_start", 0.0),
        rs::window_end(get("t_end", f64::INFINITY)),
    )
}

fn open_end(t_end: Option<f64>) -> f64 {
    t_end.unwrap_or(f64::INFINITY)
}

impl RunFolder {
    /// A value of the scenario file by dotted key (`"arm.urdf"`).
    pub fn scenario_value(&self, key: &str) -> Option<&toml::Value> {
        let mut parts = key.split('.');
        let mut value = self.scenario_toml.as_ref()?.get(parts.next()?)?;
        for p in parts {
            value = value.as_table()?.get(p)?;
        }
        Some(value)
    }

    /// A value of the scenario file as variant `variant` sees it: the variant's override
    /// (`[variants.NAME]` with the same dotted key) when there is one, else the base value.
    pub fn variant_value(&self, variant: &str, key: &str) -> Option<&toml::Value> {
        self.scenario_value(&format!("variants.{variant}.{key}"))
            .or_else(|| self.scenario_value(key))
    }

    /// The scenario's one-line description (`description` in scenario.toml).
    pub fn description(&self) -> Option<&str> {
        self.scenario_value("description")
            .and_then(toml::Value::as_str)
    }

    /// The run's settings: `settings.json`, else read from `scenario.toml`
    /// ([`RunFolder::settings_from_scenario`]).
    pub fn run_settings(&self) -> Cow<'_, RunSettings> {
        match &self.settings {
            Some(s) => Cow::Borrowed(s),
            None => Cow::Owned(self.settings_from_scenario()),
        }
    }

    /// The settings of variant `name` (defaults when `settings.json` says nothing of it).
    pub fn variant_settings(&self, name: &str) -> VariantSettings {
        match &self.settings {
            Some(s) => s.variant(name).cloned().unwrap_or_else(|| VariantSettings {
                name: name.to_string(),
                ..VariantSettings::default()
            }),
            None => self.variant_from_scenario(name),
        }
    }

    /// The settings of a folder without `settings.json`, from `scenario.toml` by the
    /// plant's and the loop's rules: a deadzone entry for `"*"` applies to every joint and a
    /// later entry replaces an earlier one; the neural controller compensates the deadzone
    /// unless `deadzone_compensation = false`; no observer unless `[observer] kind`.
    pub fn settings_from_scenario(&self) -> RunSettings {
        let top = |key: &str| self.scenario_value(key).and_then(number);
        let variants = self
            .variants
            .iter()
            .map(|v| self.variant_from_scenario(&v.name))
            .collect();
        RunSettings::new(
            top("duration").unwrap_or(0.0),
            top("evaluation_start")
                .filter(|v| v.is_finite())
                .unwrap_or(0.0),
            variants,
        )
    }

    fn variant_from_scenario(&self, name: &str) -> VariantSettings {
        let text = |key: &str| {
            self.variant_value(name, key)
                .and_then(toml::Value::as_str)
                .map(String::from)
        };
        let flag = |key: &str| self.variant_value(name, key).and_then(toml::Value::as_bool);
        let controller = text("controller.kind").unwrap_or_default();
        let neural = controller == rs::CONTROLLER_NEURAL;
        let mut deadzones: Vec<rs::Deadzone> = Vec::new();
        let list = self
            .variant_value(name, "plant.deadzones")
            .and_then(toml::Value::as_array);
        for d in list.into_iter().flatten().filter_map(toml::Value::as_table) {
            let get = |k: &str, default: f64| d.get(k).and_then(number).unwrap_or(default);
            let joint = d.get("joint").and_then(toml::Value::as_str).unwrap_or("");
            let targets: Vec<&String> = self
                .joints
                .iter()
                .filter(|j| joint == "*" || *j == joint)
                .collect();
            for j in targets {
                deadzones.retain(|x| &x.joint != j);
                deadzones.push(rs::Deadzone {
                    joint: j.clone(),
                    d_left: get("d_left", 0.0),
                    d_right: get("d_right", 0.0),
                    slope_left: get("slope_left", 1.0),
                    slope_right: get("slope_right", 1.0),
                });
            }
        }
        deadzones.retain(|d| d.d_left != 0.0 || d.d_right != 0.0);
        let index = |j: &str| self.joints.iter().position(|x| x == j);
        deadzones.sort_by_key(|d| index(&d.joint));
        let task = self.variant_value(name, "task_admittance").is_some();
        let joint_admittance = self.variant_value(name, "admittance").is_some()
            && flag("admittance.enabled") != Some(false);
        let admittance = if task {
            rs::ADMITTANCE_TASK
        } else if joint_admittance {
            rs::ADMITTANCE_JOINT
        } else {
            rs::ADMITTANCE_NONE
        };
        let saturation = if joint_admittance
            && self.variant_value(name, "admittance.saturation").is_some()
        {
            self.joints
                .iter()
                .enumerate()
                .filter_map(|(i, j)| {
                    let c = number_at(self.variant_value(name, "admittance.saturation.centre"), i)
                        .unwrap_or(0.0);
                    let h = number_at(
                        self.variant_value(name, "admittance.saturation.half_range"),
                        i,
                    )?;
                    (h.is_finite() && c.is_finite()).then(|| rs::Bound {
                        joint: j.clone(),
                        lower: c - h,
                        upper: c + h,
                    })
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut environments = Vec::new();
        let mut walls = Vec::new();
        for kind in ENVIRONMENTS {
            let key = format!("plant.environment.{kind}");
            let Some(list) = self
                .variant_value(name, &key)
                .and_then(toml::Value::as_array)
            else {
                continue;
            };
            for t in list.iter().filter_map(toml::Value::as_table) {
                let (t_start, t_end) = window(t);
                let joints = match (t.get("joints"), t.get("joint")) {
                    (Some(js), _) => js
                        .as_array()
                        .map(|a| {
                            a.iter()
                                .filter_map(|j| j.as_str().map(String::from))
                                .collect()
                        })
                        .unwrap_or_default(),
                    (None, Some(j)) => j.as_str().map(String::from).into_iter().collect(),
                    _ => Vec::new(),
                };
                environments.push(rs::Environment {
                    kind: kind.to_string(),
                    joints,
                    t_start,
                    t_end,
                });
                if kind == rs::ENVIRONMENT_WALLS {
                    let point = vec3(t.get("point")).unwrap_or([0.0; 3]);
                    let n = vec3(t.get("normal")).unwrap_or([0.0, 0.0, 1.0]);
                    let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    if norm.is_finite() && norm > 0.0 {
                        walls.push(rs::Wall {
                            point,
                            normal: n.map(|c| c / norm),
                            t_start,
                            t_end,
                        });
                    }
                }
            }
        }
        let dynamic_nodes = self
            .variant_value(name, "dynamic_nodes")
            .and_then(toml::Value::as_table)
            .map(|d| {
                let get = |k: &str, default: f64| d.get(k).and_then(number).unwrap_or(default);
                rs::DynamicNodes {
                    discard_time: get("discard_time", f64::NAN),
                    grow_time: get("grow_time", f64::NAN),
                    approximation_window: get("approximation_window", 12.0),
                }
            });
        VariantSettings {
            name: name.to_string(),
            deadzone_compensation: neural
                && flag("controller.neural.deadzone_compensation").unwrap_or(true),
            controller,
            observer: text("observer.kind").unwrap_or_else(|| rs::OBSERVER_NONE.into()),
            admittance: admittance.into(),
            deadzones,
            saturation,
            environments,
            walls,
            dynamic_nodes,
            free_motion: flag("record.free_motion_csv").unwrap_or(false),
        }
    }

    /// Start of the evaluation window (s).
    pub fn evaluation_start(&self) -> f64 {
        let s = self.run_settings().evaluation_start;
        if s.is_finite() {
            s
        } else {
            0.0
        }
    }

    /// The deadzone `[d_left, d_right]` of `joint` as the plant of `variant` applied it.
    pub fn deadzone(&self, variant: &str, joint: &str) -> Option<(f64, f64)> {
        self.run_settings()
            .variant(variant)?
            .deadzone(joint)
            .map(|d| (d.d_left, d.d_right))
    }

    /// Whether any variant has a deadzone.
    pub fn has_deadzone(&self) -> bool {
        self.run_settings()
            .variants
            .iter()
            .any(|v| !v.deadzones.is_empty())
    }

    /// The saturation bounds of `joint`'s compliant reference (the first variant that
    /// saturates it), when configured and finite.
    pub fn saturation_bounds(&self, joint: &str) -> Option<(f64, f64)> {
        self.run_settings()
            .variants
            .iter()
            .flat_map(|v| &v.saturation)
            .find(|b| b.joint == joint)
            .map(|b| (b.lower, b.upper))
    }

    /// Whether the scenario saturates the compliant reference (a finite bound on a joint).
    pub fn has_saturation(&self) -> bool {
        self.run_settings()
            .variants
            .iter()
            .any(|v| !v.saturation.is_empty())
    }

    /// The windows in which the environments of `variant` act, in the scenario's order.
    pub fn environment_windows(&self, variant: &str) -> Vec<EnvironmentWindow> {
        self.variant_settings(variant)
            .environments
            .iter()
            .map(|e| EnvironmentWindow {
                from: e.t_start,
                to: open_end(e.t_end),
                kind: e.kind.clone(),
                joints: e.joints.clone(),
            })
            .collect()
    }

    /// The walls of `variant`.
    pub fn walls(&self, variant: &str) -> Vec<Wall> {
        self.variant_settings(variant)
            .walls
            .iter()
            .map(|w| Wall {
                point: w.point,
                normal: w.normal,
                from: w.t_start,
                to: open_end(w.t_end),
            })
            .collect()
    }

    /// The approximation window of experiment C (s), 12 when absent.
    pub fn approximation_window(&self) -> f64 {
        self.run_settings()
            .variants
            .iter()
            .find_map(|v| v.dynamic_nodes.as_ref())
            .map(|d| d.approximation_window)
            .filter(|w| w.is_finite() && *w > 0.0)
            .unwrap_or(12.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::folder::Variant;
    use crate::table::Table;

    fn folder(toml: &str, variants: &[&str]) -> RunFolder {
        RunFolder {
            dir: ".".into(),
            scenario: "x".into(),
            plant: None,
            joints: vec!["a".into(), "b".into()],
            variants: variants
                .iter()
                .map(|n| Variant {
                    name: n.to_string(),
                    metrics: Default::default(),
                    table: Table::from_columns(vec!["t".into()], vec![vec![0.0]]),
                })
                .collect(),
            warnings: Vec::new(),
            health: None,
            scenario_toml: Some(toml.parse().unwrap()),
            settings: None,
            free_motion: Vec::new(),
            node_weights: Vec::new(),
            observer_validation: Vec::new(),
        }
    }

    #[test]
    fn reads_windows_walls_and_bounds_from_an_old_scenario_file() {
        let f = folder(
            "evaluation_start = 2\n\
             [[plant.environment.joint_springs]]\njoints = [\"a\"]\nt_start = 12.0\nt_end = 30.0\n\
             [[plant.environment.walls]]\npoint = [0.5, 0, 0]\nnormal = [-2, 0, 0]\nt_start = 1\n\
             [admittance]\ndamping = 3\nstiffness = 5\n\
             [admittance.saturation]\ncentre = [0.1, 0.0]\nhalf_range = [1.0, inf]\n\
             [variants.free.plant.environment]\njoint_springs = []\n",
            &["base", "free"],
        );
        assert_eq!(f.evaluation_start(), 2.0);
        let w = f.environment_windows("base");
        assert_eq!(w.len(), 2);
        assert_eq!(
            (w[0].from, w[0].to, w[0].kind.as_str(), w[0].joints.clone()),
            (12.0, 30.0, "joint_springs", vec!["a".to_string()])
        );
        assert_eq!((w[1].from, w[1].to), (1.0, f64::INFINITY));
        assert_eq!(
            f.environment_windows("free").len(),
            1,
            "the variant's override"
        );
        let walls = f.walls("base");
        assert_eq!(walls[0].normal, [-1.0, 0.0, 0.0]);
        assert!((walls[0].distance([0.4, 3.0, 1.0]) - 0.1).abs() < 1e-12);
        let (lo, hi) = f.saturation_bounds("a").unwrap();
        assert!((lo + 0.9).abs() < 1e-12 && (hi - 1.1).abs() < 1e-12);
        assert_eq!(f.saturation_bounds("b"), None, "an infinite half-range");
        assert!(f.has_saturation() && !f.has_deadzone());
        assert_eq!(f.variant_settings("base").admittance, "joint");
    }

    #[test]
    fn an_old_scenario_file_is_read_by_the_plants_deadzone_rules() {
        // A wildcard, then a later entry for `b`: the plant applies the last one.
        let f = folder(
            "[controller]\nkind = \"neural\"\n\
             [[plant.deadzones]]\njoint = \"*\"\nd_left = -1.0\nd_right = 1.0\n\
             [[plant.deadzones]]\njoint = \"b\"\nd_left = -2.0\nd_right = 3.0\n\
             [variants.off]\ncontroller.neural.deadzone_compensation = false\n",
            &["on", "off"],
        );
        assert_eq!(f.deadzone("on", "a"), Some((-1.0, 1.0)));
        assert_eq!(f.deadzone("on", "b"), Some((-2.0, 3.0)));
        let on = f.variant_settings("on");
        let off = f.variant_settings("off");
        assert!(on.deadzone_compensation && !off.deadzone_compensation);
        assert_eq!(on.deadzones, off.deadzones);
    }

    #[test]
    fn settings_json_wins_over_the_scenario_file() {
        let mut f = folder(
            "evaluation_start = 2\n[[plant.deadzones]]\njoint = \"a\"\nd_left = -9\nd_right = 9\n",
            &["v"],
        );
        let mut v = VariantSettings {
            name: "v".into(),
            ..VariantSettings::default()
        };
        v.deadzones.push(rs::Deadzone {
            joint: "b".into(),
            d_left: -0.49,
            d_right: 0.49,
            slope_left: 1.0,
            slope_right: 1.0,
        });
        f.settings = Some(RunSettings::new(10.0, 4.0, vec![v]));
        assert_eq!(f.evaluation_start(), 4.0);
        assert_eq!(f.deadzone("v", "a"), None);
        assert_eq!(f.deadzone("v", "b"), Some((-0.49, 0.49)));
    }
}
