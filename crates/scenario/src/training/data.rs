//! The free-motion data a learned observer is trained on: a data scenario simulated in
//! this process (once per run for both the training and the validation set) or a recorded
//! CSV file, with the identity that keys the cache.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use admittance_dynamics::Identification;
use admittance_learning::broad::fnv1a64;

use super::SimulateData;
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::progress::{Progress, ProgressFn, RunOptions, Stage};
use crate::source::ScenarioSource;
use crate::spec::Scenario;
use crate::FreeMotionData;

/// Free-motion data simulated in this process, by identity (a run with several learned
/// variants simulates its data once).
static SIMULATED: Mutex<Vec<(u64, Arc<FreeMotionData>)>> = Mutex::new(Vec::new());

/// Where a data set comes from, and the hash that identifies it.
pub(super) struct DataSource {
    pub path: PathBuf,
    pub simulated: bool,
    pub key: &'static str,
    pub identity: u64,
    /// Rows it will have, known before loading for a data scenario (duration x control
    /// rate), so that a fit that cannot be afforded is refused before the simulation.
    pub rows_hint: Option<usize>,
}

pub(super) fn resolve(scenario_file: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        scenario_file.parent().unwrap_or(Path::new(".")).join(p)
    }
}

pub(super) fn data_source(
    ctx: &Ctx<'_>,
    scenario_file: &Path,
    key: &'static str,
    given: &Path,
) -> Result<DataSource, ScenarioError> {
    let path = resolve(scenario_file, given);
    let simulated = path.extension().is_some_and(|e| e == "toml");
    let limit = if simulated {
        admittance_files::TEXT_LIMIT
    } else {
        admittance_files::DATA_LIMIT
    };
    let bytes = admittance_files::read_regular(&path, limit).map_err(|e| {
        ctx.err(
            key,
            format!("cannot read {}: {e}", path.display()),
            Some("the path is relative to the scenario file"),
        )
    })?;
    let mut identity = fnv1a64(&bytes);
    let mut rows_hint = None;
    if simulated {
        // The simulated data also depend on the arm file and the program that simulates.
        let data_source = ScenarioSource::load(&path)?;
        let data_scenario: Scenario = data_source.resolve(None)?;
        let rows = data_scenario.duration * data_scenario.plant.control_rate_hz;
        rows_hint = (rows.is_finite() && rows >= 0.0)
            .then_some(rows.round().min(usize::MAX as f64) as usize);
        let urdf = data_scenario.urdf_path(&path);
        let urdf_bytes = admittance_files::read_regular(&urdf, admittance_files::TEXT_LIMIT)
            .map_err(|e| {
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
        rows_hint,
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
        cache_only: options.cache_only,
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
        derived: Vec::new(),
        unwrapped: Vec::new(),
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

pub(super) fn load_data(
    ctx: &Ctx<'_>,
    data: &DataSource,
    arm_joints: &[String],
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<Arc<FreeMotionData>, ScenarioError> {
    if data.simulated {
        simulated_data(ctx, data, options, simulate)
    } else {
        // The arm's joints, in chain order, whatever the file's column order.
        FreeMotionData::load_joints(&data.path, arm_joints)
            .map(Arc::new)
            .map_err(|e| ctx.err(data.key, e.to_string(), None))
    }
}

/// Inputs `[q, q', q'']` and targets (row-major) of a data set.
pub(super) fn arrays(
    ctx: &Ctx<'_>,
    data: &FreeMotionData,
    key: &str,
    arm_joints: &[String],
    residual_of: Option<&Identification>,
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
    let (x, mut y) =
        crate::free_motion::observer_training_arrays(data, input_filter_hz).map_err(|e| {
            ctx.err(
                "observer.input_filter_hz",
                format!("with the data of {key}: {e}"),
                None,
            )
        })?;
    if let Some(nominal) = residual_of {
        nominal
            .subtract_from(&x, &mut y)
            .map_err(|e| ctx.err(key, format!("nominal model: {e}"), None))?;
    }
    Ok((x, y))
}
