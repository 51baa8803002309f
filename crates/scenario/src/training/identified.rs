//! The identified nominal model of `[observer.training] identify = true` (docs/method.md
//! section 8): the arm's inertial parameters and joint terms fitted on the scenario's
//! free-motion training data, every setting chosen on its validation data (another
//! excitation), written as an identification file into the training cache folder. The
//! momentum observer runs on it, and the hybrid's network learns its residual.

use std::collections::BTreeMap;
use std::path::PathBuf;

use admittance_dynamics::{identify, Identification, IdentificationSettings, Model};
use admittance_learning::broad::fnv1a64;

use super::data::{data_source, load_data};
use super::SimulateData;
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::identify_recording::ConditionedSamples;
use crate::progress::{RunOptions, Stage};
use crate::spec::Scenario;

/// Version of what an identification cache key stands for (bump when it changes; 2: the
/// convex physical fit of issue 30, whose results differ from the first fit's; 3: springs
/// kept within the effort limit over the joint's range; 4: springs continued along their
/// tangent beyond the training range; 5: the training speeds recorded, which the loop flags
/// motion beyond; 6: the fit regresses on a zero-phase smoothed acceleration; 7: the
/// acceleration's mean square recorded, over which predictions raise the acceleration gain).
const IDENTIFICATION_KEY_VERSION: u32 = 7;

/// An identification of the scenario's arm, and the file the loop loads it from.
pub struct IdentifiedNominal {
    /// The identification file (in the training cache folder).
    pub path: PathBuf,
    /// The identification.
    pub identification: Identification,
    /// FNV-1a 64 of the file's bytes: the hybrid's network records which residual it learned.
    pub checksum: u64,
    /// Whether it was read from an earlier run instead of fitted now.
    pub cached: bool,
}

/// The identification of `arm` from the scenario's training data (validation: its
/// validation data), read back from the cache folder when the data, the filter and the
/// arm are the same, else fitted now and written there.
pub(crate) fn identified_nominal(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    scenario_file: &std::path::Path,
    arm: &Model,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<IdentifiedNominal, ScenarioError> {
    let Some(spec) = scenario.observer.training.as_ref() else {
        return Err(ctx.err(
            "observer.training.identify",
            "needs an [observer.training] table",
            None,
        ));
    };
    let arm_joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let train_src = data_source(ctx, scenario_file, "observer.training.data", &spec.data)?;
    let val_src = data_source(
        ctx,
        scenario_file,
        "observer.training.validation",
        &spec.validation,
    )?;
    let filter = scenario.observer.input_filter_hz;
    let settings = IdentificationSettings::default();
    let key_text = format!(
        "identification v{IDENTIFICATION_KEY_VERSION}|{:016x}|{:016x}|filter {filter}|{settings:?}|{:016x}|{}",
        train_src.identity,
        val_src.identity,
        arm.fingerprint(),
        arm_joints.join(","),
    );
    let key = fnv1a64(key_text.as_bytes());
    let dir = super::cache::cache_dir(scenario_file, spec);
    let path = dir.join(format!("identification-{key:016x}.json"));
    if spec.cache {
        if let Some(hit) = cached(&path, arm, &key_text) {
            return Ok(hit);
        }
    }
    if options.cache_only {
        return Err(super::not_cached(
            ctx,
            "observer.training.identify",
            "the identification",
        ));
    }
    let key_err = |message: String| ctx.err("observer.training.identify", message, None);
    let train = load_data(ctx, &train_src, &arm_joints, options, simulate)?;
    let validation = load_data(ctx, &val_src, &arm_joints, options, simulate)?;
    let train = ConditionedSamples::new(&train, filter)
        .map_err(|e| key_err(format!("with the data of observer.training.data: {e}")))?;
    let validation = ConditionedSamples::new(&validation, filter).map_err(|e| {
        key_err(format!(
            "with the data of observer.training.validation: {e}"
        ))
    })?;
    let label = ctx.variant.unwrap_or("base");
    options.report(label, Stage::Train, 0, 1);
    let identification = identify(
        arm,
        &train.samples(),
        Some(&validation.samples()),
        &settings,
    )
    .map_err(|e| key_err(e.to_string()))?;
    options.report(label, Stage::Train, 1, 1);
    std::fs::create_dir_all(&dir).map_err(|e| {
        key_err(format!(
            "cannot create the cache folder {}: {e}",
            dir.display()
        ))
    })?;
    let mut data = BTreeMap::new();
    data.insert("cache_key".to_string(), key_text.into());
    data.insert(
        "training".to_string(),
        train_src.path.display().to_string().into(),
    );
    data.insert(
        "validation".to_string(),
        val_src.path.display().to_string().into(),
    );
    data.insert("input_filter_hz".to_string(), filter.into());
    identification
        .save(&path, arm, data)
        .map_err(|e| key_err(e.to_string()))?;
    let bytes = admittance_files::read_regular(&path, admittance_files::TEXT_LIMIT)
        .map_err(|e| key_err(format!("cannot read back {}: {e}", path.display())))?;
    Ok(IdentifiedNominal {
        path,
        identification,
        checksum: fnv1a64(&bytes),
        cached: false,
    })
}

/// The identification at `path` when it was made for this key and this arm; `None`
/// (fit again) for anything else.
fn cached(path: &std::path::Path, arm: &Model, key_text: &str) -> Option<IdentifiedNominal> {
    let bytes = admittance_files::read_regular(path, admittance_files::TEXT_LIMIT).ok()?;
    let identification = Identification::load(path, arm).ok()?;
    let envelope: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    let recorded = envelope.pointer("/payload/data/cache_key")?.as_str()?;
    (recorded == key_text).then(|| IdentifiedNominal {
        path: path.to_path_buf(),
        identification,
        checksum: fnv1a64(&bytes),
        cached: true,
    })
}
