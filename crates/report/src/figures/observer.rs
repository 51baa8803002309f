//! Experiment B, observer and admittance: Figs 13-20. Fig 13 comes from a run of
//! `free_motion` (the training data), Fig 14 from a run of `free_motion_validation` (the
//! validation data), Figs 15-20 from a run of `admittance`.

use admittance_runfolder::{columns, files};

use super::common::{
    compared, contact_joint, dashed, figure, joint_col, line, panel, planned, planned_joint, time,
    tracking, JOINT_COLORS, VARIANT_COLORS,
};
use super::model::{Figure, Line, Marker, Panel, Planned};
use crate::folder::{RunFolder, Variant};
use crate::number::setting;
use crate::table::Table;

/// Which run of experiment B a folder holds.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Run {
    /// `free_motion`: the observer's training data.
    Training,
    /// `free_motion_validation`: its validation data.
    Validation,
    /// `admittance` (or the MuJoCo co-simulation): the observers in the admittance loop.
    Admittance,
}

/// The learned observer of the paper, shown first where one variant is chosen.
const LEARNED: &str = "learned";
/// Fig 15's y axes are sized to the samples after this start-up time of the filters (s).
const FILTER_START: f64 = 1.0;

fn all_joints_panel(
    folder: &RunFolder,
    table: &Table,
    source: &str,
    title: String,
) -> Result<Panel, String> {
    let t = table
        .col(columns::TIME)
        .ok_or_else(|| format!("column `{}` is not in {source}", columns::TIME))?;
    let mut lines = Vec::new();
    for (k, j) in folder.joints.iter().enumerate() {
        let name = columns::joint(columns::POSITION, j);
        let q = table
            .col(&name)
            .ok_or_else(|| format!("column `{name}` is not in {source}"))?;
        lines.push(line(j.clone(), t, q, k % JOINT_COLORS, false));
    }
    Ok(panel(title, "angle (rad)", lines))
}

/// The joint angles of a free-motion data run: its `free_motion*.csv`, else its
/// variant's series.
fn data_run_angles(folder: &RunFolder) -> Option<(String, &Table)> {
    folder
        .free_motion
        .first()
        .map(|(n, t)| (n.clone(), t))
        .or_else(|| {
            folder
                .variants
                .first()
                .map(|v| (files::series(&v.name), &v.table))
        })
}

/// Fig 13 (training data) or Fig 14 (validation data): drawn only from the folder of the
/// run that made those data, so that the two never show the same trajectory.
fn trajectory(folder: &RunFolder, run: Run, wanted: Run) -> Result<Figure, String> {
    let (title, scenario) = match wanted {
        Run::Training => ("Fig. 13: free-motion training trajectory", "free_motion"),
        _ => ("Fig. 14: validation trajectory", "free_motion_validation"),
    };
    let found = if run == wanted {
        data_run_angles(folder)
    } else if wanted == Run::Validation {
        // A validation file that carries the angles of the validation data.
        folder
            .observer_validation
            .iter()
            .find(|(_, t)| {
                folder
                    .joints
                    .iter()
                    .all(|j| t.has(&columns::joint(columns::POSITION, j)))
            })
            .map(|(v, t)| (files::observer_validation(v), t))
    } else {
        None
    };
    let (name, table) = found.ok_or_else(|| {
        format!("the data are in the folder of `admittance run scenarios/{scenario}.toml`; this run does not write them")
    })?;
    Ok(figure(
        title,
        vec![all_joints_panel(
            folder,
            table,
            &name,
            format!("joint angles, {name}"),
        )?],
    ))
}

/// Fig 15: the network of a learned observer on its validation data, one panel per joint
/// (the paper's `learned` variant when the run has it).
fn validation_figure(folder: &RunFolder) -> Result<Figure, String> {
    let (name, table) = folder
        .observer_validation
        .iter()
        .find(|(n, _)| n == LEARNED)
        .or(folder.observer_validation.first())
        .ok_or("no validation_VARIANT.csv in the folder: it is written by runs with a learned observer (scenario admittance)")?;
    let file = files::observer_validation(name);
    let t = table
        .col(columns::TIME)
        .ok_or(format!("column `{}` is not in {file}", columns::TIME))?;
    let what = if name == "hybrid" {
        "nominal-model residual"
    } else {
        "torque"
    };
    let mut panels = Vec::new();
    for j in &folder.joints {
        let get = |prefix: &str| {
            let c = columns::joint(prefix, j);
            table
                .col(&c)
                .ok_or(format!("column `{c}` is not in {file}"))
        };
        let mut p = panel(
            format!("joint {j}, variant {name}"),
            "torque (N m)",
            vec![
                line(
                    format!("{what} (validation data)"),
                    t,
                    get(columns::VALIDATION_TARGET)?,
                    1,
                    false,
                ),
                line(
                    "network prediction",
                    t,
                    get(columns::VALIDATION_PREDICTION)?,
                    0,
                    true,
                ),
            ],
        );
        // The filters' start-up spike of the first samples would flatten the rest.
        p.y_fit_from = t.first().map(|t0| t0 + FILTER_START);
        panels.push(p);
    }
    Ok(figure(
        "Fig. 15: the observer's network on the validation data",
        panels,
    ))
}

/// `q_d` of joint `j` (dashed, from the first variant) and every variant's `q_r`.
fn adaptation_lines(variants: &[Variant], j: &str) -> Result<Vec<Line>, String> {
    let first = variants.first().ok_or("the run has no variants")?;
    let mut lines = vec![dashed(
        "desired q_d",
        time(first)?,
        joint_col(first, columns::DESIRED, j)?,
        0,
    )];
    for (k, v) in variants.iter().enumerate() {
        lines.push(line(
            format!("compliant q_r, {}", v.name),
            time(v)?,
            joint_col(v, columns::REFERENCE, j)?,
            VARIANT_COLORS[k % VARIANT_COLORS.len()],
            true,
        ));
    }
    Ok(lines)
}

/// The contact spans of the first variant (the environment's window is the scenario's).
fn with_contact(folder: &RunFolder, mut p: Panel, v: &Variant) -> Panel {
    p.spans = super::common::contact_spans(folder, v);
    p
}

fn fig16(folder: &RunFolder) -> Result<Figure, String> {
    let v = folder
        .variant(LEARNED)
        .or(folder.variants.first())
        .ok_or("the run has no variants")?;
    Ok(figure(
        "Fig. 16: test trajectory",
        vec![with_contact(
            folder,
            all_joints_panel(
                folder,
                &v.table,
                &files::series(&v.name),
                format!("joint angles, variant {}", v.name),
            )?,
            v,
        )],
    ))
}

fn fig17(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = contact_joint(folder)?;
    // One panel per variant: the true torque depends on how that variant's arm moved.
    let panels = folder
        .variants
        .iter()
        .map(|v| {
            let t = time(v)?;
            let p = panel(
                format!("joint {s}, variant {}", v.name),
                "torque (N m)",
                vec![
                    line(
                        "true tau_ext",
                        t,
                        joint_col(v, columns::EXTERNAL, j)?,
                        0,
                        false,
                    ),
                    line(
                        "estimate tau_ext_hat",
                        t,
                        joint_col(v, columns::EXTERNAL_ESTIMATE, j)?,
                        1,
                        true,
                    ),
                ],
            );
            Ok(with_contact(folder, p, v))
        })
        .collect::<Result<Vec<_>, String>>()?;
    if panels.is_empty() {
        return Err("the run has no variants".into());
    }
    Ok(compared(
        format!("Fig. 17: external torque on {s} and its estimate"),
        panels,
    ))
}

fn fig19(folder: &RunFolder) -> Result<Figure, String> {
    let (j, s) = contact_joint(folder)?;
    let panels = folder
        .variants
        .iter()
        .map(|v| Ok(with_contact(folder, tracking(v, j, columns::REFERENCE)?, v)))
        .collect::<Result<Vec<_>, String>>()?;
    if panels.is_empty() {
        return Err("the run has no variants".into());
    }
    Ok(compared(
        format!("Fig. 19: tracking of the compliant reference, joint {s}"),
        panels,
    ))
}

fn fig18_20(folder: &RunFolder, bounds: bool) -> Result<Figure, String> {
    let (j, s) = contact_joint(folder)?;
    let first = folder.variants.first().ok_or("the run has no variants")?;
    let mut p = with_contact(
        folder,
        panel(
            format!("joint {s}"),
            "angle (rad)",
            adaptation_lines(&folder.variants, j)?,
        ),
        first,
    );
    if !bounds {
        return Ok(figure(
            format!("Fig. 18: trajectory adaptation of joint {s}"),
            vec![p],
        ));
    }
    match folder.saturation_bounds(j) {
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() => {
            p.hlines = vec![
                Marker {
                    at: hi,
                    label: format!(
                        "bounds c ± C = [{}, {}] (the run's saturation)",
                        setting(lo),
                        setting(hi)
                    ),
                },
                Marker {
                    at: lo,
                    label: String::new(),
                },
            ];
        }
        _ => p
            .title
            .push_str(" (the run has no finite saturation bound on this joint)"),
    }
    Ok(figure(
        format!("Fig. 20: trajectory constraint on joint {s}"),
        vec![p],
    ))
}

/// Figs 13-15, and 16-20 for an admittance run.
pub fn plan(folder: &RunFolder, run: Run) -> Vec<Planned> {
    let mut out = vec![
        planned(
            13,
            "free_motion_training",
            trajectory(folder, run, Run::Training),
        ),
        planned(
            14,
            "validation_trajectory",
            trajectory(folder, run, Run::Validation),
        ),
        planned(15, "validation_performance", validation_figure(folder)),
    ];
    if run == Run::Admittance {
        let j = contact_joint(folder).map_or("", |(j, _)| j);
        out.extend([
            planned(16, "test_trajectory", fig16(folder)),
            planned_joint(17, "test_performance", j, fig17(folder)),
            planned_joint(18, "s0_adaptation", j, fig18_20(folder, false)),
            planned_joint(19, "s0_tracking", j, fig19(folder)),
            planned_joint(20, "s0_constraint", j, fig18_20(folder, true)),
        ]);
    }
    out
}
