//! From a resolved scenario to the parts of a run: the arm, the plant and its sensors,
//! the desired trajectory, the learned observer's network, and the [`ClosedLoop`]
//! ([`ClosedLoop::from_config`] of the scenario's [`Scenario::loop_config`]). Every value
//! is checked here, before the first step.

use std::path::Path;

use admittance_control::BroadModel;
use admittance_dynamics::Model;
use admittance_loop::{ClosedLoop, Compliance, ObserverKind};
use admittance_sim::{Plant, Sensors, SimError};

use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::metrics::{IdentificationMetrics, ObserverTrainingMetrics};
use crate::progress::RunOptions;
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
use crate::spec::Scenario;
use crate::training::{
    identified_nominal, observer_network, IdentifiedNominal, Nominal, SimulateData,
};
use crate::trajectory::Trajectory;

/// The parts of one variant's run.
pub(crate) struct Assembly {
    pub scenario: Scenario,
    pub joints: Vec<String>,
    pub trajectory: Trajectory,
    pub plant: Plant,
    pub sensors: Sensors,
    pub closed_loop: ClosedLoop,
    /// A second admittance model driven by the true external torque (the reference the
    /// variant's is compared with, `admittance_error_rms`).
    pub oracle_admittance: Option<Compliance>,
    pub observer_training: Option<ObserverTrainingMetrics>,
    pub observer_validation: Option<TimeSeries>,
    pub identification: Option<IdentificationMetrics>,
    /// What the URDF loader accepted with a warning (`file:line: element: problem`).
    pub arm_warnings: Vec<String>,
    /// Contact detection (`[contact]`).
    pub contact: Option<crate::contact_run::ContactRun>,
}

/// Resolves, validates and builds one variant of a scenario.
pub(crate) fn assemble(
    source: &ScenarioSource,
    path: &Path,
    variant: Option<&str>,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<Assembly, ScenarioError> {
    let ctx = Ctx { source, variant };
    let scenario: Scenario = source.resolve(variant)?;
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
    crate::budget::check_run(&ctx, &scenario, joints.len(), &options.limits)?;
    let n = model.nq();
    let trajectory = match &scenario.trajectory.excitation {
        Some(settings) => {
            let designed = admittance_dynamics::excitation(&model, settings)
                .map_err(|e| ctx.err("trajectory.excitation", e.to_string(), None))?;
            Trajectory::excitation(designed.base_frequency, designed.series)
        }
        None => Trajectory::new(
            &scenario.trajectory,
            &joints,
            &crate::spec::mid_range(&model),
        ),
    };
    let (mut q_d, mut qd_d, mut qdd_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    trajectory.eval(0.0, &mut q_d, &mut qd_d, &mut qdd_d);

    let mut plant_config = scenario.plant.clone();
    if plant_config.initial_q.is_empty() {
        plant_config.initial_q = q_d.clone();
    }
    if let Some(seed) = options.seed.or(scenario.seed) {
        plant_config.sensors.seed = seed;
    }
    let sim_err = |e: SimError| ctx.plant_err(e);
    let plant = Plant::new(&model, &plant_config).map_err(sim_err)?;
    let mut gain_warnings = gain_warning_lines(&ctx, &scenario, &model, &trajectory);
    let sensors = Sensors::new(&model, &plant_config.sensors, plant_config.control_rate_hz)
        .map_err(sim_err)?;
    let mut loop_config = scenario.loop_config_for(path);
    let oracle_admittance = loop_config
        .compliance(&model)
        .map_err(|e| ctx.loop_err(e))?;
    let identified = identified_nominal_of(&ctx, &scenario, &model, path, options, simulate)?;
    gain_warnings.extend(filter_warning(&ctx, &scenario, identified.as_ref()));
    if let Some(nominal) = &identified {
        loop_config.observer.identification = Some(nominal.path.clone());
    }
    let mut observer_training = None;
    let mut observer_validation = None;
    let trained = trained_network(
        &ctx,
        &scenario,
        &model,
        path,
        options,
        simulate,
        identified.as_ref(),
        &mut observer_training,
        &mut observer_validation,
    )?;
    let mut closed_loop =
        ClosedLoop::from_config(&model, &loop_config, trained).map_err(|e| ctx.loop_err(e))?;
    let contact = contact_run(
        &ctx,
        &scenario,
        &model,
        path,
        options,
        simulate,
        identified.as_ref(),
        &mut closed_loop,
    )?;
    Ok(Assembly {
        scenario,
        joints,
        trajectory,
        plant,
        sensors,
        closed_loop,
        oracle_admittance,
        observer_training,
        observer_validation,
        identification: identified.map(|i| IdentificationMetrics {
            identification_expected_false_torque_rms: i
                .identification
                .summary
                .expected_false_torque_rms
                .clone(),
            identification_cached: i.cached,
        }),
        arm_warnings: model
            .warnings()
            .iter()
            .map(|w| w.to_string())
            .chain(gain_warnings)
            .collect(),
        contact,
    })
}

/// The detector of `[contact]`, with its floor as the admittance's deadband when the table
/// asks for it.
#[allow(clippy::too_many_arguments)]
fn contact_run(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    model: &Model,
    path: &Path,
    options: &RunOptions,
    simulate: SimulateData<'_>,
    identified: Option<&IdentifiedNominal>,
    closed_loop: &mut ClosedLoop,
) -> Result<Option<crate::contact_run::ContactRun>, ScenarioError> {
    let floor = crate::contact_run::contact_floor(
        ctx, scenario, model, path, options, simulate, identified,
    )?;
    let Some(floor) = floor else {
        return Ok(None);
    };
    if scenario.contact.as_ref().is_some_and(|c| c.deadband) {
        if let Some(compliance) = closed_loop.admittance_mut() {
            compliance
                .set_deadband(&floor.contact_thresholds)
                .map_err(|e| ctx.config_err("contact.deadband", &e))?;
        }
    }
    crate::contact_run::ContactRun::new(&floor)
        .map(Some)
        .map_err(|e| ctx.config_err("contact", &e))
}

/// The identification the momentum and hybrid observers run on: fitted on the training
/// data (`[observer.training] identify = true`), or the file `observer.identification`
/// names; `None` when they run on the URDF or the observer is another kind.
pub(crate) fn identified_nominal_of(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    model: &Model,
    path: &Path,
    options: &RunOptions,
    simulate: SimulateData<'_>,
) -> Result<Option<IdentifiedNominal>, ScenarioError> {
    let spec = &scenario.observer;
    if !matches!(spec.kind, ObserverKind::Momentum | ObserverKind::Hybrid) {
        return Ok(None);
    }
    if spec.training.as_ref().is_some_and(|t| t.identify) {
        return identified_nominal(ctx, scenario, path, model, options, simulate).map(Some);
    }
    let Some(file) = &scenario.loop_config_for(path).observer.identification else {
        return Ok(None);
    };
    let key_err = |m: String| ctx.err("observer.identification", m, None);
    let bytes = admittance_files::read_regular(file, admittance_files::TEXT_LIMIT)
        .map_err(|e| key_err(format!("cannot read {}: {e}", file.display())))?;
    let identification = admittance_dynamics::Identification::load(file, model)
        .map_err(|e| key_err(e.to_string()))?;
    Ok(Some(IdentifiedNominal {
        path: file.clone(),
        identification,
        checksum: admittance_learning::broad::fnv1a64(&bytes),
        cached: true,
    }))
}

/// A warning when the identification file given was fitted on signals conditioned otherwise
/// than the observer's `input_filter_hz` feeds it (issue 30: settings travel with the
/// files): its summary's cut-off, else the one `admittance identify` recorded.
fn filter_warning(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    identified: Option<&IdentifiedNominal>,
) -> Option<String> {
    let nominal = identified.filter(|_| {
        !scenario
            .observer
            .training
            .as_ref()
            .is_some_and(|t| t.identify)
    })?;
    let summary_hz = nominal.identification.summary.input_filter_hz;
    let recorded = if summary_hz > 0.0 {
        summary_hz
    } else {
        let bytes = std::fs::read(&nominal.path).ok()?;
        serde_json::from_slice::<serde_json::Value>(&bytes)
            .ok()?
            .pointer("/payload/data/input_filter_hz")?
            .as_f64()?
    };
    let used = scenario.observer.input_filter_hz;
    (recorded.to_bits() != used.to_bits()).then(|| {
        ctx.err(
            "observer.input_filter_hz",
            format!(
                "is {used} Hz, but {} was fitted on signals conditioned at {recorded} Hz: the \
                 observer runs the identification on other signals than it was fitted on",
                nominal.path.display()
            ),
            Some(&format!("set observer.input_filter_hz = {recorded}")),
        )
        .to_string()
    })
}

/// The gain rules' warnings of a resolved, valid scenario (`Scenario::gain_warnings`) over
/// 200 poses of its desired motion, with the plant's viscous friction, each located at its
/// key and line (`file:line: key ...: problem; hint: ...`).
fn gain_warning_lines(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    model: &Model,
    trajectory: &Trajectory,
) -> Vec<String> {
    let n = model.nq();
    let poses: Vec<Vec<f64>> = (0..200)
        .map(|k| {
            let (mut q, mut v, mut a) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            trajectory.eval(scenario.duration * k as f64 / 199.0, &mut q, &mut v, &mut a);
            q
        })
        .collect();
    // The plant's friction entries, the last one naming a joint (or "*") winning.
    let mut damping = vec![0.0; n];
    for f in &scenario.plant.friction {
        for (j, name) in model.joint_names().enumerate() {
            if f.joint == "*" || f.joint == name {
                damping[j] = f.viscous;
            }
        }
    }
    scenario
        .gain_warnings(model, &poses, &damping)
        .into_iter()
        .map(|w| ctx.err(&w.key, w.message, w.hint.as_deref()).to_string())
        .collect()
}

/// The gain rules' warnings of one variant of a scenario file, as a run prints them
/// (without running it): each names the file, line, key, joint and the value to use.
pub fn gain_warnings(
    source: &ScenarioSource,
    path: &Path,
    variant: Option<&str>,
) -> Result<Vec<String>, ScenarioError> {
    let ctx = Ctx { source, variant };
    let scenario: Scenario = source.resolve(variant)?;
    let model = Model::from_urdf_file_with(&scenario.urdf_path(path), &scenario.arm.urdf_options())
        .map_err(|e| ctx.err("arm.urdf", e.to_string(), None))?;
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let mut problems = scenario.validate(&joints);
    if problems.is_empty() {
        problems = scenario.validate_for_arm(&model);
    }
    if !problems.is_empty() {
        return Err(source.invalid(variant, &problems));
    }
    let trajectory = Trajectory::new(
        &scenario.trajectory,
        &joints,
        &crate::spec::mid_range(&model),
    );
    Ok(gain_warning_lines(&ctx, &scenario, &model, &trajectory))
}

/// The network of a learned observer (docs/method.md section 5), trained or loaded from the
/// cache for `learned` and `hybrid`; `None` for the other kinds.
#[allow(clippy::too_many_arguments)]
pub(crate) fn trained_network(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    model: &Model,
    path: &Path,
    options: &RunOptions,
    simulate: SimulateData<'_>,
    identified: Option<&IdentifiedNominal>,
    training: &mut Option<ObserverTrainingMetrics>,
    validation: &mut Option<TimeSeries>,
) -> Result<Option<BroadModel>, ScenarioError> {
    let spec = &scenario.observer;
    if !spec.kind.is_learned() {
        return Ok(None);
    }
    let scaled_urdf = match (spec.kind, identified) {
        (ObserverKind::Hybrid, None) => Some(
            model
                .with_scaled_inertias(spec.nominal_inertia_scale)
                .map_err(|e| ctx.err("observer.nominal_inertia_scale", e.to_string(), None))?,
        ),
        _ => None,
    };
    let nominal = match (spec.kind, identified, &scaled_urdf) {
        (ObserverKind::Hybrid, Some(i), _) => Some(Nominal::Identified(i)),
        (ObserverKind::Hybrid, None, Some(m)) => Some(Nominal::Urdf(m)),
        _ => None,
    };
    let net = observer_network(ctx, scenario, path, model, nominal, options, simulate)?;
    *training = Some(ObserverTrainingMetrics {
        train_seconds: net.train_seconds,
        observer_nodes: net.model.n_nodes(),
        validation_nrmse: net.validation_nrmse.clone(),
        observer_model_cached: net.cached,
        training_samples: net.samples,
        observer_lambda: net.lambda,
    });
    *validation = net.validation_series.clone();
    Ok(Some(net.model))
}
