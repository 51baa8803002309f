//! The values of `scenario.toml` (the scenario as run) that the figures and the report
//! draw: the evaluation window, deadzone bands, saturation bounds, environment windows,
//! walls. A variant sees its own `[variants.NAME]` override of a key when it has one.

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

/// When an environment acts, from `[[plant.environment.*]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentWindow {
    /// Start (s).
    pub from: f64,
    /// End (s); infinite when open.
    pub to: f64,
    /// The kind of environment (`joint_springs`, `walls`, ...).
    pub kind: String,
}

/// A wall of `[[plant.environment.walls]]`: a plane through `point` with unit `normal`
/// pointing into free space (sim's `WallConfig`).
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

fn window(table: &toml::Table) -> (f64, f64) {
    let get = |k: &str, default: f64| table.get(k).and_then(number).unwrap_or(default);
    (get("t_start", 0.0), get("t_end", f64::INFINITY))
}

impl RunFolder {
    /// A value of the scenario file by dotted key (`"dynamic_nodes.approximation_window"`).
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

    /// Start of the evaluation window (s): `evaluation_start`, 0 when absent.
    pub fn evaluation_start(&self) -> f64 {
        self.scenario_value("evaluation_start")
            .and_then(number)
            .filter(|v| v.is_finite())
            .unwrap_or(0.0)
    }

    /// The deadzone `[d_left, d_right]` of `joint` as `variant` sees it.
    pub fn deadzone(&self, variant: &str, joint: &str) -> Option<(f64, f64)> {
        let list = self.variant_value(variant, "plant.deadzones")?.as_array()?;
        let d = list
            .iter()
            .filter_map(toml::Value::as_table)
            .find(|d| d.get("joint").and_then(toml::Value::as_str) == Some(joint))?;
        Some((
            d.get("d_left").and_then(number)?,
            d.get("d_right").and_then(number)?,
        ))
    }

    /// Whether any variant has a deadzone.
    pub fn has_deadzone(&self) -> bool {
        self.variants.iter().any(|v| {
            self.variant_value(&v.name, "plant.deadzones")
                .and_then(toml::Value::as_array)
                .is_some_and(|a| !a.is_empty())
        })
    }

    /// The saturation bounds `(c - C, c + C)` of joint `index` (`[admittance.saturation]`,
    /// `centre` and `half_range` a number or one per joint), when configured.
    pub fn saturation_bounds(&self, index: usize) -> Option<(f64, f64)> {
        let centre =
            number_at(self.scenario_value("admittance.saturation.centre"), index).unwrap_or(0.0);
        let half = number_at(
            self.scenario_value("admittance.saturation.half_range"),
            index,
        )?;
        Some((centre - half, centre + half))
    }

    /// Whether the scenario saturates the compliant reference.
    pub fn has_saturation(&self) -> bool {
        self.scenario_value("admittance.saturation").is_some()
    }

    /// The windows in which the environments of `variant` act, in file order.
    pub fn environment_windows(&self, variant: &str) -> Vec<EnvironmentWindow> {
        let mut out = Vec::new();
        for kind in ENVIRONMENTS {
            let key = format!("plant.environment.{kind}");
            let Some(list) = self
                .variant_value(variant, &key)
                .and_then(toml::Value::as_array)
            else {
                continue;
            };
            for t in list.iter().filter_map(toml::Value::as_table) {
                let (from, to) = window(t);
                out.push(EnvironmentWindow {
                    from,
                    to,
                    kind: kind.to_string(),
                });
            }
        }
        out
    }

    /// The walls of `variant` (`[[plant.environment.walls]]`), with sim's defaults for the
    /// keys left out.
    pub fn walls(&self, variant: &str) -> Vec<Wall> {
        let Some(list) = self
            .variant_value(variant, "plant.environment.walls")
            .and_then(toml::Value::as_array)
        else {
            return Vec::new();
        };
        list.iter()
            .filter_map(toml::Value::as_table)
            .filter_map(|t| {
                let point = vec3(t.get("point")).unwrap_or([0.0; 3]);
                let n = vec3(t.get("normal")).unwrap_or([0.0, 0.0, 1.0]);
                let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                if !(norm.is_finite() && norm > 0.0) {
                    return None;
                }
                let (from, to) = window(t);
                Some(Wall {
                    point,
                    normal: n.map(|c| c / norm),
                    from,
                    to,
                })
            })
            .collect()
    }

    /// `dynamic_nodes.approximation_window` (s), 12 when absent.
    pub fn approximation_window(&self) -> f64 {
        number_at(self.scenario_value("dynamic_nodes.approximation_window"), 0)
            .filter(|w| w.is_finite() && *w > 0.0)
            .unwrap_or(12.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(toml: &str) -> RunFolder {
        RunFolder {
            dir: ".".into(),
            scenario: "x".into(),
            plant: None,
            joints: vec!["a".into(), "b".into()],
            variants: Vec::new(),
            warnings: Vec::new(),
            health: None,
            scenario_toml: Some(toml.parse().unwrap()),
            free_motion: Vec::new(),
            node_weights: Vec::new(),
            observer_validation: Vec::new(),
        }
    }

    #[test]
    fn reads_windows_walls_and_bounds() {
        let f = folder(
            "evaluation_start = 2\n\
             [[plant.environment.joint_springs]]\njoints = [\"a\"]\nt_start = 12.0\nt_end = 30.0\n\
             [[plant.environment.walls]]\npoint = [0.5, 0, 0]\nnormal = [-2, 0, 0]\nt_start = 1\n\
             [admittance.saturation]\ncentre = [0.1, 0.0]\nhalf_range = [1.0, inf]\n\
             [variants.free.plant.environment]\njoint_springs = []\n",
        );
        assert_eq!(f.evaluation_start(), 2.0);
        let w = f.environment_windows("base");
        assert_eq!(w.len(), 2);
        assert_eq!(
            (w[0].from, w[0].to, w[0].kind.as_str()),
            (12.0, 30.0, "joint_springs")
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
        let (lo, hi) = f.saturation_bounds(0).unwrap();
        assert!((lo + 0.9).abs() < 1e-12 && (hi - 1.1).abs() < 1e-12);
        assert_eq!(
            f.saturation_bounds(1),
            Some((f64::NEG_INFINITY, f64::INFINITY))
        );
        assert!(f.has_saturation() && !f.has_deadzone());
    }
}
