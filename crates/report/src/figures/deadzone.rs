//! Experiment A, deadzone compensation: Figs 7-12 for the first deadzone of the run, and
//! Figs 11b, 12b for a second one (the wide deadzone of `scenarios/deadzone.toml`). The
//! variants are found by what they are (`crate::experiment::deadzone_groups`: the neural
//! controller with and without compensation on the same deadzone), not by their names; the
//! joint shown is the one with the deadzone (the worst tracked when several have one).

use admittance_dynamics::{forward_kinematics, Data, Model};
use admittance_runfolder::columns;

use super::common::{
    compared, extra, figure, joint_col, last_window, line, panel, planned_joint, short, time,
    tracking, variant,
};
use super::model::{Figure, Line, Marker, Panel, Planned};
use super::Arm;
use crate::experiment::{deadzone_groups, DeadzoneGroup};
use crate::folder::{RunFolder, Variant};
use crate::number::setting;

/// The variant of a group, or why the run lacks it.
fn member<'a>(name: &'a Option<String>, what: &str) -> Result<&'a str, String> {
    name.as_deref().ok_or_else(|| {
        format!("the run has no variant with the neural controller {what} on this deadzone")
    })
}

fn with_name(g: &DeadzoneGroup) -> Result<&str, String> {
    member(&g.with, "with deadzone compensation")
}

fn without_name(g: &DeadzoneGroup) -> Result<&str, String> {
    member(&g.without, "without deadzone compensation")
}

fn error_line(v: &Variant, j: &str, color: usize, thin: bool) -> Result<Line, String> {
    let r = joint_col(v, columns::REFERENCE, j)?;
    let q = joint_col(v, columns::POSITION, j)?;
    let e: Vec<f64> = r.iter().zip(q).map(|(a, b)| a - b).collect();
    Ok(line(
        format!("q_r - q, {}", v.name),
        time(v)?,
        &e,
        color,
        thin,
    ))
}

fn deadzone_band(folder: &RunFolder, variant: &str, joint: &str) -> Vec<Marker> {
    match folder.deadzone(variant, joint) {
        Some((l, r)) => vec![
            Marker {
                at: l,
                label: format!(
                    "deadzone [d_l, d_r] = [{}, {}] N m (as the plant applied it)",
                    setting(l),
                    setting(r)
                ),
            },
            Marker {
                at: r,
                label: String::new(),
            },
        ],
        None => Vec::new(),
    }
}

fn control_inputs(folder: &RunFolder, v: &Variant, j: &str) -> Result<Panel, String> {
    let t = time(v)?;
    let range = last_window(t, 6.0);
    // The run's own length when it is shorter than the paper's window.
    let span = match range {
        Some((a, b)) if b - a < 6.0 - 1e-9 => "whole run".to_string(),
        _ => "last 6 s".to_string(),
    };
    let mut p = panel(
        format!("joint {}, variant {}, {span}", short(j), v.name),
        "torque (N m)",
        vec![
            line(
                "commanded tau (controller output)",
                t,
                joint_col(v, columns::COMMAND, j)?,
                0,
                false,
            ),
            line(
                "applied D(tau) (after the deadzone)",
                t,
                joint_col(v, columns::APPLIED, j)?,
                1,
                true,
            ),
        ],
    );
    p.hlines = deadzone_band(folder, &v.name, j);
    p.x_range = range;
    Ok(p)
}

fn ee_positions(
    model: &Model,
    v: &Variant,
    joints: &[String],
    prefix: &str,
) -> Result<[Vec<f64>; 3], String> {
    let cols: Vec<&[f64]> = joints
        .iter()
        .map(|j| joint_col(v, prefix, j))
        .collect::<Result<_, _>>()?;
    let mut data = Data::new(model);
    let mut q = vec![0.0; joints.len()];
    let mut out = [Vec::new(), Vec::new(), Vec::new()];
    for k in 0..v.table.rows() {
        for (qi, c) in q.iter_mut().zip(&cols) {
            *qi = c[k];
        }
        // A row the kinematics refuses (non-finite angles) is a gap in the figure.
        let p = match forward_kinematics(model, &mut data, &q) {
            Ok(()) => {
                let p = data.frame_placements[model.tip_frame].translation;
                [p[0], p[1], p[2]]
            }
            Err(_) => [f64::NAN; 3],
        };
        for a in 0..3 {
            out[a].push(p[a]);
        }
    }
    Ok(out)
}

fn fig7(folder: &RunFolder, g: &DeadzoneGroup, arm: Arm<'_>) -> Result<Figure, String> {
    let v = variant(folder, with_name(g)?)?;
    let model = arm?;
    let names: Vec<&str> = model.joint_names().collect();
    if names.len() != folder.joints.len() || names.iter().zip(&folder.joints).any(|(a, b)| *a != b)
    {
        return Err(format!(
            "the URDF's joints [{}] are not the run's [{}]",
            names.join(", "),
            folder.joints.join(", ")
        ));
    }
    let t = time(v)?;
    let desired = ee_positions(model, v, &folder.joints, columns::DESIRED)?;
    let actual = ee_positions(model, v, &folder.joints, columns::POSITION)?;
    let panels = columns::AXES
        .iter()
        .enumerate()
        .map(|(a, axis)| {
            panel(
                format!("hand {axis} (base frame), variant {}", v.name),
                &format!("{axis} (m)"),
                vec![
                    line("desired: FK(q_d)", t, &desired[a], 0, false),
                    line("actual: FK(q)", t, &actual[a], 1, true),
                ],
            )
        })
        .collect();
    Ok(figure(
        "Fig. 7: tracking performance of the end-effector",
        panels,
    ))
}

/// Fig 8: the y axis is sized to the evaluation window, so that the start-up transient
/// does not flatten the steady error.
fn fig8(folder: &RunFolder, g: &DeadzoneGroup) -> Result<Figure, String> {
    let with = variant(folder, with_name(g)?)?;
    let mut lines = vec![line(
        format!("|p_r - p|, {}", with.name),
        time(with)?,
        super::common::col(with, columns::HAND_ERROR)?,
        1,
        false,
    )];
    if let Ok(without) = without_name(g).and_then(|n| variant(folder, n)) {
        lines.push(line(
            format!("|p_r - p|, {}", without.name),
            time(without)?,
            super::common::col(without, columns::HAND_ERROR)?,
            0,
            true,
        ));
    }
    let from = folder.evaluation_start();
    let mut p = panel(
        format!("hand position error (FK of q_r against FK of q); y axis fitted to t ≥ {from} s (evaluation window)"),
        "error (m)",
        lines,
    );
    p.y_fit_from = Some(from);
    Ok(figure(
        "Fig. 8: tracking error of the end-effector",
        vec![p],
    ))
}

fn errors(folder: &RunFolder, g: &DeadzoneGroup, number: &str) -> Result<Figure, String> {
    let (j, s) = (g.joint.as_str(), short(&g.joint));
    let (va, vb) = (
        variant(folder, with_name(g)?)?,
        variant(folder, without_name(g)?)?,
    );
    let from = folder.evaluation_start();
    let mut p = panel(
        format!("joint {s}; y axis fitted to t ≥ {from} s (evaluation window)"),
        "tracking error (rad)",
        vec![error_line(vb, j, 0, false)?, error_line(va, j, 1, true)?],
    );
    // Like Fig 8: the start-up transient would flatten the steady error.
    p.y_fit_from = Some(from);
    Ok(figure(
        format!("Fig. {number}: tracking errors of joint {s} with/without NN compensation"),
        vec![p],
    ))
}

fn inputs(folder: &RunFolder, g: &DeadzoneGroup, number: &str) -> Result<Figure, String> {
    let (j, s) = (g.joint.as_str(), short(&g.joint));
    let (va, vb) = (
        variant(folder, with_name(g)?)?,
        variant(folder, without_name(g)?)?,
    );
    Ok(compared(
        format!("Fig. {number}: control inputs of joint {s}"),
        vec![
            control_inputs(folder, va, j)?,
            control_inputs(folder, vb, j)?,
        ],
    ))
}

fn joint_tracking(
    folder: &RunFolder,
    g: &DeadzoneGroup,
    name: Result<&str, String>,
    title: &str,
) -> Result<Figure, String> {
    let (j, s) = (g.joint.as_str(), short(&g.joint));
    Ok(figure(
        format!("{title} {s}"),
        vec![tracking(variant(folder, name?)?, j, columns::DESIRED)?],
    ))
}

/// Figs 7-12 (and 11b, 12b).
pub fn plan(folder: &RunFolder, arm: Arm<'_>) -> Vec<Planned> {
    let groups = deadzone_groups(folder);
    let Some(g) = groups.first() else {
        let why = || Err("the run has no variant with an actuator deadzone".to_string());
        return [
            (7, "end_effector"),
            (8, "end_effector_error"),
            (9, "s0_with_compensation"),
            (10, "s0_without_compensation"),
            (11, "s0_errors"),
            (12, "s0_control_inputs"),
        ]
        .into_iter()
        .map(|(n, stem)| super::common::planned(n, stem, why()))
        .collect();
    };
    let j = g.joint.as_str();
    let mut out = vec![
        planned_joint(7, "end_effector", j, fig7(folder, g, arm)),
        planned_joint(8, "end_effector_error", j, fig8(folder, g)),
        planned_joint(
            9,
            "s0_with_compensation",
            j,
            joint_tracking(
                folder,
                g,
                with_name(g),
                "Fig. 9: tracking with NN compensation, joint",
            ),
        ),
        planned_joint(
            10,
            "s0_without_compensation",
            j,
            joint_tracking(
                folder,
                g,
                without_name(g),
                "Fig. 10: tracking without NN compensation, joint",
            ),
        ),
        planned_joint(11, "s0_errors", j, errors(folder, g, "11")),
        planned_joint(12, "s0_control_inputs", j, inputs(folder, g, "12")),
    ];
    if let Some(b) = groups
        .get(1)
        .filter(|b| b.with.is_some() && b.without.is_some())
    {
        let band = folder
            .deadzone(b.with.as_deref().unwrap_or_default(), &b.joint)
            .map_or(String::new(), |(l, r)| {
                format!(", deadzone [{}, {}] N m", setting(l), setting(r))
            });
        let data = format!(
            "the same columns of {}, {} (joint {}{band})",
            b.with.as_deref().unwrap_or_default(),
            b.without.as_deref().unwrap_or_default(),
            short(&b.joint)
        );
        out.push(extra(
            "11b",
            "fig11b_s0_errors_wide",
            "Fig. 11 for the run's second deadzone (not in the paper).",
            &data,
            errors(folder, b, "11b"),
        ));
        out.push(extra(
            "12b",
            "fig12b_s0_control_inputs_wide",
            "Fig. 12 for the run's second deadzone (not in the paper).",
            &data,
            inputs(folder, b, "12b"),
        ));
    }
    out
}
