//! The scenario document as an owned tree whose every key and value keeps where it was
//! written: a byte range in one offset space shared by the file (`0..text.len()`) and the
//! `--set` overrides (each appended after it). Parsed once from the file's text; a
//! variant is the base tree merged with its `[variants.NAME]` table and the overrides.

use std::ops::Range;

use toml::de::{DeTable, DeValue};

/// A value with the byte range it was written at and, for a table entry, the range of its
/// key.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    /// Where the value was written.
    pub span: Range<usize>,
    /// Where its key was written (a table entry), else the value's range.
    pub key_span: Range<usize>,
    /// The value.
    pub value: Value,
}

/// A TOML value, owned.
#[derive(Clone, Debug)]
pub(crate) enum Value {
    String(String),
    Integer(i64),
    Float(f64),
    Boolean(bool),
    Datetime(String),
    Array(Vec<Node>),
    Table(Table),
}

/// A table: entries in the order of their position in the text.
pub(crate) type Table = Vec<(String, Node)>;

impl Value {
    /// The TOML type's name, for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::String(_) => "a string",
            Value::Integer(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Boolean(_) => "a boolean",
            Value::Datetime(_) => "a date-time",
            Value::Array(_) => "a list",
            Value::Table(_) => "a table",
        }
    }
}

/// A value the tree cannot hold (an integer out of range, a float that overflows), with
/// where it was written.
#[derive(Debug)]
pub(crate) struct BadValue {
    pub span: Range<usize>,
    pub message: String,
}

fn shifted(r: Range<usize>, offset: usize) -> Range<usize> {
    r.start + offset..r.end + offset
}

/// Converts a parsed table, adding `offset` to every range.
pub(crate) fn from_de_table(table: &DeTable<'_>, offset: usize) -> Result<Table, BadValue> {
    let mut out: Table = Vec::with_capacity(table.len());
    for (key, value) in table.iter() {
        let mut node = from_de_value(value.get_ref(), shifted(value.span(), offset), offset)?;
        node.key_span = shifted(key.span(), offset);
        out.push((key.get_ref().to_string(), node));
    }
    out.sort_by_key(|(_, n)| n.key_span.start);
    Ok(out)
}

fn from_de_value(value: &DeValue<'_>, span: Range<usize>, offset: usize) -> Result<Node, BadValue> {
    let bad = |message: String| BadValue {
        span: span.clone(),
        message,
    };
    let value = match value {
        DeValue::String(s) => Value::String(s.to_string()),
        DeValue::Integer(i) => Value::Integer(
            i64::from_str_radix(&i.as_str().replace('_', ""), i.radix()).map_err(|_| {
                bad(format!(
                    "the integer {i} is out of range (at most {})",
                    i64::MAX
                ))
            })?,
        ),
        DeValue::Float(f) => {
            let text = f.as_str().replace('_', "");
            let x: f64 = text
                .parse()
                .map_err(|_| bad(format!("`{text}` is not a number")))?;
            if x.is_infinite() && !text.contains("inf") {
                return Err(bad(format!(
                    "the number {text} is too large for a 64-bit float (at most about 1.8e308)"
                )));
            }
            Value::Float(x)
        }
        DeValue::Boolean(b) => Value::Boolean(*b),
        DeValue::Datetime(d) => Value::Datetime(d.to_string()),
        DeValue::Array(a) => Value::Array(
            a.iter()
                .map(|e| from_de_value(e.get_ref(), shifted(e.span(), offset), offset))
                .collect::<Result<_, _>>()?,
        ),
        DeValue::Table(t) => Value::Table(from_de_table(t, offset)?),
    };
    Ok(Node {
        key_span: span.clone(),
        span,
        value,
    })
}

/// Deep merge: tables merge key by key, anything else in `over` replaces what `base`
/// holds (with its position).
pub(crate) fn merge(base: &mut Table, over: &Table) {
    for (k, v) in over {
        match base.iter_mut().find(|(bk, _)| bk == k) {
            Some((_, existing)) => match (&mut existing.value, &v.value) {
                (Value::Table(b), Value::Table(o)) => merge(b, o),
                _ => *existing = v.clone(),
            },
            None => base.push((k.clone(), v.clone())),
        }
    }
}

/// The entry at a dotted path (`plant.friction.0.joint`: list elements by index).
pub(crate) fn lookup<'a>(table: &'a Table, path: &str) -> Option<&'a Node> {
    let mut parts = path.split('.');
    let first = parts.next()?;
    let mut node = &table.iter().find(|(k, _)| k == first)?.1;
    for p in parts {
        node = match &node.value {
            Value::Table(t) => &t.iter().find(|(k, _)| k == p)?.1,
            Value::Array(a) => a.get(p.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(node)
}

/// The deepest written entry at or above a dotted path, with its path.
pub(crate) fn nearest<'a>(table: &'a Table, path: &str) -> Option<(String, &'a Node)> {
    let mut p = path.to_string();
    loop {
        if let Some(n) = lookup(table, &p) {
            return Some((p, n));
        }
        p.truncate(p.rfind('.')?);
    }
}
