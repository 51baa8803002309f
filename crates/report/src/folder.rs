//! A run folder read back from disk through the contract of `admittance_runfolder`:
//! `summary.json`, `scenario.toml`, the time series of every variant (`VARIANT.csv`) and,
//! when present, `free_motion*.csv`, `weights_VARIANT.csv` and `validation_VARIANT.csv`.

use std::path::{Path, PathBuf};

use admittance_runfolder::{columns, files, summary};
use serde_json::Value;

use crate::table::Table;
use crate::ReportError;

/// One variant: its metrics (from `summary.json`) and its time series.
#[derive(Clone, Debug)]
pub struct Variant {
    /// The variant's name (`VARIANT.csv`).
    pub name: String,
    /// Its metrics, as in `summary.json`.
    pub metrics: serde_json::Map<String, Value>,
    /// Its time series.
    pub table: Table,
}

/// Everything the report is made from.
#[derive(Clone, Debug)]
pub struct RunFolder {
    /// The folder.
    pub dir: PathBuf,
    /// Scenario name (`summary.json`'s `scenario`).
    pub scenario: String,
    /// The plant that produced the run when it is not this project's simulator
    /// (`summary.json`'s `plant`, e.g. `mujoco`).
    pub plant: Option<String>,
    /// Joint names in chain order.
    pub joints: Vec<String>,
    /// The variants in the scenario's order: `variant_order` of `summary.json`, else the
    /// order of `[variants.*]` in `scenario.toml`, else by name.
    pub variants: Vec<Variant>,
    /// Warnings recorded with the run (`summary.json`'s `warnings`: how the arm's
    /// description was read).
    pub warnings: Vec<String>,
    /// The health verdicts recorded with the run (`summary.json`'s `health`), per variant;
    /// `None` for a folder written before they were recorded (the report then judges the
    /// metrics with the same rules and default thresholds).
    pub health: Option<Vec<(String, admittance_runfolder::health::VariantHealth)>>,
    /// The scenario file as run (`scenario.toml`), when present and readable.
    pub scenario_toml: Option<toml::Table>,
    /// Every variant's settings as the run applied them (`settings.json`); `None` in a
    /// folder written before that file existed (the settings are then read from
    /// `scenario.toml`, and the report says so).
    pub settings: Option<admittance_runfolder::settings::RunSettings>,
    /// Free-motion recordings (`free_motion.csv`, `free_motion_VARIANT.csv`): file name
    /// and the columns `t` and `q.*`.
    pub free_motion: Vec<(String, Table)>,
    /// Per-node weight norms of the f network (`weights_VARIANT.csv`, runs with dynamic
    /// nodes): variant name and data.
    pub node_weights: Vec<(String, Table)>,
    /// Learned observers' networks on their validation data (`validation_VARIANT.csv`):
    /// variant name and data.
    pub observer_validation: Vec<(String, Table)>,
}

fn input(path: &Path, message: impl Into<String>) -> ReportError {
    ReportError::Input {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Parses `summary.json` and checks its format marker and version.
fn read_summary(path: &Path) -> Result<Value, ReportError> {
    let text =
        admittance_files::read_regular_text(path, admittance_files::TEXT_LIMIT).map_err(|e| {
            input(
                path,
                format!("cannot read ({e}); is this a run folder? (`admittance run` writes it)"),
            )
        })?;
    let value: Value = serde_json::from_str(&text).map_err(|e| {
        input(
            path,
            format!("not valid JSON ({e}); regenerate the folder with `admittance run`"),
        )
    })?;
    let format = value.get(summary::KEY_FORMAT).and_then(Value::as_str);
    if format != Some(summary::FORMAT) {
        return Err(input(
            path,
            format!(
                "`{}` is {}, expected \"{}\": not a run summary",
                summary::KEY_FORMAT,
                format.map_or("missing".to_string(), |f| format!("\"{f}\"")),
                summary::FORMAT
            ),
        ));
    }
    match value.get(summary::KEY_FORMAT_VERSION).and_then(Value::as_u64) {
        Some(v) if summary::SUPPORTED_VERSIONS.contains(&v) => Ok(value),
        Some(v) => Err(input(
            path,
            format!(
                "format_version {v} is not supported by this build (it reads {:?}); rerun the scenario with this build or use a matching `admittance`",
                summary::SUPPORTED_VERSIONS
            ),
        )),
        None => Err(input(
            path,
            "`format_version` is missing or not a whole number; regenerate the folder with `admittance run`",
        )),
    }
}

/// The variant names of `scenario.toml` in the order of the file (`[variants.NAME]`).
fn scenario_variant_order(text: &str) -> Vec<String> {
    let Ok(doc) = text.parse::<toml_edit::DocumentMut>() else {
        return Vec::new();
    };
    doc.get("variants")
        .and_then(toml_edit::Item::as_table_like)
        .map(|t| t.iter().map(|(k, _)| k.to_string()).collect())
        .unwrap_or_default()
}

/// `names` (the variants of `summary.json`) in the scenario's order.
fn ordered(names: Vec<String>, summary_order: &[String], file_order: &[String]) -> Vec<String> {
    let order = if summary_order.is_empty() {
        file_order
    } else {
        summary_order
    };
    let mut out: Vec<String> = order
        .iter()
        .filter(|n| names.contains(n))
        .cloned()
        .collect();
    out.dedup();
    out.extend(names.into_iter().filter(|n| !order.contains(n)));
    out
}

fn string_list(value: Option<&Value>) -> Option<Vec<String>> {
    value.and_then(Value::as_array).map(|a| {
        a.iter()
            .filter_map(|j| j.as_str().map(String::from))
            .collect()
    })
}

impl RunFolder {
    /// Reads a run folder written by `admittance run`.
    pub fn load(dir: &Path) -> Result<Self, ReportError> {
        if !dir.is_dir() {
            return Err(input(
                dir,
                "not a folder; pass the folder written by `admittance run SCENARIO --out DIR`",
            ));
        }
        let summary_path = dir.join(files::SUMMARY);
        let summary = read_summary(&summary_path)?;
        let scenario = summary
            .get(summary::KEY_SCENARIO)
            .and_then(Value::as_str)
            .ok_or_else(|| input(&summary_path, "`scenario` (a string) is missing"))?
            .to_string();
        let joints = string_list(summary.get(summary::KEY_JOINTS))
            .ok_or_else(|| input(&summary_path, "`joints` (a list of names) is missing"))?;
        let variant_map = summary
            .get(summary::KEY_VARIANTS)
            .and_then(Value::as_object)
            .ok_or_else(|| input(&summary_path, "`variants` (an object) is missing"))?;
        let scenario_text = admittance_files::read_regular_text(
            &dir.join(files::SCENARIO),
            admittance_files::TEXT_LIMIT,
        )
        .ok();
        let scenario_toml = scenario_text
            .as_deref()
            .and_then(|t| t.parse::<toml::Table>().ok());
        let names = ordered(
            variant_map.keys().cloned().collect(),
            &string_list(summary.get(summary::KEY_VARIANT_ORDER)).unwrap_or_default(),
            &scenario_text
                .as_deref()
                .map(scenario_variant_order)
                .unwrap_or_default(),
        );
        let mut variants = Vec::new();
        for name in names {
            let csv = dir.join(files::series(&name));
            if !csv.is_file() {
                return Err(input(
                    &csv,
                    format!("missing: summary.json lists variant `{name}`; rerun the scenario to recreate the folder"),
                ));
            }
            let table = Table::load(&csv)?;
            if !table.has(columns::TIME) {
                return Err(input(
                    &csv,
                    format!(
                        "no `{}` column (time, s): not a run time series",
                        columns::TIME
                    ),
                ));
            }
            let metrics = variant_map[&name].as_object().cloned().unwrap_or_default();
            variants.push(Variant {
                name,
                metrics,
                table,
            });
        }
        let settings = admittance_runfolder::settings::RunSettings::read(dir)
            .map_err(|e| input(&dir.join(files::SETTINGS), e))?;
        let free_motion = load_free_motion(dir)?;
        let mut node_weights = Vec::new();
        let mut observer_validation = Vec::new();
        for v in &variants {
            let path = dir.join(files::node_weights(&v.name));
            if path.is_file() {
                node_weights.push((v.name.clone(), Table::load(&path)?));
            }
            let path = dir.join(files::observer_validation(&v.name));
            if path.is_file() {
                observer_validation.push((v.name.clone(), Table::load(&path)?));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            scenario,
            plant: summary
                .get(summary::KEY_PLANT)
                .and_then(Value::as_str)
                .map(String::from),
            joints,
            variants,
            warnings: string_list(summary.get(summary::KEY_WARNINGS)).unwrap_or_default(),
            health: admittance_runfolder::health::read(&summary),
            scenario_toml,
            settings,
            free_motion,
            node_weights,
            observer_validation,
        })
    }

    /// The variant called `name`.
    pub fn variant(&self, name: &str) -> Option<&Variant> {
        self.variants.iter().find(|v| v.name == name)
    }
}

/// `free_motion*.csv`, sorted by name: only `t` and the angles are kept (Figs 13, 14), the
/// file can be hundreds of MB.
fn load_free_motion(dir: &Path) -> Result<Vec<(String, Table)>, ReportError> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| input(dir, format!("cannot list: {e}")))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| files::is_free_motion(n))
        .collect();
    names.sort();
    let angle_prefix = format!("{}.", columns::POSITION);
    let keep = |c: &str| c == columns::TIME || c.starts_with(&angle_prefix);
    names
        .into_iter()
        .map(|n| Ok((n.clone(), Table::load_columns(&dir.join(&n), &keep)?)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_follow_the_scenario_order() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let summary = names(&["b", "a", "c"]);
        // summary.json's variant_order first, unknown variants last.
        assert_eq!(
            ordered(names(&["a", "b", "c", "d"]), &summary, &[]),
            ["b", "a", "c", "d"]
        );
        // Else the order of scenario.toml.
        let file = scenario_variant_order(
            "name = \"x\"\n[variants.zeta]\nk = 1\n[variants.alpha]\nk = 2\n[variants.mid]\n",
        );
        assert_eq!(file, ["zeta", "alpha", "mid"]);
        assert_eq!(
            ordered(names(&["alpha", "mid", "zeta"]), &[], &file),
            ["zeta", "alpha", "mid"]
        );
        // Dotted keys count too.
        assert_eq!(
            scenario_variant_order("variants.b.x = 1\nvariants.a.x = 2\n"),
            ["b", "a"]
        );
    }
}
