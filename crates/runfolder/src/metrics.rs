//! The metrics of `summary.json`, one entry per variant (docs/outputs.md, "Metrics"): the
//! names the writer uses and the units, shapes and windows the report prints.

/// The samples a metric is computed over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Window {
    /// The evaluation window `[evaluation_start, duration]`.
    Evaluation,
    /// Every control step of the run.
    WholeRun,
    /// The samples of the evaluation window in contact (the true external torque or force
    /// is non-zero).
    Contact,
    /// The samples of the evaluation window without contact.
    NoContact,
    /// The observer's validation data.
    Validation,
    /// The last `approximation_window` seconds of each phase (dynamic nodes).
    Phases,
    /// Not a window: a property of the run (a count, a time, a setting).
    Run,
}

impl Window {
    /// How the report names the window.
    pub fn describe(self) -> &'static str {
        match self {
            Window::Evaluation => "evaluation window",
            Window::WholeRun => "whole run",
            Window::Contact => "in contact",
            Window::NoContact => "without contact",
            Window::Validation => "validation data",
            Window::Phases => "end of each phase",
            Window::Run => "",
        }
    }
}

/// One metric: its name in `summary.json`, unit, shape and window.
#[derive(Clone, Copy, Debug)]
pub struct Metric {
    /// Key in a variant's object.
    pub name: &'static str,
    /// Unit (`""` for a pure number or a count).
    pub unit: &'static str,
    /// One value per joint (a list in joint order).
    pub per_joint: bool,
    /// The samples it is computed over.
    pub window: Window,
    /// One line for the report.
    pub meaning: &'static str,
}

macro_rules! metrics {
    ($($konst:ident = $name:literal, $unit:literal, $per_joint:literal, $window:ident, $meaning:literal;)*) => {
        $(
            #[doc = concat!("`", $name, "`: ", $meaning)]
            pub const $konst: &str = $name;
        )*
        /// Every metric, in the order the report lists them.
        pub const ALL: &[Metric] = &[
            $(Metric { name: $name, unit: $unit, per_joint: $per_joint, window: Window::$window, meaning: $meaning },)*
        ];
    };
}

metrics! {
    DIVERGED = "diverged", "", false, Run, "the simulation or an estimate became non-finite or left physical bounds; the variant stopped there";
    DIVERGED_AT = "diverged_at", "s", false, Run, "when the variant diverged (null if it did not)";
    TRACKING_RMSE = "tracking_rmse", "rad", true, Evaluation, "RMS of q_r - q (reference against the true angle)";
    TRACKING_MAX_ABS = "tracking_max_abs", "rad", true, Evaluation, "largest |q_r - q|";
    EE_ERROR_RMS = "ee_error_rms", "m", false, Evaluation, "RMS hand position error (forward kinematics of q against q_r)";
    EE_ERROR_MAX = "ee_error_max", "m", false, Evaluation, "largest hand position error";
    TORQUE_RMS = "torque_rms", "N m", true, Evaluation, "RMS commanded torque";
    TORQUE_MAX_ABS = "torque_max_abs", "N m", true, Evaluation, "largest commanded torque";
    DEADZONE_TIME_FRACTION = "deadzone_time_fraction", "", true, Evaluation, "share of control periods whose command fell inside the deadzone";
    Q_LIMIT_VIOLATION_FRACTION = "q_limit_violation_fraction", "", true, WholeRun, "share of time the true angle is outside the joint's limits";
    TORQUE_SATURATION_FRACTION = "torque_saturation_fraction", "", true, WholeRun, "share of time the command sits at the effort limit";
    ESTIMATE_SATURATION_FRACTION = "estimate_saturation_fraction", "", true, WholeRun, "share of time the external-torque estimate exceeds the effort limit";
    EXTERNAL_TORQUE_NRMSE = "external_torque_nrmse", "", false, Contact, "estimate error over the RMS true external torque, pooled over the joints in contact";
    EXTERNAL_TORQUE_RMSE = "external_torque_rmse", "N m", true, Evaluation, "RMS of tau_ext_hat - tau_ext";
    FALSE_TORQUE_RMS = "false_torque_rms", "N m", true, NoContact, "RMS estimate where the joint's true external torque is zero";
    WRENCH_ESTIMATE_RMSE = "wrench_estimate_rmse", "N", false, Contact, "RMS error of the estimated hand force (J^+T tau_ext_hat) against the true contact force";
    WRENCH_ESTIMATE_NRMSE = "wrench_estimate_nrmse", "", false, Contact, "wrench_estimate_rmse over the RMS true contact force";
    FALSE_FORCE_RMS = "false_force_rms", "N", false, NoContact, "RMS estimated hand force while nothing touches the hand";
    CONTACT_FORCE_MAX = "contact_force_max", "N", false, Evaluation, "largest true contact force on the hand";
    HAND_COMPLIANCE_ERROR_RMS = "hand_compliance_error_rms", "m", false, Evaluation, "RMS distance of the hand from where it is in the oracle variant";
    HAND_DRIFT_AFTER_RELEASE = "hand_drift_after_release", "m", false, Run, "how far the hand moves in the last second of a hand-guiding run, after the push ended";
    ADMITTANCE_ERROR_RMS = "admittance_error_rms", "rad", true, Evaluation, "RMS of q_r - q_r(oracle): the compliant reference against one driven by the true external torque";
    REFERENCE_BOUND_VIOLATIONS = "reference_bound_violations", "", false, WholeRun, "samples x joints with q_r outside its saturation bound";
    FAULTS = "faults", "", false, WholeRun, "control steps with a controller fault (safe hold applied)";
    STALE_MEASUREMENTS = "stale_measurements", "", false, WholeRun, "control steps on which some joint's encoder reading was stale (frozen or dropped)";
    OBSERVER_FAULTS = "observer_faults", "", false, WholeRun, "observer updates that reported a fault";
    STEPS_OUTSIDE_TRAINING_RANGE = "steps_outside_training_range", "", false, WholeRun, "control steps with some joint's angle outside the observer's identification's training range";
    STEPS_FASTER_THAN_TRAINING = "steps_faster_than_training", "", false, WholeRun, "control steps with some joint faster than the observer's identification was fitted at";
    GATED_SAMPLES = "gated_samples", "", false, WholeRun, "samples the plausibility gates refused, by the gate of the first refused value (angle, jump, torque)";
    TORQUE_LIMIT_VIOLATIONS = "torque_limit_violations", "", false, WholeRun, "commands beyond the effort limit (must be 0)";
    NONFINITE_TORQUES = "nonfinite_torques", "", false, WholeRun, "commands that were not finite (must be 0)";
    CONTROLLER_STEP_MEDIAN_US = "controller_step_median_us", "us", false, WholeRun, "median wall time of one controller step";
    STEPS = "steps", "", false, Run, "control steps simulated";
    NODES = "nodes", "", false, Run, "final node count per network";
    WEIGHT_NORM_FINAL = "weight_norm_final", "", false, Run, "Frobenius norm of each network's weights at the end";
    APPROX_RMSE_FULL = "approx_rmse_full", "N m", false, Phases, "RMS of f - f_hat before the discard, all nodes";
    APPROX_RMSE_AFTER_DISCARD = "approx_rmse_after_discard", "N m", false, Phases, "RMS of f - f_hat before growth, after the discard";
    APPROX_RMSE_AFTER_GROWTH = "approx_rmse_after_growth", "N m", false, Phases, "RMS of f - f_hat at the end, after growth";
    NODES_DISCARDED = "nodes_discarded", "", false, Run, "nodes removed at the discard";
    NODES_ADDED = "nodes_added", "", false, Run, "nodes grown";
    WEIGHT_NORM_MAX = "weight_norm_max", "", false, WholeRun, "largest f-network weight norm";
    VALIDATION_NRMSE = "validation_nrmse", "", true, Validation, "the observer network's RMSE over the standard deviation of its target";
    TRAIN_SECONDS = "train_seconds", "s", false, Run, "wall time of the network fit (of the original fit when cached)";
    OBSERVER_NODES = "observer_nodes", "", false, Run, "Gaussian nodes of the observer network";
    OBSERVER_LAMBDA = "observer_lambda", "", false, Run, "chosen ridge parameter";
    OBSERVER_MODEL_CACHED = "observer_model_cached", "", false, Run, "whether the network came from the cache";
    TRAINING_SAMPLES = "training_samples", "", false, Run, "training rows";
    ESTIMATE_COVERAGE_MIN = "estimate_coverage_min", "", false, Evaluation, "lowest coverage of the hybrid observer's input by its network's training data (1 inside, 0 far outside)";
    ESTIMATE_COVERAGE_MEAN = "estimate_coverage_mean", "", false, Evaluation, "mean coverage of the hybrid observer's input by its network's training data";
    IDENTIFICATION_EXPECTED_FALSE_TORQUE_RMS = "identification_expected_false_torque_rms", "N m", true, Validation, "the identified model's RMS false torque on the validation data, free motion it was not fitted on";
    IDENTIFICATION_CACHED = "identification_cached", "", false, Run, "whether the identification came from the cache";
    CONTACT_PROMISED_FALSE_ALARMS_PER_HOUR = "contact_promised_false_alarms_per_hour", "1/h", false, Run, "the contact floor's promise: false contact events per hour ([contact] false_alarms_per_hour)";
    CONTACT_THRESHOLDS = "contact_thresholds", "N m", true, Run, "the contact floor's contact level at rest (it grows with speed and acceleration)";
    COLLISION_THRESHOLDS = "collision_thresholds", "N m", true, Run, "the contact floor's collision level at rest";
    CONTACT_UNTOUCHED_S = "contact_untouched_s", "s", false, NoContact, "time nothing touched the arm (outside every push and the 50 ms after it)";
    CONTACT_FALSE_EVENTS = "contact_false_events", "", false, NoContact, "contact events raised while nothing touched the arm";
    COLLISION_FALSE_EVENTS = "collision_false_events", "", false, NoContact, "collision events raised while nothing touched the arm";
    CONTACT_FALSE_ALARMS_PER_HOUR = "contact_false_alarms_per_hour", "1/h", false, NoContact, "contact_false_events per hour of untouched time, against the promise";
    CONTACT_PUSHES = "contact_pushes", "", false, Contact, "pushes (stretches of non-zero true external torque)";
    CONTACT_PUSHES_DETECTED = "contact_pushes_detected", "", false, Contact, "pushes flagged as contact during them or within 50 ms after";
    CONTACT_PUSHES_BY_SIZE = "contact_pushes_by_size", "", false, Contact, "pushes by peak |true torque| / contact level over the joints";
    CONTACT_DETECTED_BY_SIZE = "contact_detected_by_size", "", false, Contact, "share of the pushes of each size flagged as contact";
    CONTACT_OVER_TWICE = "contact_over_twice", "", false, Contact, "pushes whose true torque exceeded twice a joint's contact level";
    CONTACT_OVER_TWICE_WITHIN_50MS = "contact_over_twice_within_50ms", "", false, Contact, "of those, flagged within 50 ms of the crossing";
    CONTACT_DELAY_MEDIAN_S = "contact_delay_median_s", "s", false, Contact, "median time from the 2x crossing to the contact flag";
    CONTACT_DELAY_MAX_S = "contact_delay_max_s", "s", false, Contact, "largest time from the 2x crossing to the contact flag";
    CONTACT_ISOLATION = "contact_isolation", "", false, Contact, "share of the detected pushes whose touched part of the chain the detector named (no earlier than the last joint above its level, no later than the last joint the push loads)";
    CONTACT_ISOLATION_STRICT = "contact_isolation_strict", "", false, Contact, "share of the detected pushes where the detector named exactly the last joint above its level";
    REFERENCE_OFFSET_MAX_ABS = "reference_offset_max_abs", "rad", true, Evaluation, "largest |q_r - q_d|: with nobody touching the arm, the admittance's drift";
}

/// The entry of a metric, by name.
pub fn info(name: &str) -> Option<&'static Metric> {
    ALL.iter().find(|m| m.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique() {
        for (i, a) in ALL.iter().enumerate() {
            assert!(ALL[i + 1..].iter().all(|b| b.name != a.name), "{}", a.name);
        }
        assert_eq!(info(TRACKING_RMSE).map(|m| m.unit), Some("rad"));
    }
}
