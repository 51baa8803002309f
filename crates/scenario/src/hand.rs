//! The hand of a task-space run (issue 16): the true force of the environment on the hand
//! against the estimate `J^{+T} tau_ext_hat`, the hand's path, and how closely it follows
//! the oracle's (docs/outputs.md, "Hand metrics").

use admittance_dynamics::{forward_kinematics, Data, Model};
use admittance_runfolder::columns;

use crate::metrics::HandMetrics;

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

pub(crate) fn norm_sq(v: &[f64]) -> f64 {
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

    /// The metrics of one variant (the cross-variant ones are filled by `hand_paths::across_variants`).
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
