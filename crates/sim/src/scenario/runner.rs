//! The closed loop of one scenario variant: desired trajectory -> admittance model
//! (driven by the external-torque estimate) -> controller -> plant, sampled by the
//! sensors at the control rate; with metrics and a time series.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use admittance_control::{
    true_lumped_f, Admittance, AdmittanceInput, ComputedTorqueController, ControlInput, Controller,
    GrowthRequest, HybridObserver, LearnedObserver, MomentumObserver, NetworkId, NeuralController,
    Observer, ObserverInput, PdController, StepStatus,
};
use admittance_dynamics::{forward_kinematics, Data, Model};
use serde_json::{json, Value};

use super::source::{ScenarioError, ScenarioSource};
use super::spec::{ControllerKind, ObserverKind, Scenario, Trajectory};
use crate::{Plant, Sensors};

/// What a long-running stage reports to a progress display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Simulating the closed loop of a variant (`done`/`total` in control steps).
    Simulate,
    /// Simulating free motion to collect an observer's training data (control steps).
    TrainingData,
    /// Training an observer network (`done`/`total` in phases).
    Train,
}

/// One progress report: which variant, which stage, how far.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    /// The variant being run (`"base"` without variants).
    pub variant: &'a str,
    /// The stage.
    pub stage: Stage,
    /// Units done so far.
    pub done: u64,
    /// Units in the stage.
    pub total: u64,
}

/// A progress callback (called at most about a hundred times per stage).
pub type ProgressFn = std::sync::Arc<dyn Fn(Progress<'_>) + Send + Sync>;

/// Options of a run that are not part of the scenario file.
#[derive(Clone, Default)]
pub struct RunOptions {
    /// Overrides the scenario's seed (sensor noise).
    pub seed: Option<u64>,
    /// Progress display, if any.
    pub progress: Option<ProgressFn>,
}

impl std::fmt::Debug for RunOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunOptions")
            .field("seed", &self.seed)
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

impl RunOptions {
    /// Reports progress when a callback is set.
    pub fn report(&self, variant: &str, stage: Stage, done: u64, total: u64) {
        if let Some(p) = &self.progress {
            p(Progress {
                variant,
                stage,
                done,
                total,
            });
        }
    }
}

/// The recorded time series of one variant: named columns, rows in time order.
#[derive(Clone, Debug, Default)]
pub struct TimeSeries {
    /// Column names (the CSV header).
    pub columns: Vec<String>,
    /// Rows, each `columns.len()` long.
    pub rows: Vec<Vec<f64>>,
}

impl TimeSeries {
    /// Index of a column.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
}

/// The outcome of one variant.
#[derive(Clone, Debug)]
pub struct VariantRun {
    /// Variant name (`"base"` when the file has no variants).
    pub name: String,
    /// Metrics for summary.json.
    pub metrics: BTreeMap<String, Value>,
    /// The time series.
    pub series: TimeSeries,
    /// Joint names in chain order.
    pub joints: Vec<String>,
    /// The free-motion recording (`[record] free_motion_csv = true`): one row per control
    /// sample, columns `t, q.*, qdot.*, qddot.*, tau.*` (docs/outputs.md).
    pub free_motion: Option<TimeSeries>,
    /// With dynamic nodes: the norm of each f-network node's weight row, every
    /// [`NODE_WEIGHT_INTERVAL`] seconds; columns `t, w.ID` where `ID` numbers the nodes in
    /// the order they first appeared (the initial nodes first, grown ones after), `NaN`
    /// while a node does not exist (before it is grown or after it is discarded).
    pub node_weights: Option<TimeSeries>,
    /// With a learned observer: its network on the validation data
    /// (`training::TrainedNetwork::validation_series`).
    pub observer_validation: Option<TimeSeries>,
}

/// Sampling interval (s) of [`VariantRun::node_weights`].
pub const NODE_WEIGHT_INTERVAL: f64 = 0.25;

/// Follows the f network's nodes by their centres (indices shift when nodes are
/// discarded) and samples their weight-row norms.
#[derive(Default)]
struct NodeWeightTrace {
    ids: std::collections::HashMap<Vec<u64>, usize>,
    samples: Vec<(f64, Vec<(usize, f64)>)>,
}

impl NodeWeightTrace {
    fn sample(&mut self, t: f64, layer: &admittance_control::GaussianRbfLayer) {
        let mut row = Vec::with_capacity(layer.len());
        for i in 0..layer.len() {
            let (Some(centre), Some(w)) = (layer.centre(i), layer.weight_row(i)) else {
                continue;
            };
            let key: Vec<u64> = centre.iter().map(|c| c.to_bits()).collect();
            let next = self.ids.len();
            let id = *self.ids.entry(key).or_insert(next);
            row.push((id, w.iter().map(|x| x * x).sum::<f64>().sqrt()));
        }
        self.samples.push((t, row));
    }

    fn into_series(self) -> TimeSeries {
        let count = self.ids.len();
        let mut columns = vec!["t".to_string()];
        columns.extend((0..count).map(|id| format!("w.{id}")));
        let rows = self
            .samples
            .into_iter()
            .map(|(t, values)| {
                let mut row = vec![f64::NAN; count + 1];
                row[0] = t;
                for (id, v) in values {
                    row[id + 1] = v;
                }
                row
            })
            .collect();
        TimeSeries { columns, rows }
    }
}

/// A controller of any kind, keeping the neural one reachable for its node hooks.
enum AnyController {
    Neural(Box<NeuralController>),
    Other(Box<dyn Controller>),
}

impl AnyController {
    fn as_dyn(&mut self) -> &mut dyn Controller {
        match self {
            AnyController::Neural(c) => c.as_mut(),
            AnyController::Other(c) => c.as_mut(),
        }
    }
    fn neural(&self) -> Option<&NeuralController> {
        match self {
            AnyController::Neural(c) => Some(c),
            AnyController::Other(_) => None,
        }
    }
}

fn rms(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(|a, b| a.total_cmp(b));
    values[values.len() / 2]
}

/// Per-joint accumulators of a window.
struct JointStats {
    sum_sq: Vec<f64>,
    max_abs: Vec<f64>,
    count: usize,
}

impl JointStats {
    fn new(n: usize) -> Self {
        Self {
            sum_sq: vec![0.0; n],
            max_abs: vec![0.0; n],
            count: 0,
        }
    }
    fn add(&mut self, values: impl Iterator<Item = f64>) {
        for (i, v) in values.enumerate() {
            self.sum_sq[i] += v * v;
            self.max_abs[i] = self.max_abs[i].max(v.abs());
        }
        self.count += 1;
    }
    fn rms(&self) -> Vec<f64> {
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

/// Accumulators of the observer metrics (docs/outputs.md).
struct ObserverStats {
    /// Per joint: squared estimate error while in contact (`tau_ext != 0` on that joint).
    contact_err_sq: Vec<f64>,
    /// Per joint: squared true torque while in contact.
    contact_true_sq: Vec<f64>,
    /// Per joint: squared estimate and count where the true torque is zero.
    free_sq: Vec<f64>,
    free_count: Vec<usize>,
    /// Per joint: squared `q_r - q_r(oracle)`.
    adm_err_sq: Vec<f64>,
    count: usize,
    /// Samples x joints with `q_r` outside its saturation bound (whole run).
    bound_violations: usize,
}

impl ObserverStats {
    fn new(n: usize) -> Self {
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
    fn add(&mut self, estimate: &[f64], truth: &[f64], q_r: &[f64], q_r_oracle: Option<&[f64]>) {
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
    fn insert(&self, metrics: &mut BTreeMap<String, Value>, with_admittance: bool) {
        let err: f64 = self.contact_err_sq.iter().sum();
        let truth: f64 = self.contact_true_sq.iter().sum();
        metrics.insert(
            "external_torque_nrmse".into(),
            if truth > 0.0 {
                json!((err / truth).sqrt())
            } else {
                Value::Null
            },
        );
        let free: Vec<f64> = self
            .free_sq
            .iter()
            .zip(&self.free_count)
            .map(|(s, c)| if *c > 0 { (s / *c as f64).sqrt() } else { 0.0 })
            .collect();
        metrics.insert("false_torque_rms".into(), json!(free));
        metrics.insert(
            "reference_bound_violations".into(),
            json!(self.bound_violations),
        );
        if with_admittance {
            let rms: Vec<f64> = self
                .adm_err_sq
                .iter()
                .map(|s| (s / self.count.max(1) as f64).sqrt())
                .collect();
            metrics.insert("admittance_error_rms".into(), json!(rms));
        }
    }
}

/// A controller or admittance configuration error, located at its key in the scenario
/// (`k2[1]` of `[controller.neural]` is written at `controller.neural.k2`).
fn located_config_error(
    source: &ScenarioSource,
    variant: Option<&str>,
    section: &str,
    e: &admittance_control::ConfigError,
) -> ScenarioError {
    let key: String = e.key.split('[').next().unwrap_or("").to_string();
    let path = if key.is_empty() {
        section.to_string()
    } else {
        format!("{section}.{key}")
    };
    let hint =
        Some("change the value so that it meets the stated bound (the file or --set)".to_string());
    let mut err = source.error_at(&path, variant, e.message.clone(), hint);
    if e.key.contains('[') {
        err.key = Some(format!("{section}.{}", e.key));
    }
    err
}

/// Resolves, validates and runs one variant of a scenario file.
pub fn run_variant(
    source: &ScenarioSource,
    path: &Path,
    variant: Option<&str>,
    options: &RunOptions,
) -> Result<VariantRun, ScenarioError> {
    let scenario: Scenario = source.resolve(variant)?;
    let urdf = scenario.urdf_path(path);
    let model = Model::from_urdf_file(
        &urdf,
        scenario.arm.base.as_deref(),
        scenario.arm.tip.as_deref(),
    )
    .map_err(|e| {
        source.error_at(
            "arm.urdf",
            variant,
            e.to_string(),
            Some("the path is relative to the scenario file".into()),
        )
    })?;
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let problems = scenario.validate(&joints);
    if !problems.is_empty() {
        return Err(source.invalid(variant, &problems));
    }
    let n = model.nq();
    let trajectory = Trajectory::new(&scenario.trajectory, &joints);
    let mut q_d = vec![0.0; n];
    let mut qd_d = vec![0.0; n];
    let mut qdd_d = vec![0.0; n];
    trajectory.eval(0.0, &mut q_d, &mut qd_d, &mut qdd_d);

    let mut plant_config = scenario.plant.clone();
    if plant_config.initial_q.is_empty() {
        plant_config.initial_q = q_d.clone();
    }
    if let Some(seed) = options.seed.or(scenario.seed) {
        plant_config.sensors.seed = seed;
    }
    let sim_err = |e: crate::SimError| source.error_at("plant", variant, e.to_string(), None);
    let mut plant = Plant::new(&model, &plant_config).map_err(sim_err)?;
    let mut sensors = Sensors::new(&model, &plant_config.sensors, plant_config.control_rate_hz)
        .map_err(sim_err)?;
    let dt = plant.control_dt();

    let nominal = Arc::new(model.clone());
    let ctrl_err = |e: admittance_control::ConfigError, section: &str| {
        located_config_error(source, variant, &format!("controller.{section}"), &e)
    };
    let mut controller = match scenario.controller.kind {
        ControllerKind::Neural => AnyController::Neural(Box::new(
            NeuralController::new(nominal.clone(), &scenario.controller.neural)
                .map_err(|e| ctrl_err(e, "neural"))?,
        )),
        ControllerKind::Pd => {
            let cfg = scenario.controller.pd.as_ref().expect("validated");
            AnyController::Other(Box::new(
                PdController::new(nominal.clone(), cfg).map_err(|e| ctrl_err(e, "pd"))?,
            ))
        }
        ControllerKind::ComputedTorque => {
            let cfg = scenario
                .controller
                .computed_torque
                .as_ref()
                .expect("validated");
            AnyController::Other(Box::new(
                ComputedTorqueController::new(nominal.clone(), cfg)
                    .map_err(|e| ctrl_err(e, "computed_torque"))?,
            ))
        }
    };
    let mut admittance = match &scenario.admittance {
        Some(spec) if spec.enabled => Some(
            Admittance::new(n, &spec.config)
                .map_err(|e| located_config_error(source, variant, "admittance", &e))?,
        ),
        _ => None,
    };

    // The external-torque observer (METHOD.md section 5).
    let momentum_err = |e: admittance_control::ConfigError| {
        source.error_at(
            &format!("observer.momentum.{}", e.key),
            variant,
            e.message,
            None,
        )
    };
    let nominal_observer_model = || {
        model
            .with_scaled_inertias(scenario.observer.nominal_inertia_scale)
            .map_err(|e| {
                source.error_at(
                    "observer.nominal_inertia_scale",
                    variant,
                    e.to_string(),
                    None,
                )
            })
    };
    let mut observer_metrics: BTreeMap<String, Value> = BTreeMap::new();
    let mut observer_validation = None;
    let mut observer: Option<Box<dyn Observer>> = match scenario.observer.kind {
        ObserverKind::None | ObserverKind::Oracle => None,
        ObserverKind::Momentum => Some(Box::new(
            MomentumObserver::new(
                Arc::new(nominal_observer_model()?),
                &scenario.observer.momentum,
            )
            .map_err(momentum_err)?,
        )),
        ObserverKind::Learned | ObserverKind::Hybrid => {
            let hybrid = scenario.observer.kind == ObserverKind::Hybrid;
            let nominal_model = if hybrid {
                Some(nominal_observer_model()?)
            } else {
                None
            };
            let net = super::training::observer_network(
                source,
                variant,
                &scenario,
                path,
                &joints,
                nominal_model.as_ref(),
                options,
            )?;
            observer_metrics.insert("train_seconds".into(), json!(net.train_seconds));
            observer_metrics.insert("observer_nodes".into(), json!(net.model.n_nodes()));
            observer_metrics.insert("validation_nrmse".into(), json!(net.validation_nrmse));
            observer_metrics.insert("observer_model_cached".into(), json!(net.cached));
            observer_metrics.insert("training_samples".into(), json!(net.samples));
            observer_metrics.insert("observer_lambda".into(), json!(net.lambda));
            observer_validation = net.validation_series.clone();
            let observer_err = |e: admittance_control::ConfigError| {
                source.error_at("observer.training", variant, e.to_string(), None)
            };
            match nominal_model {
                Some(nominal_model) => {
                    let momentum =
                        MomentumObserver::new(Arc::new(nominal_model), &scenario.observer.momentum)
                            .map_err(momentum_err)?;
                    Some(Box::new(
                        HybridObserver::new(momentum, net.model).map_err(observer_err)?,
                    ))
                }
                // The runner low-passes every estimate (observer.cutoff_hz): none inside.
                None => Some(Box::new(
                    LearnedObserver::new(net.model, 0.0).map_err(observer_err)?,
                )),
            }
        }
    };
    // The learned networks were trained on the filtered command one sample late (the
    // pairing with q'' of the free-motion data, docs/outputs.md); they are fed the same.
    let delayed_tau = scenario.observer.kind.is_learned();
    let mut conditioner = if scenario.observer.input_filter_hz > 0.0 && observer.is_some() {
        Some(
            crate::InputConditioner::new(
                n,
                scenario.observer.input_filter_hz,
                plant_config.control_rate_hz,
            )
            .map_err(|e| {
                source.error_at("observer.input_filter_hz", variant, e.to_string(), None)
            })?,
        )
    } else {
        None
    };
    // First-order low-pass of the estimate: alpha = dt / (dt + 1 / (2 pi f_c)).
    let estimate_alpha = if scenario.observer.cutoff_hz > 0.0 {
        dt / (dt + 1.0 / (2.0 * std::f64::consts::PI * scenario.observer.cutoff_hz))
    } else {
        1.0
    };
    let mut estimate_raw = vec![0.0; n];
    let mut observer_faults = 0usize;
    let mut oracle_admittance = match &scenario.admittance {
        Some(spec) if spec.enabled => Some(
            Admittance::new(n, &spec.config)
                .map_err(|e| located_config_error(source, variant, "admittance", &e))?,
        ),
        _ => None,
    };
    let mut observer_stats = ObserverStats::new(n);
    let mut free_motion = scenario.record.free_motion_csv.then(|| {
        let mut columns = vec!["t".to_string()];
        for prefix in ["q", "qdot", "qddot", "tau"] {
            columns.extend(joints.iter().map(|j| format!("{prefix}.{j}")));
        }
        TimeSeries {
            columns,
            rows: Vec::new(),
        }
    });
    let mut tau_filtered_prev = vec![0.0; n];

    let effort: Vec<f64> = plant.effort_limits().to_vec();
    let mut kin_data = Data::new(plant.model());
    let mut f_data = Data::new(plant.model());
    let tip = plant.model().tip_frame;

    // Dynamic nodes (experiment C).
    let dynamic = scenario.dynamic_nodes.clone();
    let mut discarded: Option<usize> = None;
    let mut growth_requested = false;
    let mut approx = [Vec::<f64>::new(), Vec::new(), Vec::new()];
    let mut f_true = vec![0.0; n];

    let steps = (scenario.duration / dt).round() as usize;
    let decimation = scenario.output.decimation;
    let mut series = TimeSeries::default();
    series.columns.push("t".into());
    for prefix in [
        "q_d",
        "q_r",
        "q",
        "qdot",
        "q_meas",
        "tau_cmd",
        "tau_applied",
        "tau_ext",
        "tau_ext_hat",
    ] {
        for j in &joints {
            series.columns.push(format!("{prefix}.{j}"));
        }
    }
    series.columns.push("ee_error".into());
    let with_f = dynamic.is_some();
    if with_f {
        for prefix in ["f", "f_hat"] {
            for j in &joints {
                series.columns.push(format!("{prefix}.{j}"));
            }
        }
    }
    if controller.neural().is_some() {
        series.columns.push("nodes.f".into());
    }

    let mut tau = vec![0.0; n];
    let mut q_meas = vec![0.0; n];
    let mut qdot_meas = vec![0.0; n];
    let mut estimate = vec![0.0; n];
    let zeros = vec![0.0; n];
    let mut q_r = vec![0.0; n];
    let mut qd_r = vec![0.0; n];
    let mut qdd_r = vec![0.0; n];
    let mut tracking = JointStats::new(n);
    let mut torque = JointStats::new(n);
    let mut estimate_error = JointStats::new(n);
    let mut ee_errors = Vec::new();
    let mut deadzone_steps = vec![0usize; n];
    let mut window_steps = 0usize;
    let mut step_times: Vec<f64> = Vec::with_capacity(steps.min(200_000));
    let timing_stride = (steps / 200_000).max(1);
    let (mut faults, mut limit_violations, mut nonfinite_torques) = (0usize, 0usize, 0usize);
    let mut max_weight_norm: f64 = 0.0;
    let mut weight_trace = dynamic.as_ref().map(|_| NodeWeightTrace::default());
    let weight_stride = ((NODE_WEIGHT_INTERVAL / dt).round() as usize).max(1);

    let variant_name = variant.unwrap_or("base");
    let progress_stride = (steps / 100).max(1);
    for k in 0..steps {
        if k % progress_stride == 0 {
            options.report(variant_name, Stage::Simulate, k as u64, steps as u64);
        }
        let t = k as f64 * dt;
        trajectory.eval(t, &mut q_d, &mut qd_d, &mut qdd_d);
        {
            let m = sensors.sample(t, plant.q(), &tau).map_err(sim_err)?;
            q_meas.copy_from_slice(&m.q);
            qdot_meas.copy_from_slice(&m.qdot);
        }
        // External-torque estimate.
        match observer.as_mut() {
            None => match scenario.observer.kind {
                ObserverKind::Oracle => estimate.copy_from_slice(plant.tau_ext()),
                _ => estimate.fill(0.0),
            },
            Some(obs) => {
                // What the sensors saw: the filtered angles with their derivatives and the
                // command through the same filter (matching delays, METHOD.md section 7).
                let m = sensors.measurement();
                let tau_in: &[f64] = if delayed_tau {
                    &tau_filtered_prev
                } else {
                    &m.tau_filtered
                };
                let input = match conditioner.as_mut() {
                    Some(c) => {
                        c.update(&m.q_filtered, tau_in);
                        ObserverInput {
                            time: t,
                            q: &c.q,
                            qdot: &c.qdot,
                            qddot: &c.qddot,
                            tau_commanded: &c.tau,
                        }
                    }
                    None => ObserverInput {
                        time: t,
                        q: &m.q_filtered,
                        qdot: &m.qdot,
                        qddot: &m.qddot,
                        tau_commanded: tau_in,
                    },
                };
                if !obs.update(&input, dt, &mut estimate_raw).is_ok() {
                    observer_faults += 1;
                }
                if t < scenario.observer.warmup {
                    estimate_raw.fill(0.0);
                }
                for (e, r) in estimate.iter_mut().zip(&estimate_raw) {
                    *e += estimate_alpha * (r - *e);
                }
            }
        }
        // Free-motion data: what the sensors saw, with the filtered command delayed by one
        // sample to match qddot's delay (METHOD.md section 7, docs/outputs.md).
        if let Some(fm) = free_motion.as_mut() {
            let m = sensors.measurement();
            let mut row = Vec::with_capacity(1 + 4 * n);
            row.push(t);
            for v in [&m.q_filtered[..], &m.qdot, &m.qddot, &tau_filtered_prev] {
                row.extend_from_slice(v);
            }
            fm.rows.push(row);
        }
        tau_filtered_prev.copy_from_slice(&sensors.measurement().tau_filtered);
        // The oracle's admittance model, run beside the variant's (admittance_error_rms).
        if let Some(adm) = oracle_admittance.as_mut() {
            let input = AdmittanceInput {
                q_d: &q_d,
                qdot_d: &qd_d,
                qddot_d: &qdd_d,
                external_torque_estimate: plant.tau_ext(),
            };
            let _ = adm.step(&input, dt);
        }
        // Compliant reference.
        match admittance.as_mut() {
            Some(adm) => {
                let input = AdmittanceInput {
                    q_d: &q_d,
                    qdot_d: &qd_d,
                    qddot_d: &qdd_d,
                    external_torque_estimate: &estimate,
                };
                let _ = adm.step(&input, dt);
                q_r.copy_from_slice(adm.q_r());
                qd_r.copy_from_slice(adm.qdot_r());
                qdd_r.copy_from_slice(adm.qddot_r());
            }
            None => {
                q_r.copy_from_slice(&q_d);
                qd_r.copy_from_slice(&qd_d);
                qdd_r.copy_from_slice(&qdd_d);
            }
        }
        // Dynamic-node events.
        if let (Some(d), AnyController::Neural(nn)) = (&dynamic, &mut controller) {
            if discarded.is_none() && t >= d.discard_time {
                discarded = Some(nn.discard(NetworkId::F, d.upsilon));
            }
            if !growth_requested && t >= d.grow_time {
                let request = GrowthRequest {
                    nodes: d.grow_nodes,
                    interval_steps: d.grow_interval_steps,
                    params: d.growth,
                };
                nn.request_growth(NetworkId::F, request).map_err(|e| {
                    source.error_at("dynamic_nodes.growth", variant, e.to_string(), None)
                })?;
                growth_requested = true;
            }
        }
        let input = ControlInput {
            time: t,
            q: &q_meas,
            qdot: &qdot_meas,
            q_ref: &q_r,
            qdot_ref: &qd_r,
            qddot_ref: &qdd_r,
            external_torque_estimate: if admittance.is_some() {
                &zeros
            } else {
                &estimate
            },
        };
        let start = Instant::now();
        let status = controller.as_dyn().step(&input, dt, &mut tau);
        let elapsed = start.elapsed().as_secs_f64();
        if k % timing_stride == 0 && step_times.len() < step_times.capacity() {
            step_times.push(elapsed * 1e6);
        }
        if matches!(status, StepStatus::Fault(_)) {
            faults += 1;
        }
        for (i, t_i) in tau.iter().enumerate() {
            if !t_i.is_finite() {
                nonfinite_torques += 1;
            } else if t_i.abs() > effort[i] * (1.0 + 1e-12) {
                limit_violations += 1;
            }
        }
        // Approximation of f (experiment C) with the controller's alpha.
        if let (Some(d), Some(nn)) = (&dynamic, controller.neural()) {
            let _ = true_lumped_f(
                plant.model(),
                &mut f_data,
                plant.q(),
                plant.qdot(),
                nn.alpha(),
                nn.alpha_dot(),
                &mut f_true,
            );
            let phase_ends = [d.discard_time, d.grow_time, scenario.duration];
            for (p, end) in phase_ends.iter().enumerate() {
                if t >= end - d.approximation_window && t < *end {
                    for (a, b) in f_true.iter().zip(nn.f_hat()) {
                        approx[p].push(a - b);
                    }
                }
            }
            max_weight_norm = max_weight_norm.max(nn.weight_norm(NetworkId::F));
            if let (Some(trace), Some(layer)) = (weight_trace.as_mut(), nn.network(NetworkId::F)) {
                if k % weight_stride == 0 {
                    trace.sample(t, layer);
                }
            }
        }

        if let Some(sat) = admittance.as_ref().and_then(|a| a.saturation()) {
            for (i, r) in q_r.iter().enumerate() {
                let (c, h) = (sat.centre()[i], sat.half_range()[i]);
                if !(*r > c - h && *r < c + h) {
                    observer_stats.bound_violations += 1;
                }
            }
        }
        plant.step_control(&tau).map_err(sim_err)?;
        let record = plant.record();
        let in_window = t >= scenario.evaluation_start;
        // Hand error by forward kinematics of the true angles against the reference.
        let _ = forward_kinematics(plant.model(), &mut kin_data, &q_r);
        let p_ref = kin_data.frame_placements[tip].translation;
        let _ = forward_kinematics(plant.model(), &mut kin_data, plant.q());
        let p = kin_data.frame_placements[tip].translation;
        let ee_error = (p - p_ref).norm();
        if in_window {
            tracking.add(q_r.iter().zip(plant.q()).map(|(r, q)| r - q));
            torque.add(tau.iter().copied());
            estimate_error.add(estimate.iter().zip(&record.tau_ext).map(|(e, t)| e - t));
            observer_stats.add(
                &estimate,
                &record.tau_ext,
                &q_r,
                oracle_admittance.as_ref().map(|a| a.q_r()),
            );
            ee_errors.push(ee_error);
            window_steps += 1;
            for (c, dz) in deadzone_steps.iter_mut().zip(&record.in_deadzone) {
                *c += *dz as usize;
            }
        }
        if k % decimation == 0 {
            let mut row = Vec::with_capacity(series.columns.len());
            row.push(t);
            for v in [
                &q_d[..],
                &q_r,
                plant.q(),
                plant.qdot(),
                &q_meas,
                &tau,
                &record.applied,
                &record.tau_ext,
                &estimate,
            ] {
                row.extend_from_slice(v);
            }
            row.push(ee_error);
            if with_f {
                row.extend_from_slice(&f_true);
                row.extend_from_slice(controller.neural().map(|c| c.f_hat()).unwrap_or(&zeros));
            }
            if let Some(nn) = controller.neural() {
                row.push(nn.node_count(NetworkId::F) as f64);
            }
            series.rows.push(row);
        }
    }

    options.report(variant_name, Stage::Simulate, steps as u64, steps as u64);
    let mut metrics = BTreeMap::new();
    metrics.insert("tracking_rmse".into(), json!(tracking.rms()));
    metrics.insert("tracking_max_abs".into(), json!(tracking.max_abs));
    metrics.insert("ee_error_rms".into(), json!(rms(&ee_errors)));
    metrics.insert(
        "ee_error_max".into(),
        json!(ee_errors.iter().cloned().fold(0.0, f64::max)),
    );
    metrics.insert("torque_rms".into(), json!(torque.rms()));
    metrics.insert("torque_max_abs".into(), json!(torque.max_abs));
    let fractions: Vec<f64> = deadzone_steps
        .iter()
        .map(|c| *c as f64 / window_steps.max(1) as f64)
        .collect();
    metrics.insert("deadzone_time_fraction".into(), json!(fractions));
    metrics.insert(
        "controller_step_median_us".into(),
        json!(median(&mut step_times)),
    );
    metrics.insert("faults".into(), json!(faults));
    metrics.insert("torque_limit_violations".into(), json!(limit_violations));
    metrics.insert("nonfinite_torques".into(), json!(nonfinite_torques));
    metrics.insert("steps".into(), json!(steps));
    metrics.insert("external_torque_rmse".into(), json!(estimate_error.rms()));
    observer_stats.insert(&mut metrics, oracle_admittance.is_some());
    metrics.insert("observer_faults".into(), json!(observer_faults));
    metrics.extend(observer_metrics);
    let mut nodes = serde_json::Map::new();
    if let Some(nn) = controller.neural() {
        for id in nn.network_ids() {
            nodes.insert(id.as_str().into(), json!(nn.node_count(id)));
        }
        let norms: serde_json::Map<String, Value> = nn
            .network_ids()
            .map(|id| (id.as_str().to_string(), json!(nn.weight_norm(id))))
            .collect();
        metrics.insert("weight_norm_final".into(), Value::Object(norms));
    }
    metrics.insert("nodes".into(), Value::Object(nodes));
    if let (Some(_), Some(nn)) = (&dynamic, controller.neural()) {
        metrics.insert("approx_rmse_full".into(), json!(rms(&approx[0])));
        metrics.insert("approx_rmse_after_discard".into(), json!(rms(&approx[1])));
        metrics.insert("approx_rmse_after_growth".into(), json!(rms(&approx[2])));
        metrics.insert("nodes_discarded".into(), json!(discarded.unwrap_or(0)));
        metrics.insert(
            "nodes_added".into(),
            json!(nn.growth_progress(NetworkId::F).added),
        );
        metrics.insert("weight_norm_max".into(), json!(max_weight_norm));
    }
    Ok(VariantRun {
        name: variant.unwrap_or("base").to_string(),
        metrics,
        series,
        joints,
        free_motion,
        node_weights: weight_trace.map(NodeWeightTrace::into_series),
        observer_validation,
    })
}
