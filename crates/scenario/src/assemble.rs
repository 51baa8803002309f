//! From a resolved scenario to the parts of a run: the arm, the plant and its sensors,
//! the desired trajectory, and the [`ClosedLoop`] (controller, admittance model, observer).
//! Every value is checked here, before the first step.

use std::path::Path;
use std::sync::Arc;

use admittance_control::{
    Admittance, ComputedTorqueController, ConfigError, HybridObserver, LearnedObserver,
    MomentumObserver, NeuralController, Observer, PdController, TaskSpaceAdmittance,
};
use admittance_dynamics::Model;
use admittance_sim::{InputConditioner, Plant, Sensors, SimError};

use crate::closed_loop::{
    ClosedLoop, Compliance, EstimateSource, EstimateToController, LoopController, LoopParts,
    ObserverStage,
};
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::metrics::ObserverTrainingMetrics;
use crate::progress::RunOptions;
use crate::series::TimeSeries;
use crate::source::ScenarioSource;
use crate::spec::{ControllerKind, ObserverKind, Scenario};
use crate::training::{observer_network, SimulateData};
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
    /// What the URDF loader accepted with a warning (`file:line: element: problem`).
    pub arm_warnings: Vec<String>,
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
    let trajectory = Trajectory::new(
        &scenario.trajectory,
        &joints,
        &crate::spec::mid_range(&model),
    );
    let (mut q_d, mut qd_d, mut qdd_d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    trajectory.eval(0.0, &mut q_d, &mut qd_d, &mut qdd_d);

    let mut plant_config = scenario.plant.clone();
    if plant_config.initial_q.is_empty() {
        plant_config.initial_q = q_d.clone();
    }
    if let Some(seed) = options.seed.or(scenario.seed) {
        plant_config.sensors.seed = seed;
    }
    let sim_err = |e: SimError| ctx.err("plant", e.to_string(), None);
    let plant = Plant::new(&model, &plant_config).map_err(sim_err)?;
    let sensors = Sensors::new(&model, &plant_config.sensors, plant_config.control_rate_hz)
        .map_err(sim_err)?;
    let dt = plant.control_dt();

    let controller = controller(&ctx, &scenario, Arc::new(model.clone()))?;
    let admittance_model = || match (&scenario.admittance, &scenario.task_admittance) {
        (Some(spec), _) if spec.enabled => Admittance::new(n, &spec.config)
            .map(|a| Some(Compliance::Joint(a)))
            .map_err(|e| ctx.config_err("admittance", &e)),
        (_, Some(config)) => TaskSpaceAdmittance::new(Arc::new(model.clone()), config)
            .map(|a| Some(Compliance::Task(Box::new(a))))
            .map_err(|e| ctx.config_err("task_admittance", &e)),
        _ => Ok(None),
    };
    let admittance = admittance_model()?;
    let oracle_admittance = admittance_model()?;

    let mut observer_training = None;
    let mut observer_validation = None;
    let observer = observer(
        &ctx,
        &scenario,
        &model,
        path,
        options,
        simulate,
        &mut observer_training,
        &mut observer_validation,
    )?;
    let estimate = match (scenario.observer.kind, observer) {
        (ObserverKind::Oracle, _) => EstimateSource::Oracle,
        (_, None) => EstimateSource::None,
        (kind, Some(observer)) => {
            let conditioner = if scenario.observer.input_filter_hz > 0.0 {
                Some(
                    InputConditioner::new(
                        n,
                        scenario.observer.input_filter_hz,
                        plant_config.control_rate_hz,
                    )
                    .map_err(|e| ctx.err("observer.input_filter_hz", e.to_string(), None))?,
                )
            } else {
                None
            };
            EstimateSource::Observer(Box::new(ObserverStage::new(
                observer,
                conditioner,
                // The learned networks were trained on the filtered command one sample late
                // (the pairing with q'' of the free-motion data, docs/outputs.md).
                kind.is_learned(),
                scenario.observer.cutoff_hz,
                scenario.observer.warmup,
                dt,
            )))
        }
    };
    let closed_loop = ClosedLoop::new(LoopParts {
        controller,
        admittance,
        estimate,
        estimate_to_controller: if scenario.controller.subtract_estimate {
            EstimateToController::Passed
        } else {
            EstimateToController::OnlyWithoutAdmittance
        },
        dt,
    });
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
        arm_warnings: model.warnings().iter().map(|w| w.to_string()).collect(),
    })
}

fn controller(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    nominal: Arc<Model>,
) -> Result<LoopController, ScenarioError> {
    let c = &scenario.controller;
    Ok(match c.kind {
        ControllerKind::Neural => LoopController::Neural(Box::new(
            NeuralController::new(nominal, &c.neural)
                .map_err(|e| ctx.config_err("controller.neural", &e))?,
        )),
        ControllerKind::Pd => {
            let cfg =
                c.pd.as_ref()
                    .ok_or_else(|| ctx.err("controller.pd", "missing", None))?;
            LoopController::Other(Box::new(
                PdController::new(nominal, cfg).map_err(|e| ctx.config_err("controller.pd", &e))?,
            ))
        }
        ControllerKind::ComputedTorque => {
            let cfg = c
                .computed_torque
                .as_ref()
                .ok_or_else(|| ctx.err("controller.computed_torque", "missing", None))?;
            LoopController::Other(Box::new(
                ComputedTorqueController::new(nominal, cfg)
                    .map_err(|e| ctx.config_err("controller.computed_torque", &e))?,
            ))
        }
    })
}

/// The external-torque observer (docs/method.md section 5), trained or loaded from the cache
/// for `learned` and `hybrid`.
#[allow(clippy::too_many_arguments)]
fn observer(
    ctx: &Ctx<'_>,
    scenario: &Scenario,
    model: &Model,
    path: &Path,
    options: &RunOptions,
    simulate: SimulateData<'_>,
    training: &mut Option<ObserverTrainingMetrics>,
    validation: &mut Option<TimeSeries>,
) -> Result<Option<Box<dyn Observer + Send>>, ScenarioError> {
    let spec = &scenario.observer;
    let momentum_err =
        |e: ConfigError| ctx.err(&format!("observer.momentum.{}", e.key), e.message, None);
    let nominal = || {
        model
            .with_scaled_inertias(spec.nominal_inertia_scale)
            .map_err(|e| ctx.err("observer.nominal_inertia_scale", e.to_string(), None))
    };
    Ok(match spec.kind {
        ObserverKind::None | ObserverKind::Oracle => None,
        ObserverKind::Momentum => Some(Box::new(
            MomentumObserver::new(Arc::new(nominal()?), &spec.momentum).map_err(momentum_err)?,
        )),
        ObserverKind::Learned | ObserverKind::Hybrid => {
            let nominal_model = match spec.kind {
                ObserverKind::Hybrid => Some(nominal()?),
                _ => None,
            };
            let net = observer_network(
                ctx,
                scenario,
                path,
                model,
                nominal_model.as_ref(),
                options,
                simulate,
            )?;
            *training = Some(ObserverTrainingMetrics {
                train_seconds: net.train_seconds,
                observer_nodes: net.model.n_nodes(),
                validation_nrmse: net.validation_nrmse.clone(),
                observer_model_cached: net.cached,
                training_samples: net.samples,
                observer_lambda: net.lambda,
            });
            *validation = net.validation_series.clone();
            let observer_err = |e: ConfigError| ctx.err("observer.training", e.to_string(), None);
            match nominal_model {
                Some(nominal_model) => {
                    let momentum = MomentumObserver::new(Arc::new(nominal_model), &spec.momentum)
                        .map_err(momentum_err)?;
                    Some(Box::new(
                        HybridObserver::new(momentum, net.model).map_err(observer_err)?,
                    ))
                }
                // The loop low-passes every estimate (observer.cutoff_hz): none inside.
                None => Some(Box::new(
                    LearnedObserver::new(net.model, 0.0).map_err(observer_err)?,
                )),
            }
        }
    })
}
