//! Scenarios that are none of the paper's experiments: tracking and commanded torque of
//! the worst-tracked joint (S1, S2) and the tracking error of every joint (S3), every
//! variant.

use admittance_runfolder::columns;

use super::common::{
    extra, figure, joint_col, line, panel, short, time, tracking, worst_joint, JOINT_COLORS,
};
use super::model::{Figure, Planned};
use crate::folder::RunFolder;

fn tracking_figure(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = worst_joint(folder)?;
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
    Ok(figure(
        format!("Tracking of joint {s} (the largest tracking RMSE)"),
        panels,
    ))
}

fn torque_figure(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = worst_joint(folder)?;
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

/// `q_r - q` of every joint, one panel per variant, the y axis fitted to the evaluation
/// window.
fn errors_figure(folder: &RunFolder) -> Result<Figure, String> {
    let from = folder.evaluation_start();
    let panels = folder
        .variants
        .iter()
        .map(|v| {
            let t = time(v)?;
            let lines = folder
                .joints
                .iter()
                .enumerate()
                .map(|(k, j)| {
                    let r = joint_col(v, columns::REFERENCE, j)?;
                    let q = joint_col(v, columns::POSITION, j)?;
                    let e: Vec<f64> = r.iter().zip(q).map(|(a, b)| a - b).collect();
                    Ok(line(short(j), t, &e, k % JOINT_COLORS, false))
                })
                .collect::<Result<Vec<_>, String>>()?;
            let mut p = panel(
                format!(
                    "variant {}; y axis fitted to t ≥ {from} s (evaluation window)",
                    v.name
                ),
                "q_r - q (rad)",
                lines,
            );
            p.y_fit_from = Some(from);
            Ok(p)
        })
        .collect::<Result<Vec<_>, String>>()?;
    if panels.is_empty() {
        return Err("the run has no variants".into());
    }
    Ok(figure("Tracking error of every joint", panels))
}

/// S1, S2 and S3.
pub fn plan(folder: &RunFolder) -> Vec<Planned> {
    vec![
        extra(
            "S1",
            "s1_worst_joint_tracking",
            "Tracking of the joint with the largest tracking RMSE, every variant (the scenario is none of the paper's experiments).",
            "q_r and q of that joint",
            tracking_figure(folder),
        ),
        extra(
            "S2",
            "s2_worst_joint_torque",
            "Commanded torque of the same joint, every variant.",
            "tau_cmd of that joint",
            torque_figure(folder),
        ),
        extra(
            "S3",
            "s3_tracking_errors",
            "Tracking error of every joint, one panel per variant.",
            "q_r - q of every joint",
            errors_figure(folder),
        ),
    ]
}
