//! A variant's settings as the run applied them, for `settings.json`
//! (`admittance_runfolder::settings`): the deadzones from the plant itself (after wildcards
//! and later entries), the environment windows, the saturation bounds, and the kinds of
//! controller, observer and admittance the report classifies a run by.

use admittance_control::JointValues;
use admittance_loop::ClosedLoop;
use admittance_runfolder::settings::{
    self as rs, Bound, Deadzone, DynamicNodes, Environment, VariantSettings, Wall,
};
use admittance_sim::Plant;

use crate::spec::Scenario;

/// The snake_case name serde gives a unit enum value (`ControllerKind::Neural` -> `neural`).
fn kind_name(value: impl serde::Serialize) -> String {
    serde_json::to_value(value)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_default()
}

fn value_at(values: &JointValues, i: usize) -> Option<f64> {
    match values {
        JointValues::Uniform(v) => Some(*v),
        JointValues::PerJoint(vs) => vs.get(i).copied(),
    }
}

/// The settings of variant `name`, built once its plant and loop exist.
pub(crate) fn variant_settings(
    name: &str,
    scenario: &Scenario,
    joints: &[String],
    plant: &Plant,
    closed_loop: &ClosedLoop,
) -> VariantSettings {
    let neural = scenario.controller.kind == admittance_loop::ControllerKind::Neural;
    let admittance = match closed_loop.admittance() {
        None => rs::ADMITTANCE_NONE,
        Some(c) if c.task_space().is_some() => rs::ADMITTANCE_TASK,
        Some(_) => rs::ADMITTANCE_JOINT,
    };
    let deadzones = joints
        .iter()
        .zip(plant.deadzones())
        .filter(|(_, d)| d.d_left != 0.0 || d.d_right != 0.0)
        .map(|(j, d)| Deadzone {
            joint: j.clone(),
            d_left: d.d_left,
            d_right: d.d_right,
            slope_left: d.slope_left,
            slope_right: d.slope_right,
        })
        .collect();
    let saturation = scenario
        .admittance
        .as_ref()
        .filter(|a| a.enabled && admittance == rs::ADMITTANCE_JOINT)
        .and_then(|a| a.config.saturation.as_ref())
        .map(|s| {
            joints
                .iter()
                .enumerate()
                .filter_map(|(i, j)| {
                    let c = value_at(&s.centre, i)?;
                    let h = value_at(&s.half_range, i)?;
                    (h.is_finite() && c.is_finite()).then(|| Bound {
                        joint: j.clone(),
                        lower: c - h,
                        upper: c + h,
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    let env = &scenario.plant.environment;
    let mut environments = Vec::new();
    for s in &env.joint_springs {
        environments.push(Environment {
            kind: "joint_springs".into(),
            joints: s.joints.clone(),
            t_start: s.t_start,
            t_end: rs::window_end(s.t_end),
        });
    }
    for w in &env.walls {
        environments.push(Environment {
            kind: rs::ENVIRONMENT_WALLS.into(),
            joints: Vec::new(),
            t_start: w.t_start,
            t_end: rs::window_end(w.t_end),
        });
    }
    for p in &env.joint_torque_profiles {
        environments.push(Environment {
            kind: "joint_torque_profiles".into(),
            joints: vec![p.joint.clone()],
            t_start: p.t_start,
            t_end: rs::window_end(p.t_end),
        });
    }
    for p in &env.tip_force_profiles {
        environments.push(Environment {
            kind: "tip_force_profiles".into(),
            joints: Vec::new(),
            t_start: p.t_start,
            t_end: rs::window_end(p.t_end),
        });
    }
    let walls = env
        .walls
        .iter()
        .map(|w| {
            let n = w.normal;
            let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            Wall {
                point: w.point,
                normal: n.map(|c| c / norm),
                t_start: w.t_start,
                t_end: rs::window_end(w.t_end),
            }
        })
        .collect();
    VariantSettings {
        name: name.to_string(),
        controller: kind_name(scenario.controller.kind),
        deadzone_compensation: neural && scenario.controller.neural.deadzone_compensation,
        observer: kind_name(scenario.observer.kind),
        admittance: admittance.to_string(),
        deadzones,
        saturation,
        environments,
        walls,
        dynamic_nodes: scenario.dynamic_nodes.as_ref().map(|d| DynamicNodes {
            discard_time: d.discard_time,
            grow_time: d.grow_time,
            approximation_window: d.approximation_window,
        }),
        free_motion: scenario.record.free_motion_csv,
    }
}
