//! Which experiment a run folder holds: the paper's A, B or C, the data runs of B, a
//! task-space contact run, or a scenario the report knows nothing about.

use admittance_runfolder::{columns, summary};

use crate::folder::RunFolder;

/// The experiment of a run folder, from its scenario name (and `plant`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Experiment {
    /// A, deadzone compensation (`deadzone`, Figs 7-12).
    Deadzone,
    /// B, observer and admittance (`admittance`, Figs 13-20); `mujoco` when the run
    /// comes from the MuJoCo co-simulation (`"plant": "mujoco"` in summary.json).
    Admittance {
        /// The plant was MuJoCo.
        mujoco: bool,
    },
    /// C, dynamic RBF nodes (`dynamic_nodes`, Figs 21-26).
    DynamicNodes,
    /// The free-motion training data of B (`free_motion`, Fig 13).
    TrainingData,
    /// The free-motion validation data of B (`free_motion_validation`, Fig 14).
    ValidationData,
    /// Any other scenario.
    Other,
}

impl Experiment {
    /// The experiment of `folder`.
    pub fn of(folder: &RunFolder) -> Self {
        if folder.plant.as_deref() == Some(summary::PLANT_MUJOCO) {
            return Experiment::Admittance { mujoco: true };
        }
        match folder.scenario.as_str() {
            "deadzone" => Experiment::Deadzone,
            "admittance" => Experiment::Admittance { mujoco: false },
            "dynamic_nodes" => Experiment::DynamicNodes,
            "free_motion" => Experiment::TrainingData,
            "free_motion_validation" => Experiment::ValidationData,
            _ => Experiment::Other,
        }
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
