//! A run folder read back from disk: `summary.json`, `scenario.toml` and the time series
//! of every variant (`VARIANT.csv`), plus `free_motion*.csv` when present.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::table::Table;
use crate::ReportError;

/// The `format` string of `summary.json` this crate reads.
pub const RUN_FORMAT: &str = "admittance-run";
/// The `format_version`s of `summary.json` this crate reads.
pub const SUPPORTED_RUN_FORMAT_VERSIONS: &[u64] = &[1];

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
    /// Joint names in chain order.
    pub joints: Vec<String>,
    /// The variants, in `summary.json`'s order.
    pub variants: Vec<Variant>,
    /// The scenario file as run (`scenario.toml`), when present and readable.
    pub scenario_toml: Option<toml::Table>,
    /// Free-motion recordings (`free_motion.csv`, `free_motion_VARIANT.csv`): file name and data.
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

impl RunFolder {
    /// Reads a run folder written by `admittance run`.
    pub fn load(dir: &Path) -> Result<Self, ReportError> {
        if !dir.is_dir() {
            return Err(input(
                dir,
                "not a folder; pass the folder written by `admittance run SCENARIO --out DIR`",
            ));
        }
        let summary_path = dir.join("summary.json");
        let text = std::fs::read_to_string(&summary_path).map_err(|e| {
            input(
                &summary_path,
                format!("cannot read ({e}); is this a run folder? (`admittance run` writes it)"),
            )
        })?;
        let summary: Value = serde_json::from_str(&text).map_err(|e| {
            input(
                &summary_path,
                format!("not valid JSON ({e}); regenerate the folder with `admittance run`"),
            )
        })?;
        let format = summary.get("format").and_then(Value::as_str);
        if format != Some(RUN_FORMAT) {
            return Err(input(
                &summary_path,
                format!(
                    "`format` is {}, expected \"{RUN_FORMAT}\": not a run summary",
                    format.map_or("missing".to_string(), |f| format!("\"{f}\""))
                ),
            ));
        }
        let version = summary.get("format_version").and_then(Value::as_u64);
        match version {
            Some(v) if SUPPORTED_RUN_FORMAT_VERSIONS.contains(&v) => {}
            Some(v) => {
                return Err(input(
                    &summary_path,
                    format!(
                        "format_version {v} is not supported by this build (it reads {:?}); rerun the scenario with this build or use a matching `admittance`",
                        SUPPORTED_RUN_FORMAT_VERSIONS
                    ),
                ))
            }
            None => {
                return Err(input(
                    &summary_path,
                    "`format_version` is missing or not a whole number; regenerate the folder with `admittance run`",
                ))
            }
        }
        let scenario = summary
            .get("scenario")
            .and_then(Value::as_str)
            .ok_or_else(|| input(&summary_path, "`scenario` (a string) is missing"))?
            .to_string();
        let joints: Vec<String> = summary
            .get("joints")
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|j| j.as_str().map(String::from))
                    .collect()
            })
            .ok_or_else(|| input(&summary_path, "`joints` (a list of names) is missing"))?;
        let variant_map = summary
            .get("variants")
            .and_then(Value::as_object)
            .ok_or_else(|| input(&summary_path, "`variants` (an object) is missing"))?;
        let mut variants = Vec::new();
        for (name, metrics) in variant_map {
            let csv = dir.join(format!("{name}.csv"));
            if !csv.is_file() {
                return Err(input(
                    &csv,
                    format!("missing: summary.json lists variant `{name}`; rerun the scenario to recreate the folder"),
                ));
            }
            let table = Table::load(&csv)?;
            if !table.has("t") {
                return Err(input(
                    &csv,
                    "no `t` column (time, s): not a run time series",
                ));
            }
            variants.push(Variant {
                name: name.clone(),
                metrics: metrics.as_object().cloned().unwrap_or_default(),
                table,
            });
        }
        let scenario_path = dir.join("scenario.toml");
        let scenario_toml = std::fs::read_to_string(&scenario_path)
            .ok()
            .and_then(|t| t.parse::<toml::Table>().ok());
        let mut free_motion = Vec::new();
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .map_err(|e| input(dir, format!("cannot list: {e}")))?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| n.starts_with("free_motion") && n.ends_with(".csv"))
            .collect();
        names.sort();
        for n in names {
            // Only the angles are drawn (Figs 13, 14): the file can be hundreds of MB.
            let keep = |c: &str| c == "t" || c.starts_with("q.");
            free_motion.push((n.clone(), Table::load_columns(&dir.join(&n), &keep)?));
        }
        let mut node_weights = Vec::new();
        for v in &variants {
            let path = dir.join(format!("weights_{}.csv", v.name));
            if path.is_file() {
                node_weights.push((v.name.clone(), Table::load_columns(&path, &|_| true)?));
            }
        }
        let mut observer_validation = Vec::new();
        for v in &variants {
            let path = dir.join(format!("validation_{}.csv", v.name));
            if path.is_file() {
                observer_validation.push((v.name.clone(), Table::load_columns(&path, &|_| true)?));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            scenario,
            joints,
            variants,
            scenario_toml,
            free_motion,
            node_weights,
            observer_validation,
        })
    }

    /// The variant called `name`.
    pub fn variant(&self, name: &str) -> Option<&Variant> {
        self.variants.iter().find(|v| v.name == name)
    }

    /// A value of the scenario file by dotted key (`"dynamic_nodes.approximation_window"`).
    pub fn scenario_value(&self, key: &str) -> Option<&toml::Value> {
        let mut parts = key.split('.');
        let mut value = self.scenario_toml.as_ref()?.get(parts.next()?)?;
        for p in parts {
            value = value.as_table()?.get(p)?;
        }
        Some(value)
    }

    /// A value of the scenario file as variant `variant` sees it: the variant's override
    /// (`[variants.NAME]` with the same dotted key) when there is one, else the base value.
    pub fn variant_value(&self, variant: &str, key: &str) -> Option<&toml::Value> {
        self.scenario_value(&format!("variants.{variant}.{key}"))
            .or_else(|| self.scenario_value(key))
    }

    /// The scenario's one-line description (`description` in scenario.toml).
    pub fn description(&self) -> Option<&str> {
        self.scenario_value("description")
            .and_then(toml::Value::as_str)
    }
}
