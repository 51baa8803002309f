//! Small configuration helpers shared by the controllers.

use serde::{Deserialize, Deserializer, Serialize};

use crate::error::ConfigError;
use crate::number_or_list::{number_or_list, NumberOrList, Shape};

/// A per-joint quantity given either as one value for every joint (`k1 = 12.0`) or as one
/// value per joint (`k1 = [12.0, 12.0, 8.0]`).
///
/// Deserialising anything else fails with a message that says what is accepted, e.g.
/// `expected a number (one value for every joint) or a list of one number per joint, found
/// the string "12"`, or `joint 2: expected a number, found a list`.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum JointValues {
    /// The same value for every joint.
    Uniform(f64),
    /// One value per joint.
    PerJoint(Vec<f64>),
}

const JOINT_VALUES: Shape = Shape {
    expected: "a number (one value for every joint) or a list of one number per joint",
    element: "joint",
    element_names: &[],
    hint: "a per-joint list holds one number per joint",
    length: None,
};

impl<'de> Deserialize<'de> for JointValues {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(match number_or_list(d, &JOINT_VALUES)? {
            NumberOrList::Number(v) => JointValues::Uniform(v),
            NumberOrList::List(v) => JointValues::PerJoint(v),
        })
    }
}

impl From<f64> for JointValues {
    fn from(v: f64) -> Self {
        JointValues::Uniform(v)
    }
}

impl From<Vec<f64>> for JointValues {
    fn from(v: Vec<f64>) -> Self {
        JointValues::PerJoint(v)
    }
}

/// A quantity of the three translational or the three rotational task axes (`x`, `y`, `z`
/// of the base frame), given as one number for all three (`stiffness = 300.0`) or as
/// `[x, y, z]` (`stiffness = [300.0, 300.0, 0.0]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum AxisValues {
    /// The same value on the three axes.
    Uniform(f64),
    /// One value per axis, `[x, y, z]`.
    PerAxis([f64; 3]),
}

const AXIS_VALUES: Shape = Shape {
    expected: "a number (one value for x, y and z) or a list of three numbers [x, y, z]",
    element: "axis",
    element_names: &["x", "y", "z"],
    hint: "the list is [x, y, z]",
    length: Some(3),
};

impl<'de> Deserialize<'de> for AxisValues {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(match number_or_list(d, &AXIS_VALUES)? {
            NumberOrList::Number(v) => AxisValues::Uniform(v),
            NumberOrList::List(v) => AxisValues::PerAxis([v[0], v[1], v[2]]),
        })
    }
}

impl From<f64> for AxisValues {
    fn from(v: f64) -> Self {
        AxisValues::Uniform(v)
    }
}

impl From<[f64; 3]> for AxisValues {
    fn from(v: [f64; 3]) -> Self {
        AxisValues::PerAxis(v)
    }
}

impl AxisValues {
    /// The three values, each checked against `bound`; errors name `key` (and the axis).
    pub(crate) fn resolve(&self, key: &str, bound: Bound) -> Result<[f64; 3], ConfigError> {
        match self {
            AxisValues::Uniform(v) => {
                let v = bound.check(key, *v)?;
                Ok([v; 3])
            }
            AxisValues::PerAxis(vs) => {
                let mut out = [0.0; 3];
                for (i, (o, v)) in out.iter_mut().zip(vs).enumerate() {
                    *o = bound.check(&format!("{key}[{i}]"), *v)?;
                }
                Ok(out)
            }
        }
    }
}

/// What a value must satisfy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bound {
    /// Finite and `> 0`.
    Positive,
    /// Finite and `>= 0`.
    NonNegative,
    /// Finite.
    Finite,
}

impl Bound {
    pub(crate) fn check(self, key: &str, v: f64) -> Result<f64, ConfigError> {
        let ok = match self {
            Bound::Positive => v.is_finite() && v > 0.0,
            Bound::NonNegative => v.is_finite() && v >= 0.0,
            Bound::Finite => v.is_finite(),
        };
        if ok {
            Ok(v)
        } else {
            let need = match self {
                Bound::Positive => "a finite number > 0",
                Bound::NonNegative => "a finite number >= 0",
                Bound::Finite => "a finite number",
            };
            Err(ConfigError::new(key, format!("is {v}, must be {need}")))
        }
    }
}

impl JointValues {
    /// The values for `n` joints, each checked against `bound`; errors name `key` (and the
    /// joint index for a per-joint list).
    pub(crate) fn resolve(
        &self,
        key: &str,
        n: usize,
        bound: Bound,
    ) -> Result<Vec<f64>, ConfigError> {
        match self {
            JointValues::Uniform(v) => Ok(vec![bound.check(key, *v)?; n]),
            JointValues::PerJoint(vs) => {
                if vs.len() != n {
                    return Err(ConfigError::new(
                        key,
                        format!(
                            "has {} values but the arm has {n} joints (give one value per joint, or a single number for all)",
                            vs.len()
                        ),
                    ));
                }
                vs.iter()
                    .enumerate()
                    .map(|(i, v)| bound.check(&format!("{key}[{i}]"), *v))
                    .collect()
            }
        }
    }
}

/// Effort limits of `model`, optionally overridden; each must be finite and positive.
pub(crate) fn effort_limits(
    model: &admittance_dynamics::Model,
    over: Option<&JointValues>,
    key: &str,
) -> Result<Vec<f64>, ConfigError> {
    let n = model.nq();
    match over {
        Some(v) => v.resolve(key, n, Bound::Positive),
        None => model
            .effort_limits()
            .zip(model.joint_names())
            .map(|(e, name)| {
                if e.is_finite() && e > 0.0 {
                    Ok(e)
                } else {
                    Err(ConfigError::new(
                        key,
                        format!(
                            "joint '{name}' has no finite positive effort limit in the model ({e}); give `{key}` explicitly"
                        ),
                    ))
                }
            })
            .collect(),
    }
}

/// `x` clamped to `[-limit, limit]`; NaN becomes 0.
#[inline(always)]
pub(crate) fn clamp_effort(x: f64, limit: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-limit, limit)
    }
}
