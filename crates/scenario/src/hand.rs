//! The hand of a task-space run (issue 16): the true force of the environment on the hand
//! against the estimate `J^{+T} tau_ext_hat`, the hand's path, and how closely it follows
//! the oracle's (docs/outputs.md, "Hand metrics").

use admittance_dynamics::{forward_kinematics, Data, Model};
use admittance_runfolder::columns;

use crate::metrics::HandMetrics;
use crate::runner::VariantRun;
use crate::series::TimeSeries;

/// Forward kinematics of the hand (the model's tip frame) for the hand error and the
/// hand columns.
pub(crate) struct HandKinematics {
    data: Data,
    tip: usize,
}

impl HandKinematics {
    /// For `model`'s tip frame.
    pub fn new(model: &Model) -> Self {
        Self {
            data: Data::new(model),
            tip: model.tip_frame,
        }
    }

    /// The hand's position (m, base frame) at `q`.
    pub fn position(&mut self, model: &Model, q: &[f64]) -> [f64; 3] {
        let _ = forward_kinematics(model, &mut self.data, q);
        let p = self.data.frame_placements[self.tip].translation;
        [p.x, p.y, p.z]
    }
}

/// Per-step sums of the hand metrics over the evaluation window.
#[derive(Default)]
pub(crate) struct HandStats {
    contact_err_sq: f64,
    contact_true_sq: f64,
    contact_count: usize,
    free_sq: f64,
    free_count: usize,
    force_max: f64,
}

fn norm_sq(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

impl HandStats {
    /// One step: the true hand force and the estimated one (force part, N).
    pub fn add(&mut self, truth: &[f64; 3], estimate: &[f64]) {
        let t2 = norm_sq(truth);
        self.force_max = self.force_max.max(t2.sqrt());
        if t2 > 0.0 {
            let err: Vec<f64> = estimate.iter().zip(truth).map(|(e, t)| e - t).collect();
            self.contact_err_sq += norm_sq(&err);
            self.contact_true_sq += t2;
            self.contact_count += 1;
        } else {
            self.free_sq += norm_sq(&estimate[..3]);
            self.free_count += 1;
        }
    }

    /// The metrics of one variant (the cross-variant ones are filled by [`across_variants`]).
    pub fn finish(&self) -> HandMetrics {
        let rmse = (self.contact_err_sq / self.contact_count.max(1) as f64).sqrt();
        HandMetrics {
            wrench_estimate_rmse: (self.contact_count > 0).then_some(rmse),
            wrench_estimate_nrmse: (self.contact_true_sq > 0.0)
                .then(|| (self.contact_err_sq / self.contact_true_sq).sqrt()),
            false_force_rms: (self.free_sq / self.free_count.max(1) as f64).sqrt(),
            contact_force_max: self.force_max,
            hand_compliance_error_rms: None,
            hand_drift_after_release: None,
        }
    }
}

/// The hand columns of `VARIANT.csv`: `f_hand.x .. x_hand_d.z`.
pub(crate) fn hand_columns() -> Vec<String> {
    let mut out = Vec::new();
    for prefix in [
        columns::HAND_FORCE,
        columns::HAND_FORCE_ESTIMATE,
        columns::HAND_POSITION,
        columns::HAND_REFERENCE,
        columns::HAND_DESIRED,
    ] {
        out.extend(columns::AXES.iter().map(|a| columns::joint(prefix, a)));
    }
    out
}

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
