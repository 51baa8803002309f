//! Small configuration helpers shared by the controllers.

use std::fmt;

use serde::{de, Deserialize, Deserializer, Serialize};

use crate::error::ConfigError;

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

/// What a scenario may give for a per-joint value, as the error messages say it.
const JOINT_VALUES_EXPECTED: &str =
    "a number (one value for every joint) or a list of one number per joint";

/// `found ...` for an error message, in the words of a scenario file rather than serde's.
fn found(unexpected: de::Unexpected<'_>) -> String {
    use de::Unexpected as U;
    match unexpected {
        U::Bool(b) => format!("the boolean {b}"),
        U::Str(s) => format!("the string {s:?}"),
        U::Char(c) => format!("the character {c:?}"),
        U::Bytes(_) => "bytes".to_string(),
        U::Unit | U::Option => "no value".to_string(),
        U::Seq => "a list".to_string(),
        U::Map => "a table".to_string(),
        other => format!("{other}"),
    }
}

struct JointValuesVisitor;

impl<'de> de::Visitor<'de> for JointValuesVisitor {
    type Value = JointValues;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(JOINT_VALUES_EXPECTED)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<JointValues, E> {
        Ok(JointValues::Uniform(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<JointValues, E> {
        Ok(JointValues::Uniform(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<JointValues, E> {
        Ok(JointValues::Uniform(v as f64))
    }
    fn visit_i128<E: de::Error>(self, v: i128) -> Result<JointValues, E> {
        Ok(JointValues::Uniform(v as f64))
    }
    fn visit_u128<E: de::Error>(self, v: u128) -> Result<JointValues, E> {
        Ok(JointValues::Uniform(v as f64))
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<JointValues, A::Error> {
        let mut values = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        while let Some(v) = seq.next_element_seed(JointNumber(values.len()))? {
            values.push(v);
        }
        Ok(JointValues::PerJoint(values))
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<JointValues, D::Error> {
        d.deserialize_any(self)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<JointValues, D::Error> {
        d.deserialize_any(self)
    }

    fn visit_bool<E: de::Error>(self, v: bool) -> Result<JointValues, E> {
        Err(wrong(de::Unexpected::Bool(v)))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<JointValues, E> {
        Err(wrong(de::Unexpected::Str(v)))
    }
    fn visit_char<E: de::Error>(self, v: char) -> Result<JointValues, E> {
        Err(wrong(de::Unexpected::Char(v)))
    }
    fn visit_bytes<E: de::Error>(self, v: &[u8]) -> Result<JointValues, E> {
        Err(wrong(de::Unexpected::Bytes(v)))
    }
    fn visit_unit<E: de::Error>(self) -> Result<JointValues, E> {
        Err(wrong(de::Unexpected::Unit))
    }
    fn visit_none<E: de::Error>(self) -> Result<JointValues, E> {
        Err(wrong(de::Unexpected::Option))
    }
    fn visit_map<A: de::MapAccess<'de>>(self, _map: A) -> Result<JointValues, A::Error> {
        Err(wrong(de::Unexpected::Map))
    }
    fn visit_enum<A: de::EnumAccess<'de>>(self, _data: A) -> Result<JointValues, A::Error> {
        Err(wrong(de::Unexpected::Enum))
    }
}

fn wrong<E: de::Error>(unexpected: de::Unexpected<'_>) -> E {
    E::custom(format_args!(
        "expected {JOINT_VALUES_EXPECTED}, found {}",
        found(unexpected)
    ))
}

/// One element of a per-joint list: a number, or an error naming the joint.
struct JointNumber(usize);

impl<'de> de::DeserializeSeed<'de> for JointNumber {
    type Value = f64;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<f64, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> de::Visitor<'de> for JointNumber {
    type Value = f64;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "a number for joint {}", self.0)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
        Ok(v)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_i128<E: de::Error>(self, v: i128) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_u128<E: de::Error>(self, v: u128) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<f64, D::Error> {
        d.deserialize_any(self)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<f64, D::Error> {
        d.deserialize_any(self)
    }

    fn visit_bool<E: de::Error>(self, v: bool) -> Result<f64, E> {
        Err(self.wrong(de::Unexpected::Bool(v)))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
        Err(self.wrong(de::Unexpected::Str(v)))
    }
    fn visit_char<E: de::Error>(self, v: char) -> Result<f64, E> {
        Err(self.wrong(de::Unexpected::Char(v)))
    }
    fn visit_bytes<E: de::Error>(self, v: &[u8]) -> Result<f64, E> {
        Err(self.wrong(de::Unexpected::Bytes(v)))
    }
    fn visit_unit<E: de::Error>(self) -> Result<f64, E> {
        Err(self.wrong(de::Unexpected::Unit))
    }
    fn visit_none<E: de::Error>(self) -> Result<f64, E> {
        Err(self.wrong(de::Unexpected::Option))
    }
    fn visit_seq<A: de::SeqAccess<'de>>(self, _seq: A) -> Result<f64, A::Error> {
        Err(self.wrong(de::Unexpected::Seq))
    }
    fn visit_map<A: de::MapAccess<'de>>(self, _map: A) -> Result<f64, A::Error> {
        Err(self.wrong(de::Unexpected::Map))
    }
    fn visit_enum<A: de::EnumAccess<'de>>(self, _data: A) -> Result<f64, A::Error> {
        Err(self.wrong(de::Unexpected::Enum))
    }
}

impl JointNumber {
    fn wrong<E: de::Error>(&self, unexpected: de::Unexpected<'_>) -> E {
        E::custom(format_args!(
            "joint {}: expected a number, found {} (a per-joint list holds one number per joint)",
            self.0,
            found(unexpected)
        ))
    }
}

impl<'de> Deserialize<'de> for JointValues {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(JointValuesVisitor)
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
