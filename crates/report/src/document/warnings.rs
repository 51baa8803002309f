//! The warnings a report opens with: each variant's health verdicts as the run recorded
//! them (`admittance_runfolder::health`: divergence, hand error, saturation, estimate,
//! stale data, limits, faults, metrics that are not finite), what was said when the
//! scenario loaded (the arm's description, the gain rules), and samples the figures could
//! not draw. A folder without these metrics simply has no such warnings.

use admittance_runfolder::health;

use crate::figures::short_name;
use crate::folder::{RunFolder, Variant};

fn variant_warnings(folder: &RunFolder, v: &Variant, out: &mut Vec<String>) {
    let name = &v.name;
    // The verdicts the run recorded (admittance_runfolder::health), else the same rules on
    // the metrics with the default thresholds (a folder written before they were recorded).
    let recorded = folder
        .health
        .as_ref()
        .and_then(|h| h.iter().find(|(n, _)| n == name))
        .map(|(_, h)| h.verdicts.clone());
    let verdicts = recorded.unwrap_or_else(|| {
        health::assess(
            &v.metrics,
            &folder.joints,
            &health::HealthSettings::default(),
        )
    });
    for verdict in verdicts {
        let what = match verdict.severity {
            health::Severity::Failure => "**failed**",
            health::Severity::Warning => "warning",
        };
        let joint = verdict
            .joint
            .as_deref()
            .map_or(String::new(), |j| format!(" on {}", short_name(j)));
        out.push(format!(
            "`{name}` {what} `{}`{joint}: {}.",
            verdict.rule, verdict.message
        ));
    }
}

/// Every warning of the run, variants in the scenario's order; `figure_notes` are the
/// figures' notes on samples they could not draw (`(figure id, note)`).
pub fn warnings(folder: &RunFolder, figure_notes: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for v in &folder.variants {
        variant_warnings(folder, v, &mut out);
    }
    for w in &folder.warnings {
        out.push(format!("when the scenario loaded: {w}"));
    }
    let mut ids: Vec<&str> = figure_notes.iter().map(|(id, _)| id.as_str()).collect();
    ids.dedup();
    for id in ids {
        let notes: Vec<&str> = figure_notes
            .iter()
            .filter(|(i, _)| i == id)
            .map(|(_, n)| n.as_str())
            .collect();
        out.push(format!(
            "Fig. {id} left out data it cannot draw: {}.",
            notes.join("; ")
        ));
    }
    out
}
