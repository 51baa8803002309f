//! [`ClosedLoop::from_config`], the one builder of a loop from its settings: the
//! controller, the admittance model and the estimate's source, each checked here, before
//! the first step.

use std::sync::Arc;

use admittance_control::{
    Admittance, BroadModel, ComputedTorqueController, ConfigError, HybridObserver, LearnedObserver,
    MomentumObserver, NeuralController, Observer, PdController, TaskSpaceAdmittance,
};
use admittance_dynamics::Model;
use admittance_learning::broad::{ArmCheck, ArmIdentity};

use crate::closed_loop::{ClosedLoop, EstimateToController, LoopParts};
use crate::config::{ControllerConfig, ControllerKind, LoopConfig, ObserverKind};
use crate::error::LoopError;
use crate::parts::{Compliance, EstimateSource, LoopController};
use crate::stage::{ObserverStage, ObserverStageSettings};

impl ClosedLoop {
    /// The loop `config` describes for the arm `model` (the controller's and the
    /// observers' nominal model). `trained` is the network the learned observers run on
    /// (docs/method.md section 5): for `learned` the free-motion torque from `[q, q', q'']`,
    /// for `hybrid` what the momentum observer's nominal model misses; required by those
    /// kinds, ignored by the others. Every problem is an error at its dotted key.
    pub fn from_config<Training>(
        model: &Model,
        config: &LoopConfig<Training>,
        trained: Option<BroadModel>,
    ) -> Result<Self, LoopError> {
        config.validate()?;
        let controller = controller(Arc::new(model.clone()), &config.controller)?;
        let admittance = config.compliance(model)?;
        let estimate = estimate_source(model, config, trained)?;
        Ok(ClosedLoop::new(LoopParts {
            controller,
            admittance,
            estimate,
            estimate_to_controller: if config.controller.subtract_estimate {
                EstimateToController::Passed
            } else {
                EstimateToController::OnlyWithoutAdmittance
            },
            dt: 1.0 / config.control_rate_hz,
        }))
    }
}

impl<Training> LoopConfig<Training> {
    /// The admittance model of the settings for `model`'s joints, if any (a caller that
    /// compares the loop's reference with one driven by the true torque builds a second).
    pub fn compliance(&self, model: &Model) -> Result<Option<Compliance>, LoopError> {
        match (&self.admittance, &self.task_admittance) {
            (Some(spec), _) if spec.enabled => Admittance::new(model.nq(), &spec.config)
                .map(|a| Some(Compliance::Joint(a)))
                .map_err(|e| component("admittance", e)),
            (_, Some(config)) => TaskSpaceAdmittance::new(Arc::new(model.clone()), config)
                .map(|a| Some(Compliance::Task(Box::new(a))))
                .map_err(|e| component("task_admittance", e)),
            _ => Ok(None),
        }
    }
}

/// A component's error at its key under the component's table (`controller.neural`).
fn component(section: &str, source: ConfigError) -> LoopError {
    source.within(section).into()
}

fn controller(nominal: Arc<Model>, c: &ControllerConfig) -> Result<LoopController, LoopError> {
    Ok(match c.kind {
        ControllerKind::Neural => LoopController::Neural(Box::new(
            NeuralController::new(nominal, &c.neural)
                .map_err(|e| component("controller.neural", e))?,
        )),
        ControllerKind::Pd => {
            let cfg =
                c.pd.as_ref()
                    .ok_or_else(|| LoopError::invalid("controller.pd", "missing"))?;
            LoopController::Other(Box::new(
                PdController::new(nominal, cfg).map_err(|e| component("controller.pd", e))?,
            ))
        }
        ControllerKind::ComputedTorque => {
            let cfg = c
                .computed_torque
                .as_ref()
                .ok_or_else(|| LoopError::invalid("controller.computed_torque", "missing"))?;
            LoopController::Other(Box::new(
                ComputedTorqueController::new(nominal, cfg)
                    .map_err(|e| component("controller.computed_torque", e))?,
            ))
        }
    })
}

fn estimate_source<Training>(
    model: &Model,
    config: &LoopConfig<Training>,
    trained: Option<BroadModel>,
) -> Result<EstimateSource, LoopError> {
    let spec = &config.observer;
    let (observer, fitted) = match observer(model, config, trained)? {
        None if spec.kind == ObserverKind::Oracle => return Ok(EstimateSource::Oracle),
        None => return Ok(EstimateSource::None),
        Some(observer) => observer,
    };
    let settings = ObserverStageSettings {
        input_filter_hz: spec.input_filter_hz,
        cutoff_hz: spec.cutoff_hz,
        warmup: spec.warmup,
        // The paper's learned networks map the state to the torque and were trained on the
        // filtered command one sample late (the pairing with q'' of the free-motion data,
        // docs/outputs.md). The hybrid's network only corrects the momentum observer, which
        // takes this period's torque as the momentum stage does.
        delayed_torque: spec.kind == ObserverKind::Learned,
        rate_hz: config.control_rate_hz,
    };
    let stage = ObserverStage::new(observer, &settings)?
        .with_torque_delay(&fitted.delay_s, config.control_rate_hz)?
        .with_training_range(fitted.training_range)
        .with_training_speed(fitted.training_speed);
    Ok(EstimateSource::Observer(Box::new(stage)))
}

/// What an identification an observer runs on was fitted with: its torque delays,
/// training range and training speeds (all empty without one).
#[derive(Default)]
struct Fitted {
    delay_s: Vec<f64>,
    training_range: Vec<[f64; 2]>,
    training_speed: Vec<f64>,
}

/// The external-torque observer (docs/method.md section 5) and, when it runs on an
/// identification, what that identification was fitted with (read once, with the
/// observer); `None` for `none` and `oracle`.
fn observer<Training>(
    model: &Model,
    config: &LoopConfig<Training>,
    trained: Option<BroadModel>,
) -> Result<Option<(Box<dyn Observer + Send>, Fitted)>, LoopError> {
    let spec = &config.observer;
    let momentum_err = |e: ConfigError| component("observer.momentum", e);
    let momentum = || -> Result<_, LoopError> {
        if let Some(path) = &spec.identification {
            let ident = admittance_dynamics::Identification::load(path, model)
                .map_err(|e| LoopError::invalid("observer.identification", e.to_string()))?;
            let observer = MomentumObserver::from_identification(&ident, &spec.momentum)
                .map_err(momentum_err)?;
            let fitted = Fitted {
                delay_s: ident.summary.delay_s.clone(),
                training_range: ident.summary.training_range.clone(),
                training_speed: ident.summary.training_speed.clone(),
            };
            return Ok((observer, fitted));
        }
        let nominal = model
            .with_scaled_inertias(spec.nominal_inertia_scale)
            .map_err(|e| LoopError::invalid("observer.nominal_inertia_scale", e.to_string()))?;
        let observer =
            MomentumObserver::new(Arc::new(nominal), &spec.momentum).map_err(momentum_err)?;
        Ok((observer, Fitted::default()))
    };
    // A network of the wrong shape (its key in the observer is `model`) is at fault where
    // it came from: the file `observer.network`, or the training of the caller's.
    let network_key = match (&trained, &spec.network) {
        (None, Some(_)) => "observer.network",
        _ => "observer.training",
    };
    let network_err = |e: ConfigError| {
        LoopError::from(ConfigError {
            key: network_key.into(),
            ..e
        })
    };
    let network = || {
        match (trained, &spec.network) {
        (Some(trained), _) => Ok(trained),
        (None, Some(path)) => network_file(model, path),
        (None, None) => Err(LoopError::invalid(
            "observer.kind",
            "a learned observer needs its trained network",
        )
        .hint("name it in observer.network (admittance train writes one), or let the scenario runner train it from [observer.training]")),
    }
    };
    Ok(match spec.kind {
        ObserverKind::None | ObserverKind::Oracle => None,
        ObserverKind::Momentum => {
            let (observer, fitted) = momentum()?;
            Some((Box::new(observer) as Box<dyn Observer + Send>, fitted))
        }
        ObserverKind::Hybrid => {
            let network = network()?;
            let (observer, fitted) = momentum()?;
            Some((
                Box::new(HybridObserver::new(observer, network).map_err(network_err)?) as _,
                fitted,
            ))
        }
        // The loop low-passes every estimate (observer.cutoff_hz): none inside.
        ObserverKind::Learned => Some((
            Box::new(LearnedObserver::new(network()?, 0.0).map_err(network_err)?) as _,
            Fitted::default(),
        )),
    })
}

/// The network file `observer.network` names, checked against the arm.
fn network_file(model: &Model, path: &std::path::Path) -> Result<BroadModel, LoopError> {
    let network = BroadModel::load(path)
        .map_err(|e| LoopError::invalid("observer.network", e.to_string()))?;
    checked_network(model, network, path)
}

/// `network` (read from `path`) when it was trained on `model`'s arm (joint names and the
/// URDF's fingerprint). A network without a recorded arm (fitted in memory) cannot be
/// checked: its sizes are checked by the observer.
pub(crate) fn checked_network(
    model: &Model,
    network: BroadModel,
    path: &std::path::Path,
) -> Result<BroadModel, LoopError> {
    let arm = ArmIdentity::new(model.joint_names(), model.fingerprint());
    match network.check_arm(&arm) {
        Ok(ArmCheck::Matches | ArmCheck::Unrecorded) => Ok(network),
        Err(e) => Err(
            LoopError::invalid("observer.network", format!("{}: {e}", path.display()))
                .hint("train it on this arm's data, or deploy the arm it was trained for"),
        ),
    }
}
