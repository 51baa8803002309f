//! The networks of the learned observers (`observer.kind = "learned"` or `"hybrid"`),
//! obtained at the start of a run: from the cache when the data and every setting match,
//! otherwise trained on free-motion data (METHOD.md section 5) that is either simulated
//! from a data scenario or read from a recorded CSV file (docs/outputs.md).
//!
//! What the network learns:
//! - `learned`: the free-motion torque `tau(q, q', q'')` (the paper's eq. 19 observer);
//! - `hybrid`: what the momentum observer's nominal model misses,
//!   `delta = tau - RNEA_nominal(q, q', q'')` (`admittance_control::HybridObserver`).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use admittance_dynamics::{rnea, Data, Model};
use admittance_learning::broad::{
    fit, fnv1a64, BroadConfig, BroadModel, Dataset, FrictionFeatures, WidthRule,
};
use serde_json::{json, Value};

use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::progress::{Progress, ProgressFn, RunOptions, Stage};
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
use crate::spec::{ObserverKind, Scenario, TrainingSpec};
use crate::FreeMotionData;

/// Runs a data scenario (its source and file) and returns its joints and its free-motion
/// recording: the runner, passed in so that training does not depend on it.
pub(crate) type SimulateData<'a> =
    &'a dyn Fn(
        &ScenarioSource,
        &Path,
        &RunOptions,
    ) -> Result<(Vec<String>, Option<TimeSeries>), ScenarioError>;

/// Version of the cache entries (bump when what a key stands for changes).
const CACHE_FORMAT_VERSION: u32 = 1;

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
    let n = joints.len();
    let mut columns = vec!["t".to_string()];
    columns.extend(joints.iter().map(|j| format!("target.{j}")));
    columns.extend(joints.iter().map(|j| format!("prediction.{j}")));
    let mut ws = model.workspace();
    let mut out = vec![0.0; n];
    let mut rows = Vec::with_capacity(t.len() / VALIDATION_DECIMATION + 1);
    for k in (0..t.len()).step_by(VALIDATION_DECIMATION) {
        model
            .predict_into(&x[3 * n * k..3 * n * (k + 1)], &mut out, &mut ws)
            .ok()?;
        let mut row = Vec::with_capacity(1 + 2 * n);
        row.push(t[k]);
        row.extend_from_slice(&y[n * k..n * (k + 1)]);
        row.extend_from_slice(&out);
        rows.push(row);
    }
    Some(TimeSeries { columns, rows })
}

/// Free-motion data simulated in this process, by identity (a run with several learned
/// variants simulates its data once).
static SIMULATED: Mutex<Vec<(u64, Arc<FreeMotionData>)>> = Mutex::new(Vec::new());

/// Where a data set comes from, and the hash that identifies it.
struct DataSource {
    path: PathBuf,
    simulated: bool,
    key: &'static str,
    identity: u64,
}

fn resolve(scenario_file: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        scenario_file.parent().unwrap_or(Path::new(".")).join(p)
    }
}

/// The cache folder: `ADMITTANCE_CACHE_DIR`, or `cache_dir` relative to the scenario file.
fn cache_dir(scenario_file: &Path, spec: &TrainingSpec) -> PathBuf {
    match std::env::var_os("ADMITTANCE_CACHE_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => resolve(scenario_file, &spec.cache_dir),
    }
}

fn data_source(
    ctx: &Ctx<'_>,
    scenario_file: &Path,
    key: &'static str,
    given: &Path,
) -> Result<DataSource, ScenarioError> {
    let path = resolve(scenario_file, given);
    let simulated = path.extension().is_some_and(|e| e == "toml");
    let bytes = std::fs::read(&path).map_err(|e| {
        ctx.err(
            key,
            format!("cannot read {}: {e}", path.display()),
            Some("the path is relative to the scenario file"),
        )
    })?;
    let mut identity = fnv1a64(&bytes);
    if simulated {
        // The simulated data also depend on the arm file and the program that simulates.
        let data_source = ScenarioSource::load(&path)?;
        let data_scenario: Scenario = data_source.resolve(None)?;
        let urdf = data_scenario.urdf_path(&path);
        let urdf_bytes = std::fs::read(&urdf).map_err(|e| {
            ctx.err(
                key,
                format!(
                    "{}: cannot read its URDF {}: {e}",
                    path.display(),
                    urdf.display()
                ),
                None,
            )
        })?;
        let mut ident = identity.to_le_bytes().to_vec();
        ident.extend_from_slice(&fnv1a64(&urdf_bytes).to_le_bytes());
        ident.extend_from_slice(env!("CARGO_PKG_VERSION").as_bytes());
        identity = fnv1a64(&ident);
    }
    Ok(DataSource {
        path,
        simulated,
        key,
        identity,
    })
}

/// Simulates (or recalls) the free-motion data of a data scenario.
fn simulated_data(
    ctx: &Ctx<'_>,
    data: &DataSource,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<Arc<FreeMotionData>, ScenarioError> {
    if let Ok(memo) = SIMULATED.lock() {
        if let Some((_, d)) = memo.iter().find(|(id, _)| *id == data.identity) {
            return Ok(d.clone());
        }
    }
    let source = ScenarioSource::load(&data.path)?;
    if !source.variant_names().is_empty() {
        return Err(ctx.err(
            data.key,
            format!(
                "{} has variants; a data scenario must describe one run",
                data.path.display()
            ),
            None,
        ));
    }
    let variant_label = ctx.variant.unwrap_or("base").to_string();
    let outer = options.progress.clone();
    let nested = RunOptions {
        seed: None,
        limits: options.limits,
        progress: outer.map(|p| -> ProgressFn {
            Arc::new(move |e: Progress<'_>| {
                p(Progress {
                    variant: &variant_label,
                    stage: Stage::TrainingData,
                    ..e
                })
            })
        }),
    };
    let (joints, free_motion) = simulate(&source, &data.path, &nested)?;
    let Some(series) = free_motion else {
        return Err(ctx.err(
            data.key,
            format!("{} does not record free-motion data", data.path.display()),
            Some("add [record] free_motion_csv = true to that scenario"),
        ));
    };
    let n = joints.len();
    let mut out = FreeMotionData {
        joints,
        t: Vec::with_capacity(series.rows.len()),
        q: Vec::with_capacity(series.rows.len() * n),
        qdot: Vec::with_capacity(series.rows.len() * n),
        qddot: Vec::with_capacity(series.rows.len() * n),
        tau: Vec::with_capacity(series.rows.len() * n),
    };
    // Columns: t, q.*, qdot.*, qddot.*, tau.* (runner.rs).
    for row in &series.rows {
        out.t.push(row[0]);
        out.q.extend_from_slice(&row[1..1 + n]);
        out.qdot.extend_from_slice(&row[1 + n..1 + 2 * n]);
        out.qddot.extend_from_slice(&row[1 + 2 * n..1 + 3 * n]);
        out.tau.extend_from_slice(&row[1 + 3 * n..1 + 4 * n]);
    }
    let out = Arc::new(out);
    if let Ok(mut memo) = SIMULATED.lock() {
        // Keep the training and the validation set of the latest scenario.
        if memo.len() >= 2 {
            memo.remove(0);
        }
        memo.push((data.identity, out.clone()));
    }
    Ok(out)
}

fn load_data(
    ctx: &Ctx<'_>,
    data: &DataSource,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<Arc<FreeMotionData>, ScenarioError> {
    if data.simulated {
        simulated_data(ctx, data, options, simulate)
    } else {
        FreeMotionData::load(&data.path)
            .map(Arc::new)
            .map_err(|e| ctx.err(data.key, e.to_string(), None))
    }
}

/// Inputs `[q, q', q'']` and targets (row-major) of a data set.
fn arrays(
    ctx: &Ctx<'_>,
    data: &FreeMotionData,
    key: &str,
    arm_joints: &[String],
    nominal: Option<&Model>,
    input_filter_hz: f64,
) -> Result<(Vec<f64>, Vec<f64>), ScenarioError> {
    if data.joints != arm_joints {
        return Err(ctx.err(
            key,
            format!(
                "the data's joints [{}] are not the arm's [{}] (chain order)",
                data.joints.join(", "),
                arm_joints.join(", ")
            ),
            None,
        ));
    }
    let n = data.dof();
    let (x, mut y) =
        crate::free_motion::observer_training_arrays(data, input_filter_hz).map_err(|e| {
            ctx.err(
                "observer.input_filter_hz",
                format!("with the data of {key}: {e}"),
                None,
            )
        })?;
    if let Some(model) = nominal {
        let mut d = Data::new(model);
        for k in 0..data.len() {
            let r = k * n..(k + 1) * n;
            let row = &x[3 * k * n..3 * (k + 1) * n];
            let tau_model = rnea(model, &mut d, &row[..n], &row[n..2 * n], &row[2 * n..])
                .map_err(|e| ctx.err(key, format!("nominal model: {e}"), None))?;
            for (yi, m) in y[r].iter_mut().zip(tau_model.iter()) {
                *yi -= m;
            }
        }
    }
    Ok((x, y))
}

fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}

/// The network of a learned or hybrid observer, from the cache or trained now. `nominal`
/// is the momentum observer's nominal model for `hybrid`.
pub(crate) fn observer_network(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    scenario_file: &Path,
    arm_joints: &[String],
    nominal: Option<&Model>,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<TrainedNetwork, ScenarioError> {
    let variant = ctx.variant;
    let Some(spec) = scenario.observer.training.as_ref() else {
        return Err(ctx.err("observer.kind", "needs an [observer.training] table", None));
    };
    let n = arm_joints.len();
    let train_src = data_source(ctx, scenario_file, "observer.training.data", &spec.data)?;
    let val_src = data_source(
        ctx,
        scenario_file,
        "observer.training.validation",
        &spec.validation,
    )?;
    let config = BroadConfig {
        nodes: spec.nodes,
        friction: if spec.friction_features {
            FrictionFeatures {
                columns: (n..2 * n).collect(),
                scales: spec.friction_scales.clone(),
            }
        } else {
            FrictionFeatures::none()
        },
        seed: spec.seed,
        widths: WidthRule::Knn {
            k: spec.width_neighbours,
            scale: spec.width_scale,
        },
        ..BroadConfig::default()
    };
    // The key: data identities, the target, every fit setting.
    let target = match (scenario.observer.kind, nominal) {
        (ObserverKind::Hybrid, Some(_)) => {
            format!("hybrid:{}", scenario.observer.nominal_inertia_scale)
        }
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
    let model_path = dir.join(format!("{stem}.broad"));
    let meta_path = dir.join(format!("{stem}.json"));
    let filter = scenario.observer.input_filter_hz;
    let validation = load_data(ctx, &val_src, options, simulate)?;
    let (xv, yv) = arrays(ctx, &validation, val_src.key, arm_joints, nominal, filter)?;
    if spec.cache {
        if let Some(mut hit) = read_cache(&model_path, &meta_path, &key_text) {
            hit.validation_series =
                validation_series(&hit.model, &validation.t, &xv, &yv, arm_joints);
            return Ok(hit);
        }
    }

    let label = variant.unwrap_or("base");
    let train = load_data(ctx, &train_src, options, simulate)?;
    let (x, y) = arrays(ctx, &train, train_src.key, arm_joints, nominal, filter)?;
    let learn_err = |e: admittance_learning::broad::BroadError| {
        ctx.err("observer.training", e.to_string(), None)
    };
    let train_set = Dataset::new(&x, &y, 3 * n, n).map_err(learn_err)?;
    let val_set = Dataset::new(&xv, &yv, 3 * n, n).map_err(learn_err)?;
    options.report(label, Stage::Train, 0, 1);
    let started = Instant::now();
    let (model, report) = fit(&train_set, Some(&val_set), &config).map_err(learn_err)?;
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

fn read_cache(model_path: &Path, meta_path: &Path, key_text: &str) -> Option<TrainedNetwork> {
    let meta: Value = serde_json::from_slice(&std::fs::read(meta_path).ok()?).ok()?;
    if meta.get("format")?.as_str()? != "admittance-observer-cache"
        || meta.get("format_version")?.as_u64()? != CACHE_FORMAT_VERSION as u64
        || meta.get("key")?.as_str()? != key_text
    {
        return None;
    }
    // A corrupted or truncated model file fails its checksum: retrain.
    let model = BroadModel::load(model_path).ok()?;
    let nrmse: Vec<f64> = meta
        .get("validation_nrmse")?
        .as_array()?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    Some(TrainedNetwork {
        model,
        train_seconds: meta.get("train_seconds")?.as_f64()?,
        validation_nrmse: nrmse,
        samples: meta.get("samples")?.as_u64()? as usize,
        validation_samples: meta.get("validation_samples")?.as_u64()? as usize,
        lambda: meta.get("lambda")?.as_f64()?,
        cached: true,
        validation_series: None,
    })
}

fn write_cache(
    dir: &Path,
    model_path: &Path,
    meta_path: &Path,
    key_text: &str,
    t: &TrainedNetwork,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    t.model.save(model_path).map_err(|e| e.to_string())?;
    let meta = json!({
        "format": "admittance-observer-cache",
        "format_version": CACHE_FORMAT_VERSION,
        "key": key_text,
        "train_seconds": t.train_seconds,
        "validation_nrmse": t.validation_nrmse,
        "samples": t.samples,
        "validation_samples": t.validation_samples,
        "lambda": t.lambda,
    });
    write_atomic(
        meta_path,
        serde_json::to_string_pretty(&meta)
            .unwrap_or_default()
            .as_bytes(),
    )
    .map_err(|e| e.to_string())
}
