//! Configuration dictionaries: the keys of the scenario files' tables
//! (`[controller.neural]`, `[controller.pd]`, `[observer.momentum]`, `[admittance]`, a
//! whole loop's `[controller]`/`[admittance]`/`[observer]`, ...), deserialised straight from
//! the Python objects by a serde `Deserializer` over them ([`PyDe`]) into the same serde
//! structs a scenario file fills, so that the same validation applies; every error names
//! the dotted key it concerns (`observer.momentum.gain[2]`).
//!
//! `None` leaves a key at its default (a dict entry whose value is `None` is skipped);
//! numpy arrays are sequences, numpy scalars numbers.

use std::fmt;

use admittance_control::{ConfigError, JointValues};
use numpy::prelude::*;
use numpy::PyUntypedArray;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde::de::{
    self, DeserializeOwned, DeserializeSeed, IntoDeserializer, MapAccess, SeqAccess, Visitor,
};

use crate::convert::{shape_text, value_error};

/// A deserialisation error: the project's one keyed shape of a bad setting
/// ([`ConfigError`], issue 32) inside serde's error type, so that a Python dict's bad key
/// reads as the same key would in a scenario file or a loop file.
#[derive(Debug)]
pub struct DeError {
    /// The dotted key (`controller.pd.kp[3]`; empty: the dict itself) and what is wrong.
    pub setting: ConfigError,
    /// A Python object of a type no configuration value has (a `TypeError`).
    pub type_error: bool,
}

impl fmt::Display for DeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.setting, f)
    }
}

impl std::error::Error for DeError {}

impl de::Error for DeError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        DeError {
            setting: ConfigError::new("", msg.to_string()),
            type_error: false,
        }
    }
}

impl DeError {
    /// The error located at `key`, unless a deeper key is already known.
    fn at(mut self, key: &str) -> Self {
        if self.setting.key.is_empty() {
            self.setting.key = key.to_string();
        }
        self
    }

    /// A value of no configuration type at `key`.
    fn type_error(key: &str, message: impl Into<String>) -> Self {
        DeError {
            setting: ConfigError::new(key, message),
            type_error: true,
        }
    }

    fn from_py(e: PyErr, key: &str) -> Self {
        Python::attach(|py| <DeError as de::Error>::custom(e.value(py))).at(key)
    }

    /// The bad setting, with the fix for its kind (as a scenario file's would have).
    pub fn into_setting(self) -> ConfigError {
        match self.setting.hint {
            Some(_) => self.setting,
            None => ConfigError::unreadable(self.setting.key, self.setting.message),
        }
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// A serde `Deserializer` over one Python object at the dotted key `path`.
pub struct PyDe<'a, 'py> {
    obj: &'a Bound<'py, PyAny>,
    path: String,
}

impl<'a, 'py> PyDe<'a, 'py> {
    /// The deserializer of `obj`, whose dotted key is `path` (empty: the root).
    pub fn new(obj: &'a Bound<'py, PyAny>, path: impl Into<String>) -> Self {
        PyDe {
            obj,
            path: path.into(),
        }
    }

    fn is_sequence(&self) -> bool {
        let o = self.obj;
        o.is_instance_of::<PyList>()
            || o.is_instance_of::<PyTuple>()
            || o.is_instance_of::<PyUntypedArray>()
    }
}

impl<'de, 'a, 'py> de::Deserializer<'de> for PyDe<'a, 'py> {
    type Error = DeError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        let o = self.obj;
        let path = self.path.as_str();
        let py_err = |e: PyErr| DeError::from_py(e, path);
        if o.is_none() {
            return visitor.visit_unit().map_err(|e: DeError| e.at(path));
        }
        if let Ok(b) = o.cast::<PyBool>() {
            return visitor
                .visit_bool(b.is_true())
                .map_err(|e: DeError| e.at(path));
        }
        if o.is_instance_of::<PyInt>() {
            return match o.extract::<i64>() {
                Ok(v) => visitor.visit_i64(v),
                Err(_) => match o.extract::<u64>() {
                    Ok(v) => visitor.visit_u64(v),
                    Err(_) => Err(de::Error::custom("integer out of range")),
                },
            }
            .map_err(|e: DeError| e.at(path));
        }
        if o.is_instance_of::<PyFloat>() {
            let v: f64 = o.extract().map_err(py_err)?;
            return visitor.visit_f64(v).map_err(|e: DeError| e.at(path));
        }
        if let Ok(s) = o.cast::<PyString>() {
            let s: String = s.extract().map_err(py_err)?;
            return visitor.visit_string(s).map_err(|e: DeError| e.at(path));
        }
        if let Ok(d) = o.cast::<PyDict>() {
            let items: Vec<(Bound<'py, PyAny>, Bound<'py, PyAny>)> =
                d.iter().filter(|(_, v)| !v.is_none()).collect();
            let access = DictAccess {
                items: items.into_iter(),
                value: None,
                prefix: self.path.clone(),
                key: String::new(),
            };
            return visitor.visit_map(access).map_err(|e: DeError| e.at(path));
        }
        if self.is_sequence() {
            let items = if o.is_instance_of::<PyUntypedArray>() {
                o.call_method0("tolist").map_err(py_err)?
            } else {
                o.clone()
            };
            if !items.is_instance_of::<PyList>() && !items.is_instance_of::<PyTuple>() {
                // A 0-d array: its scalar.
                return PyDe::new(&items, path).deserialize_any(visitor);
            }
            let list: Vec<Bound<'py, PyAny>> = items
                .try_iter()
                .map_err(py_err)?
                .collect::<PyResult<_>>()
                .map_err(py_err)?;
            let access = ListAccess {
                items: list.into_iter(),
                index: 0,
                prefix: self.path.clone(),
            };
            return visitor.visit_seq(access).map_err(|e: DeError| e.at(path));
        }
        // numpy scalars and anything else with __index__ / __float__.
        let type_name = o
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default();
        if type_name == "bool" || type_name == "bool_" {
            if let Ok(v) = o.extract::<bool>() {
                return visitor.visit_bool(v).map_err(|e: DeError| e.at(path));
            }
        }
        if let Ok(v) = o.extract::<i64>() {
            return visitor.visit_i64(v).map_err(|e: DeError| e.at(path));
        }
        if let Ok(v) = o.extract::<f64>() {
            return visitor.visit_f64(v).map_err(|e: DeError| e.at(path));
        }
        Err(DeError::type_error(
            path,
            format!(
                "a `{type_name}` is not a configuration value (use numbers, strings, booleans, lists and dicts)"
            ),
        ))
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        if self.obj.is_none() {
            visitor.visit_none()
        } else {
            visitor.visit_some(self)
        }
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, DeError> {
        if let Ok(s) = self.obj.cast::<PyString>() {
            let s: String = s.extract().map_err(|e| DeError::from_py(e, &self.path))?;
            let path = self.path.clone();
            return visitor
                .visit_enum(s.into_deserializer())
                .map_err(|e: DeError| e.at(&path));
        }
        let _ = (name, variants);
        self.deserialize_any(visitor)
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, DeError> {
        visitor.visit_newtype_struct(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf unit unit_struct seq tuple tuple_struct map struct identifier
        ignored_any
    }
}

struct DictAccess<'py> {
    items: std::vec::IntoIter<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    value: Option<Bound<'py, PyAny>>,
    prefix: String,
    key: String,
}

impl<'de, 'py> MapAccess<'de> for DictAccess<'py> {
    type Error = DeError;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, DeError> {
        let Some((k, v)) = self.items.next() else {
            return Ok(None);
        };
        let Ok(k) = k.cast::<PyString>() else {
            return Err(DeError::type_error(&self.prefix, "keys must be strings"));
        };
        let k: String = k.extract().map_err(|e| DeError::from_py(e, &self.prefix))?;
        self.key = join(&self.prefix, &k);
        self.value = Some(v);
        let key = self.key.clone();
        seed.deserialize(k.into_deserializer())
            .map(Some)
            .map_err(|e: DeError| e.at(&key))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, DeError> {
        let v = self
            .value
            .take()
            .ok_or_else(|| <DeError as de::Error>::custom("a value without its key"))?;
        let key = self.key.clone();
        seed.deserialize(PyDe::new(&v, key.clone()))
            .map_err(|e: DeError| e.at(&key))
    }
}

struct ListAccess<'py> {
    items: std::vec::IntoIter<Bound<'py, PyAny>>,
    index: usize,
    prefix: String,
}

impl<'de, 'py> SeqAccess<'de> for ListAccess<'py> {
    type Error = DeError;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, DeError> {
        let Some(item) = self.items.next() else {
            return Ok(None);
        };
        let key = format!("{}[{}]", self.prefix, self.index);
        self.index += 1;
        seed.deserialize(PyDe::new(&item, key.clone()))
            .map(Some)
            .map_err(|e: DeError| e.at(&key))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.items.len())
    }
}

/// Deserialises `T` from any Python object (a dict for a table), errors as `ValueError`s
/// (`TypeError` for a value of no configuration type) starting with `context`.
pub fn from_py<T: DeserializeOwned>(obj: &Bound<'_, PyAny>, context: &str) -> PyResult<T> {
    T::deserialize(PyDe::new(obj, "")).map_err(|e| {
        let type_error = e.type_error;
        let message = format!("{context}: {}", e.into_setting());
        if type_error {
            PyTypeError::new_err(message)
        } else {
            value_error(message)
        }
    })
}

/// Deserialises a configuration dictionary into `T`, as a scenario file's table would be;
/// `context` names it in errors (`"NeuralController config"`). `None` gives `T`'s
/// defaults (an empty table).
pub fn parse<T: DeserializeOwned>(config: Option<&Bound<'_, PyAny>>, context: &str) -> PyResult<T> {
    match config {
        Some(obj) if !obj.is_none() => {
            if !obj.is_instance_of::<PyDict>() {
                return Err(PyTypeError::new_err(format!(
                    "{context} must be a dict (the keys of the scenario file's table), got {}",
                    obj.get_type()
                        .name()
                        .map(|n| n.to_string())
                        .unwrap_or_default()
                )));
            }
            from_py(obj, context)
        }
        _ => Python::attach(|py| from_py(PyDict::new(py).as_any(), context)),
    }
}

/// A per-joint value given as one number or `n` numbers (`JointValues`), checked for shape.
pub fn joint_values(obj: &Bound<'_, PyAny>, name: &str, n: usize) -> PyResult<JointValues> {
    if let Ok(v) = obj.extract::<f64>() {
        if !obj.is_instance_of::<PyUntypedArray>()
            || obj.cast::<PyUntypedArray>().is_ok_and(|a| a.ndim() == 0)
        {
            return Ok(JointValues::Uniform(v));
        }
    }
    let v = crate::convert::vector(obj, name, n, "one value per joint, or a single number")
        .map_err(|e| {
            if e.is_instance_of::<PyTypeError>(obj.py()) {
                value_error(format!(
                    "`{name}` must be a number or an array of shape {}",
                    shape_text(&[n])
                ))
            } else {
                e
            }
        })?;
    Ok(JointValues::PerJoint(v))
}
