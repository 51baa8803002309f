//! The import: bag + profile -> free-motion table and report.

use std::path::Path;

use crate::budget::MAX_TABLE_VALUES;
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
    /// Skip damaged MCAP chunks and keep the messages before the end of a truncated
    /// recording instead of failing; the damage is listed and counted in the report.
    pub accept_damage: bool,
    /// Import a recording (or an output rate) under [`MIN_RATE_HZ`] with a warning in the
    /// report instead of refusing it.
    pub accept_low_rate: bool,
}

/// The lowest rate the loop can use (Hz): its observers differentiate the measured angles
/// at the control rate (docs/method.md); 10-50 Hz learning data sets are too coarse.
pub const MIN_RATE_HZ: f64 = 200.0;

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
    let (mut damage, mut skipped_chunks) = (Vec::new(), 0);
    for f in &files {
        let outcome = crate::source::stream(f, options.accept_damage, |m| collector.visit(m))?;
        damage.extend(outcome.damage);
        skipped_chunks += outcome.skipped_chunks;
    }
    let extracted = collector.finish().map_err(|e| match damage.first() {
        // All that could be read was skipped as damage: say so, not only what is missing.
        Some(first) if matches!(e, BagError::MissingTopic { .. } | BagError::Field { .. }) => {
            data_error(
            bag,
            format!(
                "too little is left after skipping the damage ({} damaged record(s); the first: {first}): {e}",
                    skipped_chunks.max(1)
                ),
            )
        }
        _ => e,
    })?;
    let (table, mut report) = tabulate(bag, extracted, options)?;
    check_table(bag, &table)?;
    report.files = files.iter().map(|f| f.display().to_string()).collect();
    report.damage = damage;
    report.skipped_chunks = skipped_chunks;
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
    output::check_columns(bag, &imported.table)?;
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

fn data_error(bag: &Path, message: String) -> BagError {
    BagError::Data {
        bag: bag.to_path_buf(),
        message,
    }
}

/// The recording's rate (the `q` topic's median) and the output rate must reach
/// [`MIN_RATE_HZ`], or with `accept_low_rate` they give a warning (returned).
fn check_rates(
    bag: &Path,
    q: &Series,
    period_ns: i64,
    options: &ImportOptions,
) -> Result<Vec<String>, BagError> {
    let recorded = resample::median_period_ns(&q.stamps).map_or(0.0, |p| 1e9 / p as f64);
    let output = 1e9 / period_ns as f64;
    let mut low = Vec::new();
    if recorded < MIN_RATE_HZ {
        low.push(format!(
            "the recording's q topic `{}` has a median rate of {recorded:.3} Hz",
            q.topic
        ));
    }
    if output < MIN_RATE_HZ && options.rate_hz.is_some() {
        low.push(format!("--rate {output:.3} Hz"));
    }
    if low.is_empty() {
        return Ok(Vec::new());
    }
    let why = format!(
        "{}, under the {MIN_RATE_HZ} Hz the loop needs (its observers differentiate the angles at the control rate)",
        low.join(" and ")
    );
    if !options.accept_low_rate {
        return Err(data_error(bag, format!("{why}: record at the robot's rate (or give a higher --rate), or pass --accept-low-rate to import it anyway")));
    }
    Ok(vec![format!(
        "WARNING: {why}; imported because of --accept-low-rate"
    )])
}

/// The memory budget, before the resampling allocates: rows x columns <= MAX_TABLE_VALUES.
fn check_budget(bag: &Path, ex: &Extracted, rows: usize, period_ns: i64) -> Result<(), BagError> {
    let n = ex.joints.len();
    let label = ex
        .series
        .iter()
        .find(|s| s.role == "label")
        .map_or(0, |s| s.columns.len());
    let columns = 2 + 4 * n + label;
    let values = rows as u128 * columns as u128;
    if values <= MAX_TABLE_VALUES {
        return Ok(());
    }
    let span_s = rows as f64 * period_ns as f64 * 1e-9;
    let max_rate = MAX_TABLE_VALUES as f64 / columns as f64 / span_s;
    Err(data_error(bag, format!(
        "the table would have {rows} rows x {columns} columns = {values} values ({:.1} s common span at {:.3} Hz), above the import's memory budget of {MAX_TABLE_VALUES} values (400 MB): give a lower --rate (at most {max_rate:.3} Hz for this span), or if the span is longer than the recording, a stamp far from the others (a clock jump) stretches it: cut the bag before it",
        span_s,
        1e9 / period_ns as f64,
    )))
}

/// What the table cannot honestly carry: two columns of one name, a non-finite value.
fn check_table(bag: &Path, t: &Table) -> Result<(), BagError> {
    let mut names: Vec<&String> = t.joints.iter().collect();
    names.sort();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(data_error(bag, format!("joint `{}` appears twice in the joint names: the columns would be ambiguous; list the joints once in the profile's `joints`", w[0])));
    }
    let blocks = [
        ("q", &t.q),
        ("qdot", &t.qdot),
        ("qddot", &t.qddot),
        ("tau", &t.tau),
    ];
    let label = t.label.iter().map(|(c, v)| ("label", v, c));
    let joint_blocks = blocks.iter().map(|(p, v)| (*p, *v, &t.joints));
    for (prefix, values, cols) in joint_blocks.chain(label) {
        let m = cols.len().max(1);
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            return Err(data_error(bag, format!(
                "column {prefix}.{} is {} at row {} (t = {:.6} s) after resampling: values that large overflow (are the recorded values in the right unit?); nothing was written",
                cols.get(i % m).map_or("?", |c| c.as_str()),
                values[i],
                i / m,
                t.t.get(i / m).copied().unwrap_or(f64::NAN)
            )));
        }
    }
    Ok(())
}

fn tabulate(
    bag: &Path,
    ex: Extracted,
    options: &ImportOptions,
) -> Result<(Table, ImportReport), BagError> {
    let rate_hz = options.rate_hz;
    let (Some(q), Some(tau)) = (find(&ex.series, "q"), find(&ex.series, "tau")) else {
        return Err(BagError::Data {
            bag: bag.to_path_buf(),
            message: "the profile gives no q or tau".into(),
        });
    };
    let qdot = find(&ex.series, "qdot");
    let label = find(&ex.series, "label");
    let period = resample::period_ns(bag, q, rate_hz)?;
    let mut notes = ex.notes.clone();
    notes.extend(check_rates(bag, q, period, options)?);
    let rows = resample::grid_rows(bag, &ex.series, period)?;
    check_budget(bag, &ex, rows, period)?;
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
    let (q, unwrapped) = resample::unwrapped(q);
    if !unwrapped.is_empty() {
        notes.push(format!(
            "{} read within one turn (a continuous joint's angle, wrapped): put back on one \
             branch before resampling",
            unwrapped.join(", ")
        ));
    }
    let q_v = resample::interpolate(&q, &grid);
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
    // In place: the table is the budgeted memory, not twice it.
    let cut = |mut v: Vec<f64>, m: usize| {
        v.drain(..drop * m);
        v
    };
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
        skipped_chunks: 0,
        notes,
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
