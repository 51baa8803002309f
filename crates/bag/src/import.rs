//! The import: bag + profile -> free-motion table and report.

use std::path::Path;

use crate::error::BagError;
use crate::extract::{Collector, Extracted, Series};
use crate::output;
use crate::profile::Profile;
use crate::report::{ImportReport, SignalReport};
use crate::resample::{self, Table};

/// Options of an import.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// Output rate (Hz); `None`: the median rate of the `q` topic.
    pub rate_hz: Option<f64>,
    /// Keep the messages before damaged MCAP data (a truncated recording) instead of
    /// failing; the damage is listed in the report.
    pub accept_damage: bool,
}

/// The table and what was done to get it.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The free-motion table.
    pub table: Table,
    /// The report.
    pub report: ImportReport,
}

/// Reads a bag with a profile into the free-motion table.
pub fn import(
    bag: &Path,
    profile: &Profile,
    options: &ImportOptions,
) -> Result<Imported, BagError> {
    let files = crate::source::locate(bag)?;
    let mut collector = Collector::new(bag, profile);
    let mut damage = Vec::new();
    for f in &files {
        let outcome = crate::source::stream(f, options.accept_damage, |m| collector.visit(m))?;
        damage.extend(outcome.damage);
    }
    let extracted = collector.finish()?;
    let (table, mut report) = tabulate(bag, extracted, options.rate_hz)?;
    report.files = files.iter().map(|f| f.display().to_string()).collect();
    report.damage = damage;
    Ok(Imported { table, report })
}

/// Checks `out` first, imports, and writes the CSV atomically (only over a CSV this tool
/// wrote).
pub fn import_to_csv(
    bag: &Path,
    profile: &Profile,
    options: &ImportOptions,
    out: &Path,
) -> Result<ImportReport, BagError> {
    output::check_destination(out)?;
    let imported = import(bag, profile, options)?;
    output::write_csv(out, &imported.table)?;
    Ok(imported.report)
}

fn find<'a>(series: &'a [Series], role: &str) -> Option<&'a Series> {
    series.iter().find(|s| s.role == role)
}

fn signal_report(s: &Series) -> SignalReport {
    let rate = resample::median_period_ns(&s.stamps).map_or(0.0, |p| 1e9 / p as f64);
    SignalReport {
        role: s.role.to_string(),
        topic: s.topic.clone(),
        field: s.field.clone(),
        samples: s.stamps.len(),
        median_rate_hz: rate,
        time: s.time,
    }
}

fn tabulate(
    bag: &Path,
    ex: Extracted,
    rate_hz: Option<f64>,
) -> Result<(Table, ImportReport), BagError> {
    let (Some(q), Some(tau)) = (find(&ex.series, "q"), find(&ex.series, "tau")) else {
        return Err(BagError::Data {
            bag: bag.to_path_buf(),
            message: "the profile gives no q or tau".into(),
        });
    };
    let qdot = find(&ex.series, "qdot");
    let label = find(&ex.series, "label");
    let period = resample::period_ns(bag, q, rate_hz)?;
    let grid = resample::grid(bag, &ex.series, period)?;
    let drop = if qdot.is_some() { 1 } else { 2 };
    if grid.len() < drop + 1 {
        return Err(BagError::Data {
            bag: bag.to_path_buf(),
            message: format!(
                "{} grid point(s) in the signals' common span at {:.6} Hz: too few for the derivatives (need {})",
                grid.len(),
                1e9 / period as f64,
                drop + 1
            ),
        });
    }
    let n = ex.joints.len();
    let dt = period as f64 * 1e-9;
    let q_v = resample::interpolate(q, &grid);
    let (qdot_v, derivatives) = match qdot {
        Some(s) => (
            resample::interpolate(s, &grid),
            format!(
                "qdot from `{}`; qddot = backward difference of qdot",
                s.topic
            ),
        ),
        None => (
            resample::backward_difference(&q_v, n, dt),
            "qdot = backward difference of q; qddot = backward difference of qdot".to_string(),
        ),
    };
    let qddot_v = resample::backward_difference(&qdot_v, n, dt);
    let tau_v = resample::interpolate(tau, &grid);
    let cut = |v: Vec<f64>, m: usize| v[drop * m..].to_vec();
    let stamps = grid[drop..].to_vec();
    let t0 = stamps[0];
    let table = Table {
        joints: ex.joints.clone(),
        t: stamps
            .iter()
            .map(|s| s.saturating_sub(t0) as f64 / 1e9)
            .collect(),
        q: cut(q_v, n),
        qdot: cut(qdot_v, n),
        qddot: cut(qddot_v, n),
        tau: cut(tau_v, n),
        label: label.map(|s| {
            (
                s.columns.clone(),
                cut(resample::interpolate(s, &grid), s.columns.len()),
            )
        }),
        stamps_ns: stamps,
    };
    let report = ImportReport {
        files: Vec::new(),
        topics: ex.topics,
        signals: ex.series.iter().map(signal_report).collect(),
        skips: ex.skips,
        damage: Vec::new(),
        joints: ex.joints.clone(),
        rate_hz: 1e9 / period as f64,
        rate_is_median: rate_hz.is_none(),
        rows: table.len(),
        dropped_leading_rows: drop,
        duration_s: table.t.last().copied().unwrap_or(0.0),
        gaps: ex
            .series
            .iter()
            .flat_map(|s| {
                resample::gaps(&s.stamps).into_iter().map(move |(a, len)| {
                    (
                        s.topic.clone(),
                        a.saturating_sub(t0) as f64 / 1e9,
                        len as f64 / 1e9,
                    )
                })
            })
            .collect(),
        derivatives,
    };
    Ok((table, report))
}
