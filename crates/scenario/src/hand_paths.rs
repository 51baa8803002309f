//! The hand metrics that compare variants or look at a variant's whole recorded path
//! (docs/outputs.md, "Hand metrics"): filled after every variant has run.

use admittance_runfolder::columns;

use crate::hand::norm_sq;
use crate::runner::VariantRun;
use crate::series::TimeSeries;

/// The hand positions (rows of `x, y, z`) and times of a variant's series.
fn hand_path(series: &TimeSeries) -> Option<(Vec<f64>, Vec<[f64; 3]>)> {
    let t = series.column(columns::TIME)?;
    let x: Vec<usize> = columns::AXES
        .iter()
        .map(|a| series.column(&columns::joint(columns::HAND_POSITION, a)))
        .collect::<Option<_>>()?;
    Some((
        series.rows.iter().map(|r| r[t]).collect(),
        series
            .rows
            .iter()
            .map(|r| [r[x[0]], r[x[1]], r[x[2]]])
            .collect(),
    ))
}

/// The hand metrics that compare variants or look at the whole path, from the recorded
/// series: `hand_compliance_error_rms` (against the variant named `oracle`, over the
/// evaluation window) and `hand_drift_after_release` (the largest distance the hand moves
/// from where it is 0.5 s after the last contact, to the end).
pub(crate) fn across_variants(runs: &mut [VariantRun], evaluation_start: f64) {
    let oracle = runs
        .iter()
        .find(|r| r.name == "oracle")
        .and_then(|r| hand_path(&r.series));
    for run in runs.iter_mut() {
        let Some((times, path)) = hand_path(&run.series) else {
            continue;
        };
        let release = last_contact(&run.series);
        let Some(hand) = run.metrics.hand.as_mut() else {
            continue;
        };
        if let Some((ot, op)) = &oracle {
            if ot.len() == times.len() && ot.iter().zip(&times).all(|(a, b)| a == b) {
                let (mut sum, mut count) = (0.0, 0usize);
                for (k, t) in times.iter().enumerate() {
                    if *t >= evaluation_start {
                        let d: Vec<f64> = (0..3).map(|i| path[k][i] - op[k][i]).collect();
                        sum += norm_sq(&d);
                        count += 1;
                    }
                }
                hand.hand_compliance_error_rms = (count > 0).then(|| (sum / count as f64).sqrt());
            }
        }
        if let Some(tr) = release {
            let settled = tr + 0.5;
            if let Some(k0) = times.iter().position(|t| *t >= settled) {
                let p0 = path[k0];
                let drift = path[k0..]
                    .iter()
                    .map(|p| norm_sq(&[p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]]).sqrt())
                    .fold(0.0, f64::max);
                hand.hand_drift_after_release = Some(drift);
            }
        }
    }
}

/// The time of the last recorded row with a non-zero true hand force.
fn last_contact(series: &TimeSeries) -> Option<f64> {
    let t = series.column(columns::TIME)?;
    let f: Vec<usize> = columns::AXES
        .iter()
        .map(|a| series.column(&columns::joint(columns::HAND_FORCE, a)))
        .collect::<Option<_>>()?;
    series
        .rows
        .iter()
        .rev()
        .find(|r| f.iter().any(|&c| r[c] != 0.0))
        .map(|r| r[t])
}
