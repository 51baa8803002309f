//! Which figure of the paper comes from which columns of a run folder, and the figures
//! themselves as data (panels of lines, bands, markers), ready to draw.
//!
//! The experiment is found from what the run contains (`crate::experiment`): a deadzone
//! comparison gives Figs 7-12 ([`deadzone`]), an observer comparison (and its free-motion
//! data runs) Figs 13-20 ([`observer`]), dynamic nodes Figs 21-26 ([`dynamic_nodes`]); a run
//! with hand columns adds the hand-contact figures ([`hand_contact`]), any other scenario
//! gets generic ones ([`generic`]); a run with contact detection adds its figures
//! ([`contact`]). A figure whose data is not in the folder is planned as unavailable, with
//! the reason.

mod catalogue;
mod common;
mod contact;
mod deadzone;
mod dynamic_nodes;
mod generic;
mod hand_contact;
mod model;
mod observer;

pub use catalogue::{PaperFigure, PAPER_FIGURES};
pub use common::contact_spans;
pub use common::short as short_name;
#[cfg(test)]
pub use model::Marker;
pub use model::{Figure, Line, Panel, Planned};

use admittance_dynamics::Model;

use crate::experiment::{has_hand_columns, Experiment};
use crate::folder::RunFolder;

/// The arm for the figures that need kinematics (Fig 7), or why it is not at hand.
pub type Arm<'a> = Result<&'a Model, String>;

/// Plans every figure the folder's experiment corresponds to. `arm` is the robot model
/// for the kinematic figures.
pub fn plan(folder: &RunFolder, arm: Arm<'_>) -> Vec<Planned> {
    let mut out = match Experiment::of(folder) {
        Experiment::Deadzone => deadzone::plan(folder, arm),
        Experiment::Admittance { .. } => observer::plan(folder, observer::Run::Admittance),
        Experiment::TrainingData => observer::plan(folder, observer::Run::Training),
        Experiment::ValidationData => observer::plan(folder, observer::Run::Validation),
        Experiment::DynamicNodes => dynamic_nodes::plan(folder),
        Experiment::HandContact => Vec::new(),
        Experiment::Other => generic::plan(folder),
    };
    if has_hand_columns(folder) {
        out.extend(hand_contact::plan(folder));
    }
    out.extend(contact::plan(folder));
    out
}

#[cfg(test)]
mod tests;
