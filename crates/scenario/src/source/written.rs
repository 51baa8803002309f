//! The scenario file as run: the `--set` overrides (and a `--seed`) written into the text
//! where the merge puts them, so that a run folder's `scenario.toml` says what ran.

use toml_edit::{DocumentMut, Item, Table, Value};

/// `text` with every `(dotted key, TOML value text)` written in, in order: at the key in
/// the base tables and in every `[variants.NAME]` table that sets it (a later override
/// wins over a variant's value, as in the merge), with a comment at the top listing them.
/// Text that does not parse is returned with the comment only.
pub(crate) fn with_overrides(
    text: &str,
    assignments: &[(String, String)],
    seed: Option<u64>,
) -> String {
    if assignments.is_empty() && seed.is_none() {
        return text.to_string();
    }
    let mut header =
        String::from("# The scenario as run, with these command-line overrides written in:\n");
    for (k, v) in assignments {
        header.push_str(&format!("#   --set {k}={v}\n"));
    }
    if let Some(s) = seed {
        header.push_str(&format!("#   --seed {s}\n"));
    }
    let Ok(mut doc) = text.parse::<DocumentMut>() else {
        return format!("{header}{text}");
    };
    let mut all: Vec<(String, Value)> = assignments
        .iter()
        .map(|(k, v)| {
            let value = v
                .parse::<Value>()
                .unwrap_or_else(|_| Value::from(v.as_str()));
            (k.clone(), value)
        })
        .collect();
    if let Some(s) = seed {
        all.push(("seed".into(), Value::from(s as i64)));
    }
    let variant_names: Vec<String> = doc
        .get("variants")
        .and_then(Item::as_table_like)
        .map(|t| t.iter().map(|(k, _)| k.to_string()).collect())
        .unwrap_or_default();
    for (key, value) in &all {
        let parts: Vec<&str> = key.split('.').collect();
        set_path(doc.as_table_mut(), &parts, value.clone());
        for v in &variant_names {
            if let Some(Item::Table(t)) =
                doc.get_mut("variants").and_then(|x| x.get_mut(v.as_str()))
            {
                if has_path(t, &parts) {
                    set_path(t, &parts, value.clone());
                }
            }
        }
    }
    format!("{header}{doc}")
}

fn has_path(table: &Table, parts: &[&str]) -> bool {
    let mut item = match table.get(parts[0]) {
        Some(i) => i,
        None => return false,
    };
    for p in &parts[1..] {
        item = match item.get(p) {
            Some(i) => i,
            None => return false,
        };
    }
    true
}

/// Sets `parts` to `value`, making tables on the way and
/// replacing anything that is not one, as the merge does.
fn set_path(table: &mut Table, parts: &[&str], value: Value) {
    let (first, rest) = match parts.split_first() {
        Some(x) => x,
        None => return,
    };
    if rest.is_empty() {
        table.insert(first, Item::Value(value));
        return;
    }
    let entry = table.entry(first).or_insert_with(|| {
        let mut t = Table::new();
        t.set_implicit(true);
        Item::Table(t)
    });
    set_item(entry, rest, value);
}

fn set_item(item: &mut Item, parts: &[&str], value: Value) {
    let (first, rest) = match parts.split_first() {
        Some(x) => x,
        None => {
            *item = Item::Value(value);
            return;
        }
    };
    if let Some(t) = item.as_table_like_mut() {
        if rest.is_empty() {
            t.insert(first, Item::Value(value));
        } else {
            let entry = t.entry(first).or_insert(Item::Table({
                let mut n = Table::new();
                n.set_implicit(true);
                n
            }));
            set_item(entry, rest, value);
        }
        return;
    }
    let mut t = Table::new();
    t.set_implicit(true);
    *item = Item::Table(t);
    set_item(item, parts, value);
}
