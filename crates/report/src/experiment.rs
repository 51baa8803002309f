//! Which report a run folder gets, from what its variants contain (the settings of
//! `settings.json`, else of `scenario.toml`, and the columns of the series), never from the
//! scenario's name: a MuJoCo co-simulation, dynamic nodes, a deadzone comparison, a hand
//! contact, an observer comparison, free-motion data, or none of these. Also the joint
//! each report is about: the deadzone's, the one in contact, or the worst tracked.

use admittance_runfolder::settings::{self as rs, VariantSettings};
use admittance_runfolder::{columns, metrics as m, summary};

use crate::folder::RunFolder;

/// The experiment of a run folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Experiment {
    /// A, deadzone compensation (Figs 7-12): a plant with an actuator deadzone (the neural
    /// controller with and without its compensation, and PD, are compared on it).
    Deadzone,
    /// B, observer and admittance (Figs 13-20): a joint-space admittance model driven by an
    /// external-torque estimate; `mujoco` when the run comes from the MuJoCo co-simulation
    /// (`"plant": "mujoco"` in summary.json).
    Admittance {
        /// The plant was MuJoCo.
        mujoco: bool,
    },
    /// C, dynamic RBF nodes (Figs 21-26): a `[dynamic_nodes]` section.
    DynamicNodes,
    /// The free-motion training data of B (Fig 13): a run that records free motion.
    TrainingData,
    /// The free-motion validation data of B (Fig 14): the same, its name saying
    /// `validation` (the two differ only in their excitation).
    ValidationData,
    /// Contact at the hand: a task-space admittance, or the hand columns.
    HandContact,
    /// Anything else.
    Other,
}

impl Experiment {
    /// The experiment of `folder`, by these rules in this order: the co-simulation's
    /// `plant`; dynamic nodes; an actuator deadzone; a task-space
    /// admittance or hand columns; a joint-space admittance with an observer; a free-motion
    /// recording; else none.
    pub fn of(folder: &RunFolder) -> Self {
        if folder.plant.as_deref() == Some(summary::PLANT_MUJOCO) {
            return Experiment::Admittance { mujoco: true };
        }
        let settings = folder.run_settings();
        let vs = &settings.variants;
        let any = |f: &dyn Fn(&VariantSettings) -> bool| vs.iter().any(f);
        if any(&|v| v.dynamic_nodes.is_some()) {
            return Experiment::DynamicNodes;
        }
        if any(&|v| !v.deadzones.is_empty()) {
            return Experiment::Deadzone;
        }
        if any(&|v| v.admittance == rs::ADMITTANCE_TASK) || has_hand_columns(folder) {
            return Experiment::HandContact;
        }
        if any(&|v| v.admittance == rs::ADMITTANCE_JOINT && v.observer != rs::OBSERVER_NONE) {
            return Experiment::Admittance { mujoco: false };
        }
        if any(&|v| v.free_motion) || !folder.free_motion.is_empty() {
            return if folder.scenario.contains("validation") {
                Experiment::ValidationData
            } else {
                Experiment::TrainingData
            };
        }
        Experiment::Other
    }
}

/// Whether a variant's series has the hand columns of a task-space run (true and estimated
/// hand force, at least).
pub fn has_hand_columns(folder: &RunFolder) -> bool {
    folder.variants.iter().any(|v| {
        columns::AXES.iter().all(|a| {
            v.table.has(&columns::axis(columns::HAND_FORCE, a))
                && v.table.has(&columns::axis(columns::HAND_FORCE_ESTIMATE, a))
        })
    })
}

/// The variants of a deadzone comparison that share one deadzone: the neural controller
/// with and without its compensation, and PD, each the first of the run with that exact
/// deadzone; `joint` is the joint the figures show.
#[derive(Clone, Debug, PartialEq)]
pub struct DeadzoneGroup {
    /// The neural controller with deadzone compensation.
    pub with: Option<String>,
    /// The neural controller without it.
    pub without: Option<String>,
    /// PD (the neural controller's linear part).
    pub pd: Option<String>,
    /// The joint with the deadzone that matters: of the joints with a deadzone, the one
    /// whose tracking RMSE is largest without compensation (else with it).
    pub joint: String,
}

/// The deadzone comparisons of a run, in the order their deadzones first appear (the
/// paper's deadzone first, then a wider one in `scenarios/deadzone.toml`).
pub fn deadzone_groups(folder: &RunFolder) -> Vec<DeadzoneGroup> {
    let settings = folder.run_settings();
    let mut seen: Vec<&Vec<rs::Deadzone>> = Vec::new();
    let mut out = Vec::new();
    for v in &settings.variants {
        if v.deadzones.is_empty() || seen.contains(&&v.deadzones) {
            continue;
        }
        seen.push(&v.deadzones);
        let find = |ok: &dyn Fn(&VariantSettings) -> bool| {
            settings
                .variants
                .iter()
                .find(|x| x.deadzones == v.deadzones && ok(x))
                .map(|x| x.name.clone())
        };
        let with = find(&|x| x.controller == rs::CONTROLLER_NEURAL && x.deadzone_compensation);
        let without = find(&|x| x.controller == rs::CONTROLLER_NEURAL && !x.deadzone_compensation);
        let pd = find(&|x| x.controller == rs::CONTROLLER_PD);
        let rmse = |variant: &Option<String>, joint: &str| {
            let k = folder.joints.iter().position(|j| j == joint)?;
            let v = folder.variant(variant.as_deref()?)?;
            crate::values::joint_metric(v, m::TRACKING_RMSE, k)
        };
        let joint = v
            .deadzones
            .iter()
            .map(|d| d.joint.clone())
            .max_by(|a, b| {
                let key = |j: &str| rmse(&without, j).or(rmse(&with, j)).unwrap_or(f64::MIN);
                key(a).total_cmp(&key(b))
            })
            .unwrap_or_default();
        let rmse_pd = |j: &str| rmse(&pd, j);
        let joint = if without.is_none() && with.is_none() {
            // PD alone: its worst deadzone joint.
            v.deadzones
                .iter()
                .map(|d| d.joint.clone())
                .max_by(|a, b| {
                    let key = |j: &str| rmse_pd(j).unwrap_or(f64::MIN);
                    key(a).total_cmp(&key(b))
                })
                .unwrap_or(joint)
        } else {
            joint
        };
        out.push(DeadzoneGroup {
            with,
            without,
            pd,
            joint,
        });
    }
    out
}

/// The joint an observer comparison is about: the first joint an environment of the
/// scenario acts on directly, else the joint with the largest true external torque (RMS
/// over the run, every variant: the co-simulation's push at the hand), else the first.
pub fn contact_joint(folder: &RunFolder) -> Option<&str> {
    let settings = folder.run_settings();
    let named = settings
        .variants
        .iter()
        .flat_map(|v| &v.environments)
        .flat_map(|e| &e.joints)
        .find_map(|j| folder.joints.iter().find(|x| *x == j));
    if let Some(j) = named {
        return Some(j.as_str());
    }
    let rms = |j: &str| {
        folder
            .variants
            .iter()
            .filter_map(|v| v.table.col(&columns::joint(columns::EXTERNAL, j)))
            .map(|c| {
                let finite: Vec<f64> = c.iter().copied().filter(|x| x.is_finite()).collect();
                (finite.iter().map(|x| x * x).sum::<f64>() / finite.len().max(1) as f64).sqrt()
            })
            .fold(0.0, f64::max)
    };
    let best = folder
        .joints
        .iter()
        .map(|j| (j, rms(j)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .filter(|(_, r)| *r > 0.0)
        .map(|(j, _)| j.as_str());
    best.or(folder.joints.first().map(String::as_str))
}

/// The worst-tracked joint: the largest `tracking_rmse` of any variant, else the first.
pub fn worst_joint(folder: &RunFolder) -> Option<&str> {
    let mut best: Option<(usize, f64)> = None;
    for v in &folder.variants {
        for k in 0..folder.joints.len() {
            if let Some(x) = crate::values::joint_metric(v, m::TRACKING_RMSE, k) {
                if x.is_finite() && best.is_none_or(|(_, b)| x > b) {
                    best = Some((k, x));
                }
            }
        }
    }
    folder
        .joints
        .get(best.map_or(0, |(k, _)| k))
        .map(String::as_str)
}
