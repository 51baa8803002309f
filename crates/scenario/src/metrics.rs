//! The metrics of one variant (docs/outputs.md, "Metrics"; names in
//! `admittance_runfolder::metrics`): the typed record written to `summary.json` and the
//! accumulators that gather it step by step.

use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::Value;

/// Everything `summary.json` says about one variant. Field names are the metric names.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VariantMetrics {
    /// Whether the variant diverged (and stopped there).
    pub diverged: bool,
    /// When it diverged (s).
    pub diverged_at: Option<f64>,
    /// Per joint: share of control steps with the true angle outside its limits.
    pub q_limit_violation_fraction: Vec<f64>,
    /// Per joint: share of control steps with the command at the effort limit.
    pub torque_saturation_fraction: Vec<f64>,
    /// Per joint: share of control steps with the estimate beyond the effort limit.
    pub estimate_saturation_fraction: Vec<f64>,
    /// Per joint: RMS of `q_r - q` (rad), evaluation window.
    pub tracking_rmse: Vec<f64>,
    /// Per joint: largest `|q_r - q|` (rad).
    pub tracking_max_abs: Vec<f64>,
    /// RMS hand position error (m).
    pub ee_error_rms: f64,
    /// Largest hand position error (m).
    pub ee_error_max: f64,
    /// Per joint: RMS command (N m).
    pub torque_rms: Vec<f64>,
    /// Per joint: largest command (N m).
    pub torque_max_abs: Vec<f64>,
    /// Per joint: share of control periods inside the deadzone.
    pub deadzone_time_fraction: Vec<f64>,
    /// Median controller step (us).
    pub controller_step_median_us: f64,
    /// Controller faults (steps).
    pub faults: usize,
    /// Steps on which some joint's encoder reading was stale (frozen or dropped): a subset
    /// of `faults`.
    pub stale_measurements: usize,
    /// Commands beyond the effort limit.
    pub torque_limit_violations: usize,
    /// Non-finite commands.
    pub nonfinite_torques: usize,
    /// Control steps simulated.
    pub steps: usize,
    /// Per joint: RMS of the estimate error (N m).
    pub external_torque_rmse: Vec<f64>,
    /// Estimate error over the RMS true torque in contact (`None`: no contact).
    pub external_torque_nrmse: Option<f64>,
    /// Per joint: RMS estimate without contact (N m).
    pub false_torque_rms: Vec<f64>,
    /// Samples x joints with `q_r` outside its saturation bound.
    pub reference_bound_violations: usize,
    /// With an admittance model: per joint RMS of `q_r - q_r(oracle)` (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub admittance_error_rms: Option<Vec<f64>>,
    /// Observer updates that faulted.
    pub observer_faults: usize,
    /// Samples the plausibility gates refused, by the gate of the first refused value
    /// (`angle`, `jump`, `torque`; issue 34); absent when the loop's caller gates.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gated_samples: Option<BTreeMap<String, u64>>,
    /// Lowest coverage of the observer's input by its network's training data over the
    /// evaluation window (hybrid; 1 inside the data, 0 far outside).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate_coverage_min: Option<f64>,
    /// Mean coverage over the evaluation window.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate_coverage_mean: Option<f64>,
    /// Control steps on which some joint's measured angle lay outside the training range of
    /// the observer's identification (absent when it records none): its model extrapolated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps_outside_training_range: Option<usize>,
    /// Control steps on which some joint moved faster than the observer's identification was
    /// fitted at, beyond `TRAINING_SPEED_MARGIN` (absent when it records no speeds): its
    /// friction extrapolated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps_faster_than_training: Option<usize>,
    /// How a learned observer's network was obtained.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub observer_training: Option<ObserverTrainingMetrics>,
    /// The identification the momentum or hybrid observer runs on.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub identification: Option<IdentificationMetrics>,
    /// Final node count per network of the neural controller.
    pub nodes: BTreeMap<String, usize>,
    /// Final weight norm per network of the neural controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weight_norm_final: Option<BTreeMap<String, f64>>,
    /// Experiment C.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub dynamic_nodes: Option<DynamicNodeMetrics>,
    /// Task-space runs: the hand.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub hand: Option<HandMetrics>,
    /// Contact detection against the true external torque (`[contact]`, issue 31).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub contact: Option<crate::contact_score::ContactMetrics>,
}

/// The hand of a task-space run (issue 16; docs/outputs.md).
#[derive(Clone, Debug, Serialize)]
pub struct HandMetrics {
    /// RMS of the estimated minus the true hand force while in contact (N); `None` without
    /// contact.
    pub wrench_estimate_rmse: Option<f64>,
    /// That over the RMS true force in contact.
    pub wrench_estimate_nrmse: Option<f64>,
    /// RMS estimated hand force while nothing touches the hand (N).
    pub false_force_rms: f64,
    /// Largest true force on the hand (N).
    pub contact_force_max: f64,
    /// RMS distance of the hand from the `oracle` variant's (m), when that variant ran.
    pub hand_compliance_error_rms: Option<f64>,
    /// How far the hand moves after the last contact has ended and 0.5 s have passed (m).
    pub hand_drift_after_release: Option<f64>,
}

/// A learned observer's network (docs/outputs.md).
#[derive(Clone, Debug, Serialize)]
pub struct ObserverTrainingMetrics {
    /// Wall time of the fit (s).
    pub train_seconds: f64,
    /// Gaussian nodes.
    pub observer_nodes: usize,
    /// Per joint NRMSE on the validation data.
    pub validation_nrmse: Vec<f64>,
    /// Whether it came from the cache.
    pub observer_model_cached: bool,
    /// Training rows.
    pub training_samples: usize,
    /// Chosen ridge parameter.
    pub observer_lambda: f64,
}

/// The identified nominal model of a momentum or hybrid observer (docs/outputs.md).
#[derive(Clone, Debug, Serialize)]
pub struct IdentificationMetrics {
    /// Per joint: the identified model's RMS false torque on its validation data (N m).
    pub identification_expected_false_torque_rms: Vec<f64>,
    /// Whether it came from the cache (or a given file).
    pub identification_cached: bool,
}

/// Experiment C (dynamic nodes).
#[derive(Clone, Debug, Serialize)]
pub struct DynamicNodeMetrics {
    /// RMS of `f - f_hat` before the discard (N m).
    pub approx_rmse_full: f64,
    /// After the discard (N m).
    pub approx_rmse_after_discard: f64,
    /// After growth (N m).
    pub approx_rmse_after_growth: f64,
    /// Nodes discarded.
    pub nodes_discarded: usize,
    /// Nodes added.
    pub nodes_added: usize,
    /// Largest f-network weight norm.
    pub weight_norm_max: f64,
}

impl VariantMetrics {
    /// The metrics as `summary.json` writes them (keys sorted).
    pub fn to_map(&self) -> BTreeMap<String, Value> {
        match serde_json::to_value(self) {
            Ok(Value::Object(m)) => m.into_iter().collect(),
            _ => BTreeMap::new(),
        }
    }
}

/// RMS of a list (0 when empty).
pub(crate) fn rms(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

/// Median of a list (0 when empty); sorts it.
pub(crate) fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(|a, b| a.total_cmp(b));
    values[values.len() / 2]
}

/// Per-joint RMS and largest magnitude over a window.
pub(crate) struct JointStats {
    sum_sq: Vec<f64>,
    pub max_abs: Vec<f64>,
    count: usize,
}

impl JointStats {
    pub fn new(n: usize) -> Self {
        Self {
            sum_sq: vec![0.0; n],
            max_abs: vec![0.0; n],
            count: 0,
        }
    }

    pub fn add(&mut self, values: impl Iterator<Item = f64>) {
        for (i, v) in values.enumerate() {
            self.sum_sq[i] += v * v;
            self.max_abs[i] = self.max_abs[i].max(v.abs());
        }
        self.count += 1;
    }

    pub fn rms(&self) -> Vec<f64> {
        self.sum_sq
            .iter()
            .map(|s| {
                if self.count > 0 {
                    (s / self.count as f64).sqrt()
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// The observer metrics (docs/outputs.md): error in contact, estimate without contact,
/// the reference against the oracle's.
pub(crate) struct ObserverStats {
    contact_err_sq: Vec<f64>,
    contact_true_sq: Vec<f64>,
    free_sq: Vec<f64>,
    free_count: Vec<usize>,
    adm_err_sq: Vec<f64>,
    count: usize,
    pub bound_violations: usize,
}

impl ObserverStats {
    pub fn new(n: usize) -> Self {
        Self {
            contact_err_sq: vec![0.0; n],
            contact_true_sq: vec![0.0; n],
            free_sq: vec![0.0; n],
            free_count: vec![0; n],
            adm_err_sq: vec![0.0; n],
            count: 0,
            bound_violations: 0,
        }
    }

    pub fn add(
        &mut self,
        estimate: &[f64],
        truth: &[f64],
        q_r: &[f64],
        q_r_oracle: Option<&[f64]>,
    ) {
        for i in 0..estimate.len() {
            if truth[i] != 0.0 {
                self.contact_err_sq[i] += (estimate[i] - truth[i]).powi(2);
                self.contact_true_sq[i] += truth[i] * truth[i];
            } else {
                self.free_sq[i] += estimate[i] * estimate[i];
                self.free_count[i] += 1;
            }
        }
        if let Some(o) = q_r_oracle {
            for i in 0..q_r.len() {
                self.adm_err_sq[i] += (q_r[i] - o[i]).powi(2);
            }
        }
        self.count += 1;
    }

    /// Writes `external_torque_nrmse`, `false_torque_rms`, `reference_bound_violations`
    /// and, with an admittance model, `admittance_error_rms`.
    pub fn finish(&self, metrics: &mut VariantMetrics, with_admittance: bool) {
        let err: f64 = self.contact_err_sq.iter().sum();
        let truth: f64 = self.contact_true_sq.iter().sum();
        metrics.external_torque_nrmse = (truth > 0.0).then(|| (err / truth).sqrt());
        metrics.false_torque_rms = self
            .free_sq
            .iter()
            .zip(&self.free_count)
            .map(|(s, c)| if *c > 0 { (s / *c as f64).sqrt() } else { 0.0 })
            .collect();
        metrics.reference_bound_violations = self.bound_violations;
        if with_admittance {
            metrics.admittance_error_rms = Some(
                self.adm_err_sq
                    .iter()
                    .map(|s| (s / self.count.max(1) as f64).sqrt())
                    .collect(),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every metric the writer can produce is in the run-folder contract, which the report
    /// reads its units and windows from.
    #[test]
    fn every_metric_is_in_the_run_folder_contract() {
        let full = VariantMetrics {
            diverged_at: Some(1.0),
            external_torque_nrmse: Some(0.5),
            admittance_error_rms: Some(vec![0.0]),
            estimate_coverage_min: Some(1.0),
            estimate_coverage_mean: Some(1.0),
            steps_outside_training_range: Some(0),
            steps_faster_than_training: Some(0),
            observer_training: Some(ObserverTrainingMetrics {
                train_seconds: 1.0,
                observer_nodes: 1,
                validation_nrmse: vec![0.1],
                observer_model_cached: false,
                training_samples: 1,
                observer_lambda: 1e-3,
            }),
            identification: Some(IdentificationMetrics {
                identification_expected_false_torque_rms: vec![0.1],
                identification_cached: false,
            }),
            weight_norm_final: Some(BTreeMap::new()),
            gated_samples: Some(BTreeMap::new()),
            dynamic_nodes: Some(DynamicNodeMetrics {
                approx_rmse_full: 1.0,
                approx_rmse_after_discard: 1.0,
                approx_rmse_after_growth: 1.0,
                nodes_discarded: 1,
                nodes_added: 1,
                weight_norm_max: 1.0,
            }),
            hand: Some(HandMetrics {
                wrench_estimate_rmse: Some(1.0),
                wrench_estimate_nrmse: Some(0.1),
                false_force_rms: 0.1,
                contact_force_max: 1.0,
                hand_compliance_error_rms: Some(0.0),
                hand_drift_after_release: Some(0.0),
            }),
            ..VariantMetrics::default()
        };
        let keys = full.to_map();
        assert!(keys.len() > 40, "{}", keys.len());
        for key in keys.keys() {
            assert!(
                admittance_runfolder::metrics::info(key).is_some(),
                "`{key}` is written but not in admittance_runfolder::metrics"
            );
        }
    }
}
