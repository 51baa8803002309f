//! The run folder: `summary.json`, one CSV per variant, a copy of the scenario, and
//! `report.md`. Written into a temporary sibling folder and renamed into place at the end,
//! so that a failed or interrupted run never leaves a folder that looks complete.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::runner::{run_variant, RunOptions, TimeSeries, VariantRun};
use super::source::{ScenarioError, ScenarioSource};

/// Version of the run-folder format (`summary.json`'s `format_version`).
pub const RUN_FORMAT_VERSION: u32 = 1;

/// What a finished run produced.
#[derive(Debug)]
pub struct RunSummary {
    /// Scenario name.
    pub scenario: String,
    /// The summary as written to `summary.json`.
    pub json: Value,
    /// The runs, in variant order.
    pub variants: Vec<VariantRun>,
    /// The folder written.
    pub out_dir: PathBuf,
}

/// A failure of a whole run: a scenario problem or an I/O problem writing the folder.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid (boxed, so that `RunError` stays small for callers'
    /// closures such as the `finish` hook).
    #[error("{0}")]
    Scenario(Box<ScenarioError>),
    /// A finishing step (report, figures, recording) failed.
    #[error("{0}")]
    Finish(String),
    /// Writing the output failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: String,
        /// The error.
        source: std::io::Error,
    },
}

impl From<ScenarioError> for RunError {
    fn from(e: ScenarioError) -> Self {
        RunError::Scenario(Box::new(e))
    }
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Writes a variant's time series as CSV (header row, then one row per sample).
pub fn write_csv(path: &Path, run: &VariantRun) -> Result<(), RunError> {
    write_series_csv(path, &run.series)
}

/// Writes any time series as CSV (header row, then one row per sample; shortest
/// round-trip decimal form of every value).
pub fn write_series_csv(path: &Path, series: &TimeSeries) -> Result<(), RunError> {
    let file = std::fs::File::create(path).map_err(io_err(path))?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "{}", series.columns.join(",")).map_err(io_err(path))?;
    let mut line = String::new();
    for row in &series.rows {
        line.clear();
        for (k, v) in row.iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            let _ = write!(line, "{v}");
        }
        writeln!(w, "{line}").map_err(io_err(path))?;
    }
    w.flush().map_err(io_err(path))
}

fn fmt_metric(v: &Value) -> String {
    match v {
        Value::Number(n) => {
            let x = n.as_f64().unwrap_or(0.0);
            if x == x.trunc() && x.abs() < 1e9 {
                format!("{x}")
            } else {
                format!("{x:.4e}")
            }
        }
        Value::Array(a) => a.iter().map(fmt_metric).collect::<Vec<_>>().join(", "),
        Value::Object(o) => o
            .iter()
            .map(|(k, v)| format!("{k}: {}", fmt_metric(v)))
            .collect::<Vec<_>>()
            .join(", "),
        other => other.to_string(),
    }
}

fn report(scenario: &str, description: &str, runs: &[VariantRun]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Scenario `{scenario}`\n\n{description}\n");
    let _ = writeln!(
        out,
        "Joints: {}\n",
        runs.first()
            .map(|r| r.joints.join(", "))
            .unwrap_or_default()
    );
    let mut keys: Vec<&String> = Vec::new();
    for r in runs {
        for k in r.metrics.keys() {
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    let _ = writeln!(
        out,
        "| metric | {} |",
        runs.iter()
            .map(|r| format!("`{}`", r.name))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(out, "|---|{}", "---|".repeat(runs.len()));
    for k in keys {
        let cells: Vec<String> = runs
            .iter()
            .map(|r| r.metrics.get(k).map(fmt_metric).unwrap_or_default())
            .collect();
        let _ = writeln!(out, "| {k} | {} |", cells.join(" | "));
    }
    let _ = writeln!(
        out,
        "\nTime series: `<variant>.csv` beside this file (columns in docs/outputs.md)."
    );
    out
}

/// Runs every variant of the scenario at `path` (or only `only`) with the `--set`
/// `overrides` and writes the folder `out_dir`. `progress` is told when each variant starts
/// (name, index, count); `finish` runs on the complete but not yet renamed folder (its
/// path is the argument; `summary.json` and every CSV are there) to add more outputs
/// (figures, report, recording): an error there removes the folder like any other.
pub fn run_scenario(
    path: &Path,
    out_dir: &Path,
    only: Option<&str>,
    overrides: &[String],
    options: &RunOptions,
    mut progress: impl FnMut(&str, usize, usize),
    finish: impl FnOnce(&Path) -> Result<(), RunError>,
) -> Result<RunSummary, RunError> {
    let mut source = ScenarioSource::load(path)?;
    for o in overrides {
        source.set(o)?;
    }
    let names = source.variant_names();
    let selected: Vec<Option<String>> = match only {
        Some(v) => vec![Some(v.to_string())],
        None if names.is_empty() => vec![None],
        None => names.iter().cloned().map(Some).collect(),
    };
    // Resolve and validate every selected variant before the first long run.
    let mut scenario_name = String::new();
    let mut description = String::new();
    for v in &selected {
        let s: super::spec::Scenario = source.resolve(v.as_deref())?;
        scenario_name = s.name.clone();
        description = s.description.clone();
    }
    let mut runs = Vec::new();
    for (k, v) in selected.iter().enumerate() {
        progress(v.as_deref().unwrap_or("base"), k, selected.len());
        runs.push(run_variant(&source, path, v.as_deref(), options)?);
    }

    let parent = out_dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(io_err(parent))?;
    let leaf = out_dir
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "run".into());
    let partial = parent.join(format!(".{leaf}.partial-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&partial);
    std::fs::create_dir_all(&partial).map_err(io_err(&partial))?;

    // Everything is written into the hidden partial folder; on any failure it is removed.
    let written = (|| -> Result<Value, RunError> {
        let mut variants = serde_json::Map::new();
        for run in &runs {
            write_csv(&partial.join(format!("{}.csv", run.name)), run)?;
            if let Some(fm) = &run.free_motion {
                let name = if runs.len() == 1 {
                    "free_motion.csv".to_string()
                } else {
                    format!("free_motion_{}.csv", run.name)
                };
                write_series_csv(&partial.join(name), fm)?;
            }
            if let Some(w) = &run.node_weights {
                write_series_csv(&partial.join(format!("weights_{}.csv", run.name)), w)?;
            }
            if let Some(v) = &run.observer_validation {
                write_series_csv(&partial.join(format!("validation_{}.csv", run.name)), v)?;
            }
            let metrics: serde_json::Map<String, Value> = run
                .metrics
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            variants.insert(run.name.clone(), Value::Object(metrics));
        }
        let summary = json!({
            "format": "admittance-run",
            "format_version": RUN_FORMAT_VERSION,
            "scenario": scenario_name,
            "joints": runs.first().map(|r| r.joints.clone()).unwrap_or_default(),
            "variants": Value::Object(variants),
        });
        let scenario_copy = partial.join("scenario.toml");
        std::fs::write(&scenario_copy, source.text()).map_err(io_err(&scenario_copy))?;
        let report_path = partial.join("report.md");
        std::fs::write(&report_path, report(&scenario_name, &description, &runs))
            .map_err(io_err(&report_path))?;
        // summary.json last: its presence marks a complete folder.
        let summary_path = partial.join("summary.json");
        let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
        std::fs::write(&summary_path, text).map_err(io_err(&summary_path))?;
        finish(&partial)?;
        Ok(summary)
    })();
    let summary = match written {
        Ok(summary) => summary,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&partial);
            return Err(e);
        }
    };

    let old = parent.join(format!(".{leaf}.old-{}", std::process::id()));
    if out_dir.exists() {
        std::fs::rename(out_dir, &old).map_err(io_err(out_dir))?;
    }
    std::fs::rename(&partial, out_dir).map_err(io_err(out_dir))?;
    let _ = std::fs::remove_dir_all(&old);
    Ok(RunSummary {
        scenario: scenario_name,
        json: summary,
        variants: runs,
        out_dir: out_dir.to_path_buf(),
    })
}
