//! The networks of the learned observers (`observer.kind = "learned"` or `"hybrid"`),
//! obtained at the start of a run: from the cache when the data and every setting match,
//! otherwise trained on free-motion data (docs/method.md section 5) that is either simulated
//! from a data scenario or read from a recorded CSV file (docs/outputs.md).
//!
//! What the network learns:
//! - `learned`: the free-motion torque `tau(q, q', q'')` (the paper's eq. 19 observer);
//! - `hybrid`: what the momentum observer's nominal model misses,
//!   `delta = tau - RNEA_nominal(q, q', q'')` (`admittance_control::HybridObserver`).

mod cache;
mod data;
mod identified;

pub(crate) use identified::{identified_nominal, IdentifiedNominal};

use std::path::Path;
use std::time::Instant;

use admittance_dynamics::{Identification, Model};
use admittance_learning::broad::{
    check_budget, fit, fnv1a64, ArmIdentity, BroadConfig, BroadModel, DataSettings, Dataset,
    FitSize, FrictionFeatures, TrainingTarget, ValidationSplit, WidthRule,
};

use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::progress::{RunOptions, Stage};
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
use admittance_loop::ObserverKind;

use crate::spec::Scenario;
use cache::{cache_dir, entry_paths, read_cache, write_cache, CACHE_FORMAT_VERSION};
use data::{arrays, data_source, load_data};

/// Runs a data scenario (its source and file) and returns its joints and its free-motion
/// recording: the runner, passed in so that training does not depend on it.
pub(crate) type SimulateData<'a> =
    &'a dyn Fn(
        &ScenarioSource,
        &Path,
        &RunOptions,
    ) -> Result<(Vec<String>, Option<TimeSeries>), ScenarioError>;

/// Free-motion data named by the scenario at `key` (a data scenario, simulated now or
/// recalled, or a CSV), with the arm's joints in chain order.
pub(crate) fn free_motion_data(
    ctx: &Ctx<'_>,
    scenario_file: &Path,
    key: &'static str,
    given: &Path,
    arm_joints: &[String],
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<std::sync::Arc<crate::FreeMotionData>, ScenarioError> {
    let source = data_source(ctx, scenario_file, key, given)?;
    load_data(ctx, &source, arm_joints, options, simulate)
}

/// A network ready for an observer, with how it was obtained.
#[derive(Clone, Debug)]
pub struct TrainedNetwork {
    /// The network.
    pub model: BroadModel,
    /// Wall time of the fit (features, Gram, solves, validation) when it was trained; the
    /// recorded time of the original fit when it came from the cache.
    pub train_seconds: f64,
    /// Per-joint NRMSE of the network's target on the validation data (RMSE over the
    /// standard deviation of the target).
    pub validation_nrmse: Vec<f64>,
    /// Training rows.
    pub samples: usize,
    /// Validation rows.
    pub validation_samples: usize,
    /// Chosen (absolute) ridge parameter.
    pub lambda: f64,
    /// Whether it came from the cache.
    pub cached: bool,
    /// The network on the validation data (the paper's Fig 15), every
    /// [`VALIDATION_DECIMATION`]-th sample: columns `t`, `target.JOINT` (what the network
    /// learns: the torque for `learned`, the nominal model's residual for `hybrid`) and
    /// `prediction.JOINT`.
    pub validation_series: Option<TimeSeries>,
}

/// Decimation of [`TrainedNetwork::validation_series`].
pub const VALIDATION_DECIMATION: usize = 10;

fn validation_series(
    model: &BroadModel,
    t: &[f64],
    x: &[f64],
    y: &[f64],
    joints: &[String],
) -> Option<TimeSeries> {
    use admittance_runfolder::columns as col;
    let n = joints.len();
    let mut columns = vec![col::TIME.to_string()];
    columns.extend(col::per_joint(col::VALIDATION_TARGET, joints));
    columns.extend(col::per_joint(col::VALIDATION_PREDICTION, joints));
    // The angles too: Fig 14 draws the validation trajectory from them.
    columns.extend(col::per_joint(col::POSITION, joints));
    let mut ws = model.workspace();
    let mut out = vec![0.0; n];
    let mut rows = Vec::with_capacity(t.len() / VALIDATION_DECIMATION + 1);
    for k in (0..t.len()).step_by(VALIDATION_DECIMATION) {
        model
            .predict_into(&x[3 * n * k..3 * n * (k + 1)], &mut out, &mut ws)
            .ok()?;
        let mut row = Vec::with_capacity(1 + 3 * n);
        row.push(t[k]);
        row.extend_from_slice(&y[n * k..n * (k + 1)]);
        row.extend_from_slice(&out);
        row.extend_from_slice(&x[3 * n * k..3 * n * k + n]);
        rows.push(row);
    }
    Some(TimeSeries { columns, rows })
}

/// The model whose residual a hybrid's network learns: the momentum observer's nominal
/// model.
pub(crate) enum Nominal<'a> {
    /// The URDF with its inertias scaled by `observer.nominal_inertia_scale`.
    Urdf(&'a Model),
    /// An identification (`[observer.training] identify = true`).
    Identified(&'a IdentifiedNominal),
}

impl Nominal<'_> {
    fn identification(&self) -> Identification {
        match self {
            // A URDF model is an identification without joint terms: one residual rule.
            Nominal::Urdf(model) => Identification::from_model((*model).clone()),
            Nominal::Identified(nominal) => nominal.identification.clone(),
        }
    }
}

/// The network of a learned or hybrid observer, from the cache or trained now. `nominal`
/// is the momentum observer's nominal model for `hybrid`.
pub(crate) fn observer_network(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    scenario_file: &Path,
    arm: &Model,
    nominal: Option<Nominal<'_>>,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<TrainedNetwork, ScenarioError> {
    let variant = ctx.variant;
    let Some(spec) = scenario.observer.training.as_ref() else {
        return Err(ctx.err("observer.kind", "needs an [observer.training] table", None));
    };
    let arm_joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let arm_joints = &arm_joints[..];
    let n = arm_joints.len();
    let train_src = data_source(ctx, scenario_file, "observer.training.data", &spec.data)?;
    let val_src = data_source(
        ctx,
        scenario_file,
        "observer.training.validation",
        &spec.validation,
    )?;
    let hybrid = scenario.observer.kind == ObserverKind::Hybrid;
    let config = BroadConfig {
        nodes: spec.nodes,
        friction: FrictionFeatures::for_observer(
            n,
            spec.friction_features,
            Some(spec.friction_scales.clone()),
        ),
        seed: spec.seed,
        widths: WidthRule::Knn {
            k: spec.width_neighbours,
            scale: spec.width_scale,
        },
        // The hybrid's residual keeps the nominal model alone where it does not pay; a
        // validation source that is the training data is no evidence of other motion
        // (issue 30): every output is zero, the hybrid is the momentum observer.
        zero_unhelpful_outputs: hybrid,
        zero_all_outputs: hybrid && train_src.identity == val_src.identity,
        ..BroadConfig::default()
    };
    // The key: data identities, the target, every fit setting.
    let target = match (hybrid, &nominal) {
        (true, Some(Nominal::Urdf(_))) => {
            format!("hybrid:{}", scenario.observer.nominal_inertia_scale)
        }
        (true, Some(Nominal::Identified(i))) => format!("hybrid-identified:{:016x}", i.checksum),
        _ => "learned".to_string(),
    };
    let key_text = format!(
        "v{CACHE_FORMAT_VERSION}|{:016x}|{:016x}|{target}|filter {}|{}|{}",
        train_src.identity,
        val_src.identity,
        scenario.observer.input_filter_hz,
        serde_json::to_string(&config).unwrap_or_default(),
        arm_joints.join(","),
    );
    let key = fnv1a64(key_text.as_bytes());
    let stem = format!(
        "{}-{key:016x}",
        if target == "learned" {
            "learned"
        } else {
            "hybrid"
        }
    );
    let dir = cache_dir(scenario_file, spec);
    let (model_path, meta_path) = entry_paths(&dir, &stem);
    let filter = scenario.observer.input_filter_hz;
    // What the model file records of the arm and the data, checked on a cache hit.
    let identity = ArmIdentity::new(arm_joints.iter().cloned(), arm.fingerprint());
    let settings = DataSettings {
        input_filter_hz: filter,
        validation: ValidationSplit::SeparateData,
        target: match (hybrid, &nominal) {
            (true, Some(Nominal::Urdf(_))) => TrainingTarget::NominalResidual {
                nominal_inertia_scale: scenario.observer.nominal_inertia_scale,
            },
            (true, Some(Nominal::Identified(i))) => TrainingTarget::IdentifiedResidual {
                checksum: i.checksum,
            },
            _ => TrainingTarget::FreeMotionTorque,
        },
    };
    let learn_err = |e: admittance_learning::broad::BroadError| {
        ctx.err("observer.training", e.to_string(), None)
    };
    // Refuse a fit that cannot be afforded before any data is simulated.
    if let (Some(rows), Some(val_rows)) = (train_src.rows_hint, val_src.rows_hint) {
        check_budget(
            &FitSize::fit(rows, val_rows, 3 * n, n, &config),
            &config.budget,
        )
        .map_err(|e| ctx.err("observer.training.nodes", e.to_string(), None))?;
    }
    let residual_of = nominal.as_ref().map(Nominal::identification);
    let validation = load_data(ctx, &val_src, arm_joints, options, simulate)?;
    let (xv, yv) = arrays(
        ctx,
        &validation,
        val_src.key,
        arm_joints,
        residual_of.as_ref(),
        filter,
    )?;
    if spec.cache {
        if let Some(mut hit) = read_cache(&model_path, &meta_path, &key_text, &identity, &settings)
        {
            hit.validation_series =
                validation_series(&hit.model, &validation.t, &xv, &yv, arm_joints);
            return Ok(hit);
        }
    }
    if options.cache_only {
        return Err(not_cached(
            ctx,
            "observer.training",
            "the observer's network",
        ));
    }

    let label = variant.unwrap_or("base");
    let train = load_data(ctx, &train_src, arm_joints, options, simulate)?;
    let (x, y) = arrays(
        ctx,
        &train,
        train_src.key,
        arm_joints,
        residual_of.as_ref(),
        filter,
    )?;
    let train_set = Dataset::new(&x, &y, 3 * n, n).map_err(learn_err)?;
    let val_set = Dataset::new(&xv, &yv, 3 * n, n).map_err(learn_err)?;
    options.report(label, Stage::Train, 0, 1);
    let started = Instant::now();
    let (mut model, report) = fit(&train_set, Some(&val_set), &config).map_err(learn_err)?;
    model.set_arm(identity).map_err(learn_err)?;
    model.set_data_settings(settings).map_err(learn_err)?;
    let train_seconds = started.elapsed().as_secs_f64();
    options.report(label, Stage::Train, 1, 1);
    let trained = TrainedNetwork {
        model,
        train_seconds,
        validation_nrmse: report.validation_nrmse.clone(),
        samples: report.samples,
        validation_samples: report.validation_samples,
        lambda: report.lambda,
        cached: false,
        validation_series: None,
    };
    if spec.cache {
        // A cache that cannot be written costs a retrain next time, nothing else.
        let _ = write_cache(&dir, &model_path, &meta_path, &key_text, &trained);
    }
    let mut trained = trained;
    trained.validation_series =
        validation_series(&trained.model, &validation.t, &xv, &yv, arm_joints);
    Ok(trained)
}

/// The error of a cache-only assembly (`admittance deploy`) that would have to train.
pub(crate) fn not_cached(ctx: &Ctx<'_>, key: &str, what: &str) -> ScenarioError {
    let variant = ctx
        .variant
        .map(|v| format!(" --variant {v}"))
        .unwrap_or_default();
    ctx.err(
        key,
        format!("{what} is not in the training cache, and deploy never trains"),
        Some(&format!(
            "train it first: `admittance run SCENARIO{variant}` trains and caches it (or name a trained file in observer.network / observer.identification)"
        )),
    )
}
