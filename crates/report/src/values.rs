//! Reading and formatting the metric values of `summary.json`.

use serde_json::Value;

use crate::folder::Variant;

pub use crate::number::short as fmt_num;

/// A fraction as a percentage (`4.0 %`).
pub fn fmt_percent(x: f64) -> String {
    if x == 0.0 {
        return "0 %".into();
    }
    let p = 100.0 * x;
    if p.abs() >= 10.0 {
        format!("{p:.1} %")
    } else if p.abs() >= 0.01 {
        format!("{p:.2} %")
    } else {
        format!("{p:.1e} %")
    }
}

/// A metric value as a table cell.
pub fn fmt_value(v: &Value, percent: bool) -> String {
    match v {
        Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) if !percent => i.to_string(),
            (_, Some(x)) if percent => fmt_percent(x),
            (_, Some(x)) => fmt_num(x),
            _ => n.to_string(),
        },
        Value::Array(a) => a
            .iter()
            .map(|x| fmt_value(x, percent))
            .collect::<Vec<_>>()
            .join(", "),
        Value::Object(o) => o
            .iter()
            .map(|(k, v)| format!("{k}: {}", fmt_value(v, percent)))
            .collect::<Vec<_>>()
            .join(", "),
        Value::Null => "–".into(),
        Value::String(s) => s.clone(),
        Value::Bool(b) => if *b { "yes" } else { "no" }.into(),
    }
}

/// A number metric of a variant.
pub fn num(v: &Variant, name: &str) -> Option<f64> {
    v.metrics.get(name).and_then(Value::as_f64)
}

/// A per-joint metric of a variant (`None` entries for nulls).
pub fn per_joint(v: &Variant, name: &str) -> Option<Vec<Option<f64>>> {
    v.metrics
        .get(name)
        .and_then(Value::as_array)
        .map(|a| a.iter().map(Value::as_f64).collect())
}

/// Whether a value is "nothing happened": zero, false, null, or a list or object of those.
pub fn is_zero(v: &Value) -> bool {
    match v {
        Value::Number(n) => n.as_f64() == Some(0.0),
        Value::Bool(b) => !b,
        Value::Null => true,
        Value::Array(a) => a.iter().all(is_zero),
        Value::Object(o) => o.values().all(is_zero),
        Value::String(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn formats_values() {
        assert_eq!(fmt_value(&json!(0.0017234), false), "0.001723");
        assert_eq!(fmt_value(&json!(12), false), "12");
        assert_eq!(fmt_value(&json!(2.5634), false), "2.563");
        assert_eq!(fmt_value(&json!(1.5e-7), false), "1.500e-7");
        assert_eq!(fmt_value(&json!([1, null]), false), "1, –");
        assert_eq!(fmt_value(&json!({"f": 512}), false), "f: 512");
        assert_eq!(fmt_value(&json!(0.0399), true), "3.99 %");
        assert_eq!(fmt_value(&json!(0.299), true), "29.9 %");
        assert_eq!(fmt_value(&json!(true), false), "yes");
        assert!(is_zero(&json!([0, 0.0, null])) && !is_zero(&json!([0, 1e-9])));
    }
}

/// The value of a per-joint metric of `v` at joint `index`.
pub(crate) fn joint_metric(v: &Variant, name: &str, index: usize) -> Option<f64> {
    per_joint(v, name)?.get(index).copied().flatten()
}
