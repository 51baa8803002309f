//! Small configuration helpers shared by the controllers.

use serde::{Deserialize, Serialize};

use crate::error::ConfigError;

/// A per-joint quantity given either as one value for every joint (`k1 = 12.0`) or as one
/// value per joint (`k1 = [12.0, 12.0, 8.0]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum JointValues {
    /// The same value for every joint.
    Uniform(f64),
    /// One value per joint.
    PerJoint(Vec<f64>),
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
