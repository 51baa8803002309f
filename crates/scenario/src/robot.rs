//! What a robot's deployment folder is made of (`admittance deploy`, docs/your_robot.md): a
//! scenario variant's loop settings, its arm, and the identification and network its
//! observer runs on, taken from the training cache and never trained here. Nothing
//! simulated is kept: the plant, its sensors and the trajectory stay with the scenario.

use std::path::{Path, PathBuf};

use admittance_control::BroadModel;
use admittance_dynamics::Model;
use admittance_loop::{LoopConfig, ObserverKind};

use crate::assemble::{identified_nominal_of, trained_network};
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::progress::RunOptions;
use crate::source::ScenarioSource;
use crate::spec::{Scenario, TrainingSpec};

/// One scenario variant, resolved for a robot.
pub struct Deployable {
    /// The resolved variant.
    pub scenario: Scenario,
    /// The arm's URDF file (resolved against the scenario file).
    pub urdf: PathBuf,
    /// The arm.
    pub model: Model,
    /// The loop's settings; `observer.identification` names the identification file the
    /// momentum part runs on, if any (a file of the scenario's, or the training cache's).
    pub loop_config: LoopConfig<TrainingSpec>,
    /// The learned observers' trained network, from the training cache.
    pub network: Option<BroadModel>,
}

/// Resolves one variant of a scenario file for a robot, with `options.cache_only` forced:
/// a network or identification the cache does not hold is an error naming the command
/// that trains it. The observer kind `oracle` is refused (a robot does not measure its
/// true external torque).
pub fn deployable(
    source: &ScenarioSource,
    path: &Path,
    variant: Option<&str>,
    options: &RunOptions,
) -> Result<Deployable, ScenarioError> {
    let ctx = Ctx { source, variant };
    let scenario: Scenario = source.resolve(variant)?;
    if scenario.observer.kind == ObserverKind::Oracle {
        return Err(ctx.err(
            "observer.kind",
            "`oracle` reads the true external torque, which a robot does not measure",
            Some("choose momentum, learned, hybrid or none (--variant)"),
        ));
    }
    let urdf = scenario.urdf_path(path);
    let model = Model::from_urdf_file_with(&urdf, &scenario.arm.urdf_options()).map_err(|e| {
        ctx.err(
            "arm.urdf",
            e.to_string(),
            Some("the path is relative to the scenario file"),
        )
    })?;
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let mut problems = scenario.validate(&joints);
    if problems.is_empty() {
        problems = scenario.validate_for_arm(&model);
    }
    if !problems.is_empty() {
        return Err(source.invalid(variant, &problems));
    }
    let options = RunOptions {
        seed: options.seed,
        progress: options.progress.clone(),
        limits: options.limits,
        cache_only: true,
    };
    // Validation data may be simulated to look the network up (its key names the data);
    // nothing is fitted.
    let simulate = |src: &ScenarioSource, p: &Path, o: &RunOptions| {
        crate::runner::run_variant(src, p, None, o).map(|r| (r.joints, r.free_motion))
    };
    let mut loop_config = scenario.loop_config_for(path);
    let identified = identified_nominal_of(&ctx, &scenario, &model, path, &options, &simulate)?;
    if let Some(nominal) = &identified {
        loop_config.observer.identification = Some(nominal.path.clone());
    }
    let network = if loop_config.observer.network.is_some() {
        None // the file named in the scenario is copied as it is
    } else {
        let (mut training, mut validation) = (None, None);
        trained_network(
            &ctx,
            &scenario,
            &model,
            path,
            &options,
            &simulate,
            identified.as_ref(),
            &mut training,
            &mut validation,
        )?
    };
    Ok(Deployable {
        scenario,
        urdf,
        model,
        loop_config,
        network,
    })
}
