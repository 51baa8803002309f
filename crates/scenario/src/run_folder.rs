//! The run folder (docs/outputs.md; names from `admittance_runfolder`): `summary.json`, one
//! CSV per variant, the scenario as run. Written into a hidden sibling folder and renamed
//! into place at the end, so that a failed or interrupted run never leaves a folder that
//! looks complete. `--out` may replace only a folder this tool wrote (or an empty one);
//! anything else is refused before the run starts, unless forced.

use std::path::{Path, PathBuf};

use admittance_runfolder::health::{self, Severity, VariantHealth};
use admittance_runfolder::settings::RunSettings;
use admittance_runfolder::summary::{self, OutTarget};
use admittance_runfolder::{files, writer};
use serde_json::{json, Value};

use crate::error::ScenarioError;
use crate::progress::RunOptions;
use crate::runner::{run_variant, VariantRun};
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
use crate::spec::Scenario;

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
    /// Variants that failed although the folder was written: diverged, or a metric that
    /// is not finite. A run with failures must not be reported as a success.
    pub failures: Vec<String>,
    /// Every variant's health verdicts (`summary.json`'s `health`), in variant order.
    pub health: Vec<(String, VariantHealth)>,
    /// The variants that finished but broke a health rule of severity failure (hand error,
    /// effort saturation, ...; not counting `failures`), one line each.
    pub health_failures: Vec<String>,
}

/// A failure of a whole run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid (boxed, so that `RunError` stays small).
    #[error("{0}")]
    Scenario(Box<ScenarioError>),
    /// The output folder may not be written (it holds something this tool did not write).
    #[error("{0}")]
    Refused(String),
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

/// Writes any time series as CSV (header row, then one row per sample; shortest
/// round-trip decimal form of every value): `admittance_runfolder::writer`'s.
pub fn write_series_csv(path: &Path, series: &TimeSeries) -> Result<(), RunError> {
    writer::write_series_csv(path, &series.columns, &series.rows).map_err(io_err(path))
}

/// Where a run may write `out_dir`: refused (before any work) when it holds anything this
/// tool did not write, unless `force`; never the current folder, one of its parents, or a
/// folder holding the scenario file.
pub fn check_out_dir(out_dir: &Path, scenario: &Path, force: bool) -> Result<(), RunError> {
    let refuse = |why: String| {
        RunError::Refused(format!(
            "--out {}: {why}; nothing was written",
            out_dir.display()
        ))
    };
    if out_dir.file_name().is_none() || out_dir.as_os_str().is_empty() {
        return Err(refuse("is not a folder name a run can replace (`.`, `..` or `/`); give a new folder, e.g. --out runs/NAME".into()));
    }
    let canonical = |p: &Path| std::fs::canonicalize(p).ok();
    if let Some(out) = canonical(out_dir) {
        let inside = |p: Option<PathBuf>| p.is_some_and(|p| p.starts_with(&out));
        if inside(std::env::current_dir().ok().and_then(|d| canonical(&d))) {
            return Err(refuse(
                "holds the current folder; give a new folder, e.g. --out runs/NAME".into(),
            ));
        }
        if inside(canonical(scenario)) {
            return Err(refuse(
                "holds the scenario file being run; give a new folder, e.g. --out runs/NAME".into(),
            ));
        }
    }
    match summary::classify_out(out_dir) {
        OutTarget::Absent | OutTarget::EmptyFolder | OutTarget::RunFolder => Ok(()),
        OutTarget::Other(_) if force && out_dir.is_dir() => Ok(()),
        OutTarget::Other(why) => Err(refuse(format!(
            "{why}; a run replaces only a folder it wrote (or an empty one): choose another folder{}",
            if out_dir.is_dir() { ", or pass --force to replace this one" } else { "" }
        ))),
    }
}

/// Removes partial folders (`.NAME.partial-PID`) left in `parent` by runs that were
/// killed: only those holding this tool's marker whose process no longer exists.
/// Returns the folders removed.
pub fn remove_stale_partials(parent: &Path) -> Vec<PathBuf> {
    writer::remove_stale_partials(parent)
}

/// Runs every variant of the scenario at `path` (or only `only`) with the `--set`
/// `overrides` and writes the folder `out_dir`: [`run_scenario_variants`] with at most one
/// variant.
#[allow(clippy::too_many_arguments)]
pub fn run_scenario(
    path: &Path,
    out_dir: &Path,
    only: Option<&str>,
    overrides: &[String],
    options: &RunOptions,
    force: bool,
    progress: impl FnMut(&str, usize, usize),
    finish: impl FnOnce(&Path) -> Result<(), RunError>,
) -> Result<RunSummary, RunError> {
    let only: Vec<String> = only.map(str::to_string).into_iter().collect();
    run_scenario_variants(
        path, out_dir, &only, overrides, options, force, progress, finish,
    )
}

/// Runs every variant of the scenario at `path` (or only those named in `only`, in that
/// order, each once) with the `--set` `overrides` and writes the folder `out_dir`.
/// `progress` is told when each variant starts (name, index, count); `finish` runs on the
/// complete but not yet renamed folder (its path is the argument; `summary.json` and every
/// CSV are there) to add more outputs (figures, report, recording): an error there removes
/// the folder like any other.
#[allow(clippy::too_many_arguments)]
pub fn run_scenario_variants(
    path: &Path,
    out_dir: &Path,
    only: &[String],
    overrides: &[String],
    options: &RunOptions,
    force: bool,
    mut progress: impl FnMut(&str, usize, usize),
    finish: impl FnOnce(&Path) -> Result<(), RunError>,
) -> Result<RunSummary, RunError> {
    check_out_dir(out_dir, path, force)?;
    let mut source = ScenarioSource::load(path)?;
    for o in overrides {
        source.set(o)?;
    }
    let names = source.variant_names();
    let mut selected: Vec<Option<String>> = Vec::new();
    for v in only {
        if !selected.iter().any(|s| s.as_deref() == Some(v.as_str())) {
            selected.push(Some(v.clone()));
        }
    }
    if selected.is_empty() {
        selected = if names.is_empty() {
            vec![None]
        } else {
            names.iter().cloned().map(Some).collect()
        };
    }
    // Resolve and validate every selected variant before the first long run.
    let mut scenario_name = String::new();
    for v in &selected {
        let s: Scenario = source.resolve(v.as_deref())?;
        scenario_name = s.name.clone();
    }
    let mut runs = Vec::new();
    for (k, v) in selected.iter().enumerate() {
        progress(v.as_deref().unwrap_or("base"), k, selected.len());
        runs.push(run_variant(&source, path, v.as_deref(), options)?);
    }
    let first = source.resolve::<Scenario>(selected[0].as_deref())?;
    let evaluation_start = first.evaluation_start;
    crate::hand_paths::across_variants(&mut runs, evaluation_start);
    let judged: Vec<(String, VariantHealth)> =
        runs.iter().map(|r| (r.name.clone(), judge(r))).collect();
    let mut summary = summary_json(&scenario_name, &runs, &judged);
    if let Ok(file) = std::fs::canonicalize(path) {
        summary[summary::KEY_SCENARIO_FILE] = json!(file.display().to_string());
    }
    let settings = RunSettings::new(
        first.duration,
        evaluation_start,
        runs.iter().map(|r| r.settings.clone()).collect(),
    );
    write_folder(out_dir, path, force, |partial| {
        for run in &runs {
            write_series_csv(&partial.join(files::series(&run.name)), &run.series)?;
            if let Some(fm) = &run.free_motion {
                write_series_csv(&partial.join(files::free_motion(&run.name, runs.len())), fm)?;
            }
            if let Some(w) = &run.node_weights {
                write_series_csv(&partial.join(files::node_weights(&run.name)), w)?;
            }
            if let Some(v) = &run.observer_validation {
                write_series_csv(&partial.join(files::observer_validation(&run.name)), v)?;
            }
            if let Some(floor) = &run.contact_floor {
                let p = partial.join(files::contact_floor(&run.name));
                floor
                    .save(&p)
                    .map_err(|e| RunError::Finish(e.to_string()))?;
            }
        }
        let scenario_copy = partial.join(files::SCENARIO);
        std::fs::write(&scenario_copy, source.text_as_run(options.seed))
            .map_err(io_err(&scenario_copy))?;
        let settings_path = partial.join(files::SETTINGS);
        std::fs::write(&settings_path, settings.to_text()).map_err(io_err(&settings_path))?;
        // summary.json last: its presence marks a complete folder.
        let summary_path = partial.join(files::SUMMARY);
        let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
        std::fs::write(&summary_path, text).map_err(io_err(&summary_path))?;
        finish(partial)
    })?;
    let mut failures = Vec::new();
    let mut health_failures = Vec::new();
    for (name, h) in &judged {
        for v in h
            .verdicts
            .iter()
            .filter(|v| v.severity == Severity::Failure)
        {
            if v.rule == "divergence" {
                failures.push(format!("variant `{name}` {}", v.message));
            } else if STOPPING_RULES.contains(&v.rule.as_str()) {
                failures.push(format!("variant `{name}`: {}", v.message));
            } else {
                health_failures.push(format!("variant `{name}`: {}", v.message));
            }
        }
    }
    Ok(RunSummary {
        scenario: scenario_name,
        json: summary,
        variants: runs,
        out_dir: out_dir.to_path_buf(),
        failures,
        health: judged,
        health_failures,
    })
}

/// Writes the run folder of variants run on a plant outside this crate
/// ([`crate::ExternalVariant`], the MuJoCo co-simulation): the same files as
/// [`run_scenario_variants`] (one CSV per variant, `summary.json`, `scenario.toml`), written
/// the same way (a hidden partial sibling renamed into place; `out_dir` may replace only a
/// folder this tool wrote, or an empty one, unless `force`). `scenario_text` is the scenario
/// as run; it must load as a scenario (every variant resolved and validated as a scenario
/// file's, so that the scenario loader and `admittance report` accept the folder).
/// `extra` holds the summary's keys beyond the metrics (`plant`, ...). `protect` is a file
/// the folder must not contain (the arm's URDF). Returns the summary and the failures (a
/// divergence, a metric not finite), as [`RunSummary`] has them.
pub fn write_external_run_folder(
    out_dir: &Path,
    scenario_text: &str,
    runs: &[VariantRun],
    extra: serde_json::Map<String, Value>,
    force: bool,
    protect: &Path,
) -> Result<(Value, Vec<String>), RunError> {
    check_out_dir(out_dir, protect, force)?;
    let source = ScenarioSource::parse(scenario_text, files::SCENARIO)?;
    let mut scenario_name = String::new();
    let mut thresholds = Vec::with_capacity(runs.len());
    let names = source.variant_names();
    for run in runs {
        if !names.contains(&run.name) {
            return Err(RunError::Finish(format!(
                "{}: has no [variants.{}] for the variant run",
                files::SCENARIO,
                run.name
            )));
        }
        let s: Scenario = source.resolve(Some(&run.name))?;
        thresholds.push(s.health);
        scenario_name = s.name;
    }
    let judged: Vec<(String, VariantHealth)> = runs
        .iter()
        .zip(&thresholds)
        .map(|(r, h)| (r.name.clone(), judge_with(r, h)))
        .collect();
    let mut summary = summary_json(&scenario_name, runs, &judged);
    if let Value::Object(map) = &mut summary {
        for (k, v) in extra {
            map.entry(k).or_insert(v);
        }
    }
    write_folder(out_dir, protect, force, |partial| {
        for run in runs {
            write_series_csv(&partial.join(files::series(&run.name)), &run.series)?;
        }
        let scenario_copy = partial.join(files::SCENARIO);
        std::fs::write(&scenario_copy, scenario_text).map_err(io_err(&scenario_copy))?;
        let summary_path = partial.join(files::SUMMARY);
        let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
        std::fs::write(&summary_path, text).map_err(io_err(&summary_path))
    })?;
    let failures = judged
        .iter()
        .flat_map(|(name, h)| {
            h.verdicts
                .iter()
                .filter(|v| v.severity == Severity::Failure)
                .map(move |v| format!("variant `{name}`: {}", v.message))
        })
        .collect();
    Ok((summary, failures))
}

/// The rules whose failure means the run's numbers are not usable (exit 1 of `admittance
/// run`), unlike the other failures, of a run that finished but did not work (exit 4).
pub const STOPPING_RULES: [&str; 2] = ["divergence", "nonfinite_metric"];

/// The health of one variant: `admittance_runfolder::health::assess` on its metrics, with
/// the divergence's reason in its message.
fn judge(run: &VariantRun) -> VariantHealth {
    judge_with(run, &run.health_settings)
}

/// [`judge`] with the thresholds `settings` (a variant run outside this crate: its
/// scenario's `[health]`).
fn judge_with(run: &VariantRun, settings: &health::HealthSettings) -> VariantHealth {
    let metrics: serde_json::Map<String, Value> = run.metrics.to_map().into_iter().collect();
    let mut verdicts = health::assess(&metrics, &run.joints, settings);
    if let Some(d) = &run.divergence {
        for v in verdicts.iter_mut().filter(|v| v.rule == "divergence") {
            v.message = format!("diverged at t = {} s: {}", d.time, d.reason);
        }
    }
    VariantHealth::new(settings.clone(), verdicts)
}

/// `summary.json` of a run.
fn summary_json(scenario: &str, runs: &[VariantRun], judged: &[(String, VariantHealth)]) -> Value {
    let variants: serde_json::Map<String, Value> = runs
        .iter()
        .map(|run| {
            (
                run.name.clone(),
                Value::Object(run.metrics.to_map().into_iter().collect()),
            )
        })
        .collect();
    let mut out = serde_json::Map::new();
    out.insert(summary::KEY_FORMAT.into(), json!(summary::FORMAT));
    out.insert(
        summary::KEY_FORMAT_VERSION.into(),
        json!(summary::FORMAT_VERSION),
    );
    out.insert(summary::KEY_SCENARIO.into(), json!(scenario));
    out.insert(
        summary::KEY_JOINTS.into(),
        json!(runs.first().map(|r| r.joints.clone()).unwrap_or_default()),
    );
    out.insert(summary::KEY_VARIANTS.into(), Value::Object(variants));
    out.insert(
        summary::KEY_VARIANT_ORDER.into(),
        json!(runs.iter().map(|r| r.name.clone()).collect::<Vec<_>>()),
    );
    // The arm's load warnings, once each (variants may load the same arm).
    let mut warnings: Vec<&String> = Vec::new();
    for w in runs.iter().flat_map(|r| &r.arm_warnings) {
        if !warnings.contains(&w) {
            warnings.push(w);
        }
    }
    if !warnings.is_empty() {
        out.insert(summary::KEY_WARNINGS.into(), json!(warnings));
    }
    out.insert(
        summary::KEY_HEALTH.into(),
        health::summary_value(judged.iter().map(|(n, h)| (n.as_str(), h))),
    );
    Value::Object(out)
}

/// Writes a folder through a hidden partial sibling (`fill` writes into it) and renames it
/// to `out_dir` (replacing what [`check_out_dir`] allowed): `admittance_runfolder::writer`.
fn write_folder(
    out_dir: &Path,
    scenario: &Path,
    force: bool,
    fill: impl FnOnce(&Path) -> Result<(), RunError>,
) -> Result<(), RunError> {
    // Checked again: the run may have taken hours.
    check_out_dir(out_dir, scenario, force)?;
    writer::write_folder(out_dir, fill, |path, e| io_err(path)(e))
}
