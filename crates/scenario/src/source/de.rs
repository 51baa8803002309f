//! A serde deserializer over the positioned tree: a type or key error is returned with
//! the dotted path and the byte range of the value (or key) it concerns, straight from the
//! parse, so that every error names its line.

use std::fmt;
use std::ops::Range;

use serde::de::{self, DeserializeSeed, IntoDeserializer, MapAccess, SeqAccess, Visitor};

use super::tree::{Node, Value};

/// A deserialisation error, located when known.
#[derive(Debug)]
pub(crate) struct DeError {
    pub message: String,
    /// The dotted path and the byte range of the offending key or value.
    pub at: Option<(String, Range<usize>)>,
}

impl fmt::Display for DeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for DeError {}

impl de::Error for DeError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        DeError {
            message: msg.to_string(),
            at: None,
        }
    }
}

impl DeError {
    fn located(mut self, path: &str, span: &Range<usize>) -> Self {
        if self.at.is_none() {
            self.at = Some((path.to_string(), span.clone()));
        }
        self
    }
}

/// Deserializes `T` from a table of the tree (`path` is the table's dotted path, empty for
/// the root).
pub(crate) fn from_table<'de, T: serde::Deserialize<'de>>(
    table: &'de [(String, Node)],
    span: Range<usize>,
) -> Result<T, DeError> {
    let access = TableAccess {
        entries: table.iter(),
        pending: None,
        prefix: String::new(),
    };
    T::deserialize(TableDe { access, span })
}

struct TableDe<'de> {
    access: TableAccess<'de>,
    span: Range<usize>,
}

impl<'de> de::Deserializer<'de> for TableDe<'de> {
    type Error = DeError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        let span = self.span.clone();
        visitor
            .visit_map(self.access)
            .map_err(|e| e.located("", &span))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct enum
        identifier ignored_any
    }
}

/// One value of the tree with its dotted path.
struct NodeDe<'de> {
    node: &'de Node,
    path: String,
}

fn child(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

impl<'de> NodeDe<'de> {
    fn fail(&self, e: DeError) -> DeError {
        e.located(&self.path, &self.node.span)
    }
}

impl<'de> de::Deserializer<'de> for NodeDe<'de> {
    type Error = DeError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        let result = match &self.node.value {
            Value::String(s) => visitor.visit_str(s),
            Value::Integer(i) => visitor.visit_i64(*i),
            Value::Float(x) => visitor.visit_f64(*x),
            Value::Boolean(b) => visitor.visit_bool(*b),
            Value::Datetime(d) => visitor.visit_str(d),
            Value::Array(items) => visitor.visit_seq(ArrayAccess {
                items: items.iter().enumerate(),
                prefix: &self.path,
            }),
            Value::Table(t) => visitor.visit_map(TableAccess {
                entries: t.iter(),
                pending: None,
                prefix: self.path.clone(),
            }),
        };
        result.map_err(|e| self.fail(e))
    }

    // A present value is `Some`: a missing key is how a TOML file says `None`.
    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        let (path, span) = (self.path.clone(), self.node.span.clone());
        visitor
            .visit_some(self)
            .map_err(|e| e.located(&path, &span))
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, DeError> {
        let (path, span) = (self.path.clone(), self.node.span.clone());
        visitor
            .visit_newtype_struct(self)
            .map_err(|e| e.located(&path, &span))
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, DeError> {
        match &self.node.value {
            Value::String(s) => {
                let d: de::value::StrDeserializer<'_, DeError> = s.as_str().into_deserializer();
                visitor.visit_enum(d).map_err(|e| self.fail(e))
            }
            other => Err(self.fail(de::Error::custom(format!(
                "expected one of the strings {}, found {}",
                variants
                    .iter()
                    .map(|v| format!("\"{v}\""))
                    .collect::<Vec<_>>()
                    .join(", "),
                other.kind()
            )))),
        }
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        visitor.visit_unit()
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        unit unit_struct seq tuple tuple_struct map struct identifier
    }
}

struct TableAccess<'de> {
    entries: std::slice::Iter<'de, (String, Node)>,
    pending: Option<&'de (String, Node)>,
    prefix: String,
}

impl<'de> MapAccess<'de> for TableAccess<'de> {
    type Error = DeError;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, DeError> {
        let Some(entry) = self.entries.next() else {
            return Ok(None);
        };
        self.pending = Some(entry);
        let key: de::value::StrDeserializer<'_, DeError> = entry.0.as_str().into_deserializer();
        seed.deserialize(key)
            .map(Some)
            .map_err(|e| e.located(&child(&self.prefix, &entry.0), &entry.1.key_span))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, DeError> {
        let entry = self
            .pending
            .take()
            .ok_or_else(|| <DeError as de::Error>::custom("value without a key"))?;
        seed.deserialize(NodeDe {
            node: &entry.1,
            path: child(&self.prefix, &entry.0),
        })
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.entries.len())
    }
}

struct ArrayAccess<'de, 'p> {
    items: std::iter::Enumerate<std::slice::Iter<'de, Node>>,
    prefix: &'p str,
}

impl<'de> SeqAccess<'de> for ArrayAccess<'de, '_> {
    type Error = DeError;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, DeError> {
        let Some((i, node)) = self.items.next() else {
            return Ok(None);
        };
        seed.deserialize(NodeDe {
            node,
            path: child(self.prefix, &i.to_string()),
        })
        .map(Some)
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.items.len())
    }
}
