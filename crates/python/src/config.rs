//! Configuration dictionaries: the keys of the scenario files' tables
//! (`[controller.neural]`, `[controller.pd]`, `[observer.momentum]`, `[admittance]`, ...),
//! deserialised through the same serde structs and the same loader as a scenario file, so
//! that the same validation applies and an unknown key is an error naming it.
//!
//! The dictionary becomes a TOML table (`None` values are left out, i.e. take their
//! default; numpy arrays become lists), which `admittance_scenario::ScenarioSource`
//! resolves into the target struct.

use admittance_control::JointValues;
use admittance_scenario::ScenarioSource;
use numpy::prelude::*;
use numpy::PyUntypedArray;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde::de::DeserializeOwned;
use toml::{Table, Value};

use crate::convert::{shape_text, value_error};

/// One Python value as TOML; `None` gives `None` (the key is left out).
pub fn to_toml(obj: &Bound<'_, PyAny>, key: &str) -> PyResult<Option<Value>> {
    if obj.is_none() {
        return Ok(None);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Some(Value::Boolean(b.is_true())));
    }
    if obj.is_instance_of::<PyInt>() {
        let v: i64 = obj
            .extract()
            .map_err(|_| value_error(format!("config key `{key}`: integer out of range")))?;
        return Ok(Some(Value::Integer(v)));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Some(Value::Float(obj.extract()?)));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Some(Value::String(s.extract::<String>()?)));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return table(d, key).map(|t| Some(Value::Table(t)));
    }
    if obj.is_instance_of::<PyUntypedArray>()
        || obj.is_instance_of::<PyList>()
        || obj.is_instance_of::<PyTuple>()
    {
        let items = if obj.is_instance_of::<PyUntypedArray>() {
            obj.call_method0("tolist")?
        } else {
            obj.clone()
        };
        if !items.is_instance_of::<PyList>() && !items.is_instance_of::<PyTuple>() {
            // A 0-d array: its scalar.
            return to_toml(&items, key);
        }
        let mut out = Vec::new();
        for (i, item) in items.try_iter()?.enumerate() {
            if let Some(v) = to_toml(&item?, &format!("{key}[{i}]"))? {
                out.push(v);
            }
        }
        return Ok(Some(Value::Array(out)));
    }
    // numpy scalars and anything else with __index__ / __float__.
    if let Ok(v) = obj.extract::<i64>() {
        return Ok(Some(Value::Integer(v)));
    }
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(Some(Value::Float(v)));
    }
    Err(PyTypeError::new_err(format!(
        "config key `{key}`: a {} is not a configuration value (use numbers, strings, booleans, lists and dicts)",
        obj.get_type().name()?
    )))
}

fn table(d: &Bound<'_, PyDict>, prefix: &str) -> PyResult<Table> {
    let mut t = Table::new();
    for (k, v) in d.iter() {
        let Ok(k) = k.cast::<PyString>() else {
            return Err(PyTypeError::new_err(format!(
                "config key {}{}: keys must be strings",
                if prefix.is_empty() { "" } else { "under " },
                prefix
            )));
        };
        let k: String = k.extract()?;
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        if let Some(v) = to_toml(&v, &path)? {
            t.insert(k, v);
        }
    }
    Ok(t)
}

/// Deserialises a configuration dictionary into `T`, as a scenario file's table would be;
/// `context` names it in errors (`"NeuralController config"`). `None` gives `T`'s
/// defaults (an empty table).
pub fn parse<T: DeserializeOwned>(config: Option<&Bound<'_, PyAny>>, context: &str) -> PyResult<T> {
    let root =
        match config {
            None => Table::new(),
            Some(obj) if obj.is_none() => Table::new(),
            Some(obj) => {
                let d =
                    obj.cast::<PyDict>().map_err(|_| {
                        PyTypeError::new_err(format!(
                    "{context} must be a dict (the keys of the scenario file's table), got {}",
                    obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
                ))
                    })?;
                table(d, "")?
            }
        };
    // The loader treats a top-level `variants` table as the scenario's variants.
    if root.contains_key("variants") {
        return Err(value_error(format!(
            "{context}: key `variants`: unknown field `variants`"
        )));
    }
    let text = toml::to_string(&root)
        .map_err(|e| value_error(format!("{context}: cannot be written as TOML: {e}")))?;
    let source = ScenarioSource::parse(&text, context).map_err(|e| value_error(e.message))?;
    source.resolve::<T>(None).map_err(|e| {
        let mut message = context.to_string();
        if let Some(key) = &e.key {
            message.push_str(&format!(": key `{key}`"));
        }
        message.push_str(&format!(": {}", e.message));
        if let Some(hint) = &e.hint {
            message.push_str(&format!("; hint: {hint}"));
        }
        value_error(message)
    })
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
