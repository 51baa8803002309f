//! A scenario's loop for a real robot: the same assembly as a simulated run (controller,
//! admittance model, observer with its trained network from the cache or trained now),
//! without the plant, for a caller that samples its own arm (the C ABI of `admittance-ffi`).

use std::path::Path;

use admittance_dynamics::Model;

use crate::assemble::assemble;
use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::progress::RunOptions;
use crate::runner::run_variant;
use crate::source::ScenarioSource;
use crate::spec::Scenario;
use crate::trajectory::Trajectory;
use admittance_loop::{ClosedLoop, ObserverKind};

/// What a robot's loop needs of a scenario variant.
pub struct RobotLoop {
    /// The resolved variant.
    pub scenario: Scenario,
    /// The arm (the URDF of `[arm]`).
    pub model: Model,
    /// Joint names in chain order.
    pub joints: Vec<String>,
    /// The desired trajectory of `[trajectory]`.
    pub trajectory: Trajectory,
    /// The loop: observer -> admittance model -> controller.
    pub closed_loop: ClosedLoop,
    /// What the URDF loader accepted with a warning.
    pub arm_warnings: Vec<String>,
}

/// Resolves and builds one variant of a scenario file for a robot. The observer kind
/// `oracle` is refused (a robot does not know its true external torque); a learned
/// observer's network is loaded from the cache, or trained now when the cache has none.
/// The plant and sensor sections are read only for the control rate and the
/// differentiation filter (`plant.control_rate_hz`, `plant.sensors.filter_cutoff_hz`).
pub fn robot_loop(
    source: &ScenarioSource,
    path: &Path,
    variant: Option<&str>,
    options: &RunOptions,
) -> Result<RobotLoop, ScenarioError> {
    let ctx = Ctx { source, variant };
    let scenario: Scenario = source.resolve(variant)?;
    if scenario.observer.kind == ObserverKind::Oracle {
        return Err(ctx.err(
            "observer.kind",
            "`oracle` reads the true external torque, which a robot does not measure",
            Some("choose momentum, learned, hybrid or none"),
        ));
    }
    let simulate = |src: &ScenarioSource, p: &Path, o: &RunOptions| {
        run_variant(src, p, None, o).map(|r| (r.joints, r.free_motion))
    };
    let parts = assemble(source, path, variant, options, &simulate)?;
    let model = Model::from_urdf_file_with(
        &parts.scenario.urdf_path(path),
        &parts.scenario.arm.urdf_options(),
    )
    .map_err(|e| ctx.err("arm.urdf", e.to_string(), None))?;
    Ok(RobotLoop {
        scenario: parts.scenario,
        model,
        joints: parts.joints,
        trajectory: parts.trajectory,
        closed_loop: parts.closed_loop,
        arm_warnings: parts.arm_warnings,
    })
}
