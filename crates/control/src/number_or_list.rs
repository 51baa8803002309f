//! Deserialisation of "one number, or a list of numbers" values ([`crate::JointValues`],
//! [`crate::AxisValues`]) with messages in the words of a scenario file: what is accepted,
//! what was found, and which element is wrong (issue 14: serde's untagged enums say only
//! `data did not match any variant`).

use std::fmt;

use serde::de::{self, Deserializer};

/// How a value is described in error messages.
pub(crate) struct Shape {
    /// What is accepted, e.g. "a number (one value for every joint) or a list of one number
    /// per joint".
    pub expected: &'static str,
    /// What one element is called ("joint", "axis").
    pub element: &'static str,
    /// Names of the elements by index (`["x", "y", "z"]`); empty: the index is used.
    pub element_names: &'static [&'static str],
    /// A hint appended to an element's error.
    pub hint: &'static str,
    /// The required list length, if fixed.
    pub length: Option<usize>,
}

impl Shape {
    fn label(&self, i: usize) -> String {
        match self.element_names.get(i) {
            Some(name) => format!("{} {name}", self.element),
            None => format!("{} {i}", self.element),
        }
    }
}

/// The two accepted forms.
pub(crate) enum NumberOrList {
    Number(f64),
    List(Vec<f64>),
}

/// Reads a number or a list of numbers, or fails with a message built from `shape`.
pub(crate) fn number_or_list<'de, D: Deserializer<'de>>(
    d: D,
    shape: &'static Shape,
) -> Result<NumberOrList, D::Error> {
    d.deserialize_any(ValueVisitor(shape))
}

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

/// The visitor methods shared by the value and element visitors: numbers are accepted
/// (`$number` maps an `f64` to the result), everything else goes to `self.wrong(...)`.
macro_rules! reject_non_numbers {
    () => {
        fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            d.deserialize_any(self)
        }
        fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            d.deserialize_any(self)
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
            self.visit_f64(v as f64)
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
            self.visit_f64(v as f64)
        }
        fn visit_i128<E: de::Error>(self, v: i128) -> Result<Self::Value, E> {
            self.visit_f64(v as f64)
        }
        fn visit_u128<E: de::Error>(self, v: u128) -> Result<Self::Value, E> {
            self.visit_f64(v as f64)
        }
        fn visit_bool<E: de::Error>(self, v: bool) -> Result<Self::Value, E> {
            Err(self.wrong(de::Unexpected::Bool(v)))
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
            Err(self.wrong(de::Unexpected::Str(v)))
        }
        fn visit_char<E: de::Error>(self, v: char) -> Result<Self::Value, E> {
            Err(self.wrong(de::Unexpected::Char(v)))
        }
        fn visit_bytes<E: de::Error>(self, v: &[u8]) -> Result<Self::Value, E> {
            Err(self.wrong(de::Unexpected::Bytes(v)))
        }
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            Err(self.wrong(de::Unexpected::Unit))
        }
        fn visit_none<E: de::Error>(self) -> Result<Self::Value, E> {
            Err(self.wrong(de::Unexpected::Option))
        }
        fn visit_map<A: de::MapAccess<'de>>(self, _map: A) -> Result<Self::Value, A::Error> {
            Err(self.wrong(de::Unexpected::Map))
        }
        fn visit_enum<A: de::EnumAccess<'de>>(self, _data: A) -> Result<Self::Value, A::Error> {
            Err(self.wrong(de::Unexpected::Enum))
        }
    };
}

struct ValueVisitor(&'static Shape);

impl ValueVisitor {
    fn wrong<E: de::Error>(&self, unexpected: de::Unexpected<'_>) -> E {
        E::custom(format_args!(
            "expected {}, found {}",
            self.0.expected,
            found(unexpected)
        ))
    }
}

impl<'de> de::Visitor<'de> for ValueVisitor {
    type Value = NumberOrList;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.0.expected)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<NumberOrList, E> {
        Ok(NumberOrList::Number(v))
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<NumberOrList, A::Error> {
        let shape = self.0;
        let mut values = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        while let Some(v) = seq.next_element_seed(ElementVisitor(shape, values.len()))? {
            values.push(v);
        }
        match shape.length {
            Some(n) if values.len() != n => Err(de::Error::custom(format_args!(
                "expected {}, found a list of {} numbers",
                shape.expected,
                values.len()
            ))),
            _ => Ok(NumberOrList::List(values)),
        }
    }

    reject_non_numbers!();
}

/// One element of a list: a number, or an error naming the element.
struct ElementVisitor(&'static Shape, usize);

impl ElementVisitor {
    fn wrong<E: de::Error>(&self, unexpected: de::Unexpected<'_>) -> E {
        E::custom(format_args!(
            "{}: expected a number, found {} ({})",
            self.0.label(self.1),
            found(unexpected),
            self.0.hint
        ))
    }
}

impl<'de> de::DeserializeSeed<'de> for ElementVisitor {
    type Value = f64;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<f64, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> de::Visitor<'de> for ElementVisitor {
    type Value = f64;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "a number for {}", self.0.label(self.1))
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
        Ok(v)
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, _seq: A) -> Result<f64, A::Error> {
        Err(self.wrong(de::Unexpected::Seq))
    }

    reject_non_numbers!();
}
