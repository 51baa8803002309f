//! Shared helpers of the scenario tests.
#![allow(dead_code)]

use admittance_scenario::VariantRun;
use serde_json::Value;

/// A file of the project's `scenarios/` folder.
pub fn scenario_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name)
}

/// A metric of a variant as `summary.json` writes it (panics, naming it, when missing).
pub fn metric(run: &VariantRun, key: &str) -> Value {
    run.metrics
        .to_map()
        .remove(key)
        .unwrap_or_else(|| panic!("{}: metric `{key}` missing", run.name))
}

/// A scalar metric of a variant (panics, naming it, when missing).
pub fn number(run: &VariantRun, key: &str) -> f64 {
    metric(run, key)
        .as_f64()
        .unwrap_or_else(|| panic!("{}: metric `{key}` is not a number", run.name))
}

/// A per-joint metric of a variant (panics, naming it, when missing or of the wrong length).
pub fn per_joint(run: &VariantRun, key: &str) -> Vec<f64> {
    let v = metric(run, key);
    let v = v
        .as_array()
        .unwrap_or_else(|| panic!("{}: metric `{key}` is not an array", run.name));
    assert_eq!(
        v.len(),
        run.joints.len(),
        "{}: `{key}` has one value per joint",
        run.name
    );
    v.iter()
        .map(|x| {
            x.as_f64()
                .unwrap_or_else(|| panic!("{}: `{key}` holds a non-number", run.name))
        })
        .collect()
}

/// A column of a variant's time series (panics, naming it, when missing).
pub fn column(run: &VariantRun, name: &str) -> Vec<f64> {
    let c = run
        .series
        .column(name)
        .unwrap_or_else(|| panic!("no column {name}"));
    run.series.rows.iter().map(|r| r[c]).collect()
}

/// Records a data scenario of `scenarios/`, shortened to `seconds`, into
/// `dir/free_motion.csv`.
pub fn record(name: &str, seconds: f64, dir: &std::path::Path) -> std::path::PathBuf {
    admittance_scenario::run_scenario(
        &scenario_path(name),
        dir,
        None,
        &[format!("duration={seconds}")],
        &admittance_scenario::RunOptions::default(),
        false,
        |_, _, _| {},
        |_| Ok(()),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    dir.join("free_motion.csv")
}
