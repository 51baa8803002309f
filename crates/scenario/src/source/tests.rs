use super::*;
use serde::Deserialize;

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct Gains {
    k1: f64,
    #[serde(default)]
    k2: Option<f64>,
    #[serde(default)]
    list: Vec<Entry>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct Entry {
    joint: String,
    value: f64,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct Doc {
    name: String,
    controller: Gains,
}

const TEXT: &str = "name = \"x\"\n\n[controller]\nk1 = 12.0\n\n[variants.slow]\ncontroller.k1 = 3.0\n\n[variants.typo]\ncontroller.kk = 1.0\n\n[variants.wrong]\ncontroller.k2 = \"six\"\n";

#[test]
fn variants_merge_over_the_base() {
    let src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
    assert_eq!(src.variant_names(), ["slow", "typo", "wrong"]);
    let base: Doc = src.resolve(None).unwrap();
    assert_eq!(base.controller.k1, 12.0);
    let slow: Doc = src.resolve(Some("slow")).unwrap();
    assert_eq!(slow.controller.k1, 3.0);
}

#[test]
fn unknown_keys_and_wrong_types_name_line_and_key() {
    let src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
    let e = src.resolve::<Doc>(Some("typo")).unwrap_err();
    assert_eq!(e.line, Some(10), "{e}");
    assert!(e.to_string().contains("unknown field `kk`"), "{e}");
    let e = src.resolve::<Doc>(Some("wrong")).unwrap_err();
    assert_eq!(e.line, Some(13), "{e}");
    assert_eq!(e.key.as_deref(), Some("controller.k2"), "{e}");
    let e = src.resolve::<Doc>(Some("nope")).unwrap_err();
    assert!(e.to_string().contains("slow, typo, wrong"), "{e}");
}

#[test]
fn a_table_where_a_number_belongs_names_the_key_and_line() {
    let text = "name = \"x\"\n[controller]\nk1 = 1.0\n[controller.k2]\na = 1\n";
    let src = ScenarioSource::parse(text, "s.toml").unwrap();
    let e = src.resolve::<Doc>(None).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("controller.k2"), "{e}");
    assert_eq!(e.line, Some(4), "{e}");
    assert!(e.message.contains("invalid type: map"), "{e}");
}

#[test]
fn entries_of_arrays_of_tables_have_lines() {
    let text = "name = \"x\"\n[controller]\nk1 = 1.0\n\n[[controller.list]]\njoint = \"a\"\nvalue = 1.0\n\n[[controller.list]]\njoint = \"b\"\nvalue = \"one\"\n";
    let src = ScenarioSource::parse(text, "s.toml").unwrap();
    let e = src.resolve::<Doc>(None).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("controller.list.1.value"), "{e}");
    assert_eq!(e.line, Some(11), "{e}");
    let e = src.invalid(
        None,
        &[ConfigError::new("controller.list.1.joint", "unknown joint")],
    );
    assert_eq!(e.line, Some(10), "{e}");
}

#[test]
fn syntax_errors_have_lines_and_overrides_apply() {
    let e = ScenarioSource::parse("a = 1\nb = [1,\n", "bad.toml").unwrap_err();
    assert!(
        e.line.is_some() && e.to_string().starts_with("bad.toml:"),
        "{e}"
    );
    let mut src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
    src.set("controller.k1=7").unwrap();
    let d: Doc = src.resolve(Some("slow")).unwrap();
    assert_eq!(d.controller.k1, 7.0);
    src.set("controller.k2=oops").unwrap();
    let e = src.resolve::<Doc>(None).unwrap_err();
    assert_eq!(e.file, "--set controller.k2=oops", "{e}");
    assert!(src.set("novalue").is_err());
    assert!(src.set("nodes=[1,").is_err());
}

#[test]
fn deep_nesting_is_a_located_syntax_error() {
    let text = format!("name = \"x\"\nv = {}{}\n", "[".repeat(200), "]".repeat(200));
    let e = ScenarioSource::parse(&text, "deep.toml").unwrap_err();
    assert_eq!(e.line, Some(2), "{e}");
}

#[test]
fn validation_problems_are_located_and_all_listed() {
    let src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
    let e = src.invalid(
        Some("slow"),
        &[ConfigError::new("controller.k1", "must be positive").hint("use 12")],
    );
    assert_eq!(e.line, Some(7));
    assert_eq!(
        e.to_string(),
        "s.toml:7: key `controller.k1` (variant `slow`): must be positive; hint: use 12"
    );
    let e = src.invalid(
        None,
        &[
            ConfigError::new("controller.k1", "bad"),
            ConfigError::new("name", "too short"),
        ],
    );
    assert_eq!(e.line, Some(4));
    let text = e.to_string();
    assert_eq!(text.lines().count(), 2, "{text}");
    assert!(
        text.lines()
            .nth(1)
            .unwrap()
            .starts_with("s.toml:1: key `name`: too short"),
        "{text}"
    );
}

#[test]
fn the_text_as_run_carries_the_overrides() {
    let mut src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
    src.set("controller.k1=7.5").unwrap();
    src.set("plant.rate_hz=2000").unwrap();
    let text = src.text_as_run(Some(3));
    let again = ScenarioSource::parse(&text, "again.toml").unwrap();
    let doc: toml::Table = again.resolve(Some("slow")).unwrap();
    assert_eq!(doc["controller"]["k1"].as_float(), Some(7.5), "{text}");
    assert_eq!(doc["plant"]["rate_hz"].as_integer(), Some(2000), "{text}");
    assert_eq!(doc["seed"].as_integer(), Some(3), "{text}");
    assert!(text.starts_with("# The scenario as run"), "{text}");
}
