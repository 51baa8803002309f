//! Scenarios that are none of the paper's experiments: tracking and commanded torque of
//! the first joint, every variant (S1, S2).

use admittance_runfolder::columns;

use super::common::{extra, figure, joint0, joint_col, line, panel, time, tracking, JOINT_COLORS};
use super::model::{Figure, Planned};
use crate::folder::RunFolder;

fn tracking_figure(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = joint0(folder)?;
    let panels = folder
        .variants
        .iter()
        .map(|v| {
            let mut p = tracking(v, j, columns::REFERENCE)?;
            p.spans = super::common::contact_spans(folder, v);
            Ok(p)
        })
        .collect::<Result<Vec<_>, String>>()?;
    if panels.is_empty() {
        return Err("the run has no variants".into());
    }
    Ok(figure(format!("Tracking of joint {s}"), panels))
}

fn torque_figure(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = joint0(folder)?;
    let lines = folder
        .variants
        .iter()
        .enumerate()
        .map(|(k, v)| {
            Ok(line(
                v.name.clone(),
                time(v)?,
                joint_col(v, columns::COMMAND, j)?,
                k % JOINT_COLORS,
                false,
            ))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(figure(
        format!("Commanded torque of joint {s}"),
        vec![panel(format!("joint {s}"), "torque (N m)", lines)],
    ))
}

/// S1 and S2.
pub fn plan(folder: &RunFolder) -> Vec<Planned> {
    vec![
        extra(
            "S1",
            "s1_joint0_tracking",
            "Tracking of the first joint, every variant (the scenario is not one of the paper's experiments).",
            "q_r and q of the first joint",
            tracking_figure(folder),
        ),
        extra(
            "S2",
            "s2_joint0_torque",
            "Commanded torque of the first joint, every variant.",
            "tau_cmd of the first joint",
            torque_figure(folder),
        ),
    ]
}
