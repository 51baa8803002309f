//! Which figure of the paper comes from which columns of a run folder, and the figures
//! themselves as data (panels of lines), ready to draw.
//!
//! Experiment A (scenario `deadzone`) gives Figs 7-12, B (`admittance`, and
//! `free_motion` for the training data) Figs 13-20, C (`dynamic_nodes`) Figs 21-26. A
//! figure whose data is not in the folder is planned as unavailable, with the reason.

use admittance_dynamics::{forward_kinematics, Data, Model};

use crate::folder::{RunFolder, Variant};

/// A figure of the paper: its number, the scenario that produces it and its caption.
#[derive(Clone, Copy, Debug)]
pub struct PaperFigure {
    /// Figure number in the paper.
    pub number: u32,
    /// The scenario (experiment) whose run folder holds its data.
    pub scenario: &'static str,
    /// The paper's caption.
    pub caption: &'static str,
    /// The data it shows, in terms of this project's outputs.
    pub data: &'static str,
}

/// Figs 7-26 of the paper and where their data lives.
pub const PAPER_FIGURES: &[PaperFigure] = &[
    PaperFigure { number: 7, scenario: "deadzone", caption: "The tracking performance of the end-effector.", data: "hand position from forward kinematics of q_d.* and q.* (nn_compensated), needs the URDF" },
    PaperFigure { number: 8, scenario: "deadzone", caption: "The tracking error of the end-effector.", data: "ee_error (nn_compensated, nn_uncompensated)" },
    PaperFigure { number: 9, scenario: "deadzone", caption: "The tracking performance of joint s0 with NN compensation.", data: "q_d.s0, q.s0 (nn_compensated)" },
    PaperFigure { number: 10, scenario: "deadzone", caption: "The tracking performance of joint s0 without NN compensation.", data: "q_d.s0, q.s0 (nn_uncompensated)" },
    PaperFigure { number: 11, scenario: "deadzone", caption: "The tracking errors of joint s0 with/without NN compensation.", data: "q_r.s0 - q.s0 (nn_compensated, nn_uncompensated)" },
    PaperFigure { number: 12, scenario: "deadzone", caption: "The control inputs of joint s0.", data: "tau_cmd.s0, tau_applied.s0 and the deadzone band (nn_compensated, nn_uncompensated)" },
    PaperFigure { number: 13, scenario: "admittance", caption: "The free-motion training trajectory.", data: "q.* of a run of scenario free_motion" },
    PaperFigure { number: 14, scenario: "admittance", caption: "The validation trajectory.", data: "q.* of a run of scenario free_motion_validation" },
    PaperFigure { number: 15, scenario: "admittance", caption: "The validation performance with proposed observer.", data: "target.* and prediction.* of validation_VARIANT.csv (the paper's `learned` first)" },
    PaperFigure { number: 16, scenario: "admittance", caption: "The test trajectory.", data: "q.* of the run" },
    PaperFigure { number: 17, scenario: "admittance", caption: "The test performance with proposed observer.", data: "tau_ext.s0 and tau_ext_hat.s0, one panel per variant" },
    PaperFigure { number: 18, scenario: "admittance", caption: "The trajectory adaptation of joint s0.", data: "q_d.s0 and q_r.s0 of every variant" },
    PaperFigure { number: 19, scenario: "admittance", caption: "The trajectory tracking of joint s0.", data: "q_r.s0 and q.s0 of every variant" },
    PaperFigure { number: 20, scenario: "admittance", caption: "The performance of trajectory constraint.", data: "q_r.s0 against the saturation bounds centre +- half_range of scenario.toml" },
    PaperFigure { number: 21, scenario: "dynamic_nodes", caption: "The function approximation with 512 NN nodes and 304 NN nodes.", data: "f.s0, f_hat.s0 in the windows before discard and before growth (nodes.f finds them)" },
    PaperFigure { number: 22, scenario: "dynamic_nodes", caption: "The convergence of NN weight with 512 NN nodes.", data: "w.ID of weights_VARIANT.csv (norm of each node's weight row)" },
    PaperFigure { number: 23, scenario: "dynamic_nodes", caption: "The convergence of NN weight with 304 NN nodes.", data: "w.ID of weights_VARIANT.csv (norm of each node's weight row)" },
    PaperFigure { number: 24, scenario: "dynamic_nodes", caption: "The function approximation with dynamic RBFNN learning framework.", data: "f.s0, f_hat.s0 in the last window, after growth" },
    PaperFigure { number: 25, scenario: "dynamic_nodes", caption: "The convergence of NN weight with 304 NN nodes under dynamic RBFNN learning framework.", data: "w.ID of weights_VARIANT.csv (norm of each node's weight row)" },
    PaperFigure { number: 26, scenario: "dynamic_nodes", caption: "The convergence of NN weight of 100 new NN nodes.", data: "w.ID of weights_VARIANT.csv (norm of each node's weight row)" },
];

/// Why the weight figures cannot be drawn.
const NO_WEIGHTS: &str = "the run folder has no weights_VARIANT.csv (per-node weight norms; written by runs with dynamic nodes)";

/// Which nodes a weight figure shows.
#[derive(Clone, Copy)]
enum NodeSelection {
    /// Nodes that existed at the start of the run.
    Initial,
    /// Nodes that did not exist at the start (grown).
    New,
}

/// A weight-convergence panel (Figs 22, 23, 25, 26): the norm of each selected node's
/// weight row over `[from, to]`, for the nodes that exist throughout that window.
fn weights_panel(
    table: &crate::table::Table,
    range: (f64, f64),
    select: NodeSelection,
    what: &str,
) -> Result<Panel, String> {
    let t = table
        .col("t")
        .ok_or("column `t` is not in the weights file")?;
    let rows: Vec<usize> = (0..t.len())
        .filter(|&k| t[k] >= range.0 && t[k] <= range.1)
        .collect();
    let (Some(&first), Some(&last)) = (rows.first(), rows.last()) else {
        return Err(format!(
            "no weight samples between {:.1} and {:.1} s",
            range.0, range.1
        ));
    };
    let mut lines = Vec::new();
    for name in table.columns.iter().filter(|c| c.starts_with("w.")) {
        let Some(w) = table.col(name) else { continue };
        let initial = w.first().is_some_and(|v| v.is_finite());
        let wanted = match select {
            NodeSelection::Initial => initial,
            NodeSelection::New => !initial,
        };
        if !wanted || !w[first].is_finite() || !w[last].is_finite() {
            continue;
        }
        let (x, y): (Vec<f64>, Vec<f64>) = rows
            .iter()
            .filter(|&&k| w[k].is_finite())
            .map(|&k| (t[k], w[k]))
            .unzip();
        lines.push(line("", &x, &y, lines.len() % 8, true));
    }
    if lines.is_empty() {
        return Err(format!(
            "no {what} exist from {:.1} to {:.1} s",
            range.0, range.1
        ));
    }
    let mut p = panel(
        format!("{} {what}, {:.0}-{:.0} s", lines.len(), range.0, range.1),
        "|W_i| (weight row norm)",
        lines,
    );
    p.x_range = Some(range);
    Ok(p)
}

/// One line of a panel.
#[derive(Clone, Debug)]
pub struct Line {
    /// Legend entry.
    pub label: String,
    /// x values (time, s).
    pub x: Vec<f64>,
    /// y values.
    pub y: Vec<f64>,
    /// Palette index (0 blue, 1 red, 2 green, 3 orange, 4 purple, 5 grey, 6 brown, 7 cyan).
    pub color: usize,
    /// Drawn thinner, on top of the lines before it (the second of a compared pair).
    pub thin: bool,
}

/// A horizontal or vertical marker line with a label.
#[derive(Clone, Debug)]
pub struct Marker {
    /// Where (y for horizontal, x for vertical markers).
    pub at: f64,
    /// Legend text.
    pub label: String,
}

/// One chart: axes, lines and markers.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// The lines.
    pub lines: Vec<Line>,
    /// Horizontal markers (bounds, bands).
    pub hlines: Vec<Marker>,
    /// Vertical markers (events).
    pub vlines: Vec<Marker>,
    /// Shown x range (default: the data's).
    pub x_range: Option<(f64, f64)>,
}

/// A figure: a title and panels stacked vertically.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Title.
    pub title: String,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

/// A figure the report will show, or the reason it cannot.
#[derive(Clone, Debug)]
pub struct Planned {
    /// Its number in the report: the paper's (`"12"`) or a supplementary one (`"12b"`, `"S1"`).
    pub id: String,
    /// Base name of its files (`figures/STEM.png`, `figures/STEM.svg`).
    pub stem: String,
    /// Caption.
    pub caption: String,
    /// The data it shows (columns and variants).
    pub data: String,
    /// The figure, or why it is not available.
    pub figure: Result<Figure, String>,
}

/// The arm for the figures that need kinematics (Fig 7), or why it is not at hand.
pub type Arm<'a> = Result<&'a Model, String>;

fn variant<'a>(folder: &'a RunFolder, name: &str) -> Result<&'a Variant, String> {
    folder.variant(name).ok_or_else(|| {
        format!(
            "variant `{name}` is not in this run (it has: {})",
            folder
                .variants
                .iter()
                .map(|v| v.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

fn col<'a>(v: &'a Variant, name: &str) -> Result<&'a [f64], String> {
    v.table
        .col(name)
        .ok_or_else(|| format!("column `{name}` is not in {}.csv", v.name))
}

fn line(label: impl Into<String>, x: &[f64], y: &[f64], color: usize, thin: bool) -> Line {
    Line {
        label: label.into(),
        x: x.to_vec(),
        y: y.to_vec(),
        color,
        thin,
    }
}

fn panel(title: impl Into<String>, y_label: &str, lines: Vec<Line>) -> Panel {
    Panel {
        title: title.into(),
        x_label: "time (s)".into(),
        y_label: y_label.into(),
        lines,
        ..Panel::default()
    }
}

fn figure(title: impl Into<String>, panels: Vec<Panel>) -> Figure {
    Figure {
        title: title.into(),
        panels,
    }
}

fn paper(number: u32) -> &'static PaperFigure {
    PAPER_FIGURES
        .iter()
        .find(|f| f.number == number)
        .expect("figure number in the catalogue")
}

fn planned(number: u32, stem: &str, figure: Result<Figure, String>) -> Planned {
    let p = paper(number);
    Planned {
        id: number.to_string(),
        stem: format!("fig{number:02}_{stem}"),
        caption: p.caption.replace("s0", "s_0"),
        data: p.data.to_string(),
        figure,
    }
}

/// Plans every figure the folder's scenario corresponds to. `arm` is the robot model for
/// the kinematic figures.
pub fn plan(folder: &RunFolder, arm: Arm<'_>) -> Vec<Planned> {
    match folder.scenario.as_str() {
        "deadzone" => plan_a(folder, arm),
        "admittance" => plan_b(folder, BRun::Admittance),
        "free_motion" => plan_b(folder, BRun::Training),
        "free_motion_validation" => plan_b(folder, BRun::Validation),
        "dynamic_nodes" => plan_c(folder),
        _ => plan_generic(folder),
    }
}

/// The first joint (the paper's s0) and the short name used in labels.
fn joint0(folder: &RunFolder) -> Result<(&str, String), String> {
    let j = folder
        .joints
        .first()
        .ok_or_else(|| "summary.json lists no joints".to_string())?;
    let short = j
        .strip_prefix("left_")
        .or_else(|| j.strip_prefix("right_"))
        .unwrap_or(j);
    Ok((j.as_str(), short.to_string()))
}

fn tracking(v: &Variant, j: &str, short: &str, desired: &str) -> Result<Panel, String> {
    let t = col(v, "t")?;
    let d = col(v, &format!("{desired}.{j}"))?;
    let q = col(v, &format!("q.{j}"))?;
    let name = if desired == "q_d" {
        "desired q_d"
    } else {
        "reference q_r"
    };
    Ok(panel(
        format!("joint {short}, variant {}", v.name),
        "angle (rad)",
        vec![line(name, t, d, 0, false), line("actual q", t, q, 1, true)],
    ))
}

fn error_line(v: &Variant, j: &str, color: usize, thin: bool) -> Result<Line, String> {
    let t = col(v, "t")?;
    let r = col(v, &format!("q_r.{j}"))?;
    let q = col(v, &format!("q.{j}"))?;
    let e: Vec<f64> = r.iter().zip(q).map(|(a, b)| a - b).collect();
    Ok(line(format!("q_r - q, {}", v.name), t, &e, color, thin))
}

fn deadzone_band(folder: &RunFolder, variant: &str, joint: &str) -> Vec<Marker> {
    let Some(list) = folder
        .variant_value(variant, "plant.deadzones")
        .and_then(toml::Value::as_array)
    else {
        return Vec::new();
    };
    let num =
        |v: Option<&toml::Value>| v.and_then(|x| x.as_float().or(x.as_integer().map(|i| i as f64)));
    let Some(d) = list
        .iter()
        .filter_map(toml::Value::as_table)
        .find(|d| d.get("joint").and_then(toml::Value::as_str) == Some(joint))
    else {
        return Vec::new();
    };
    match (num(d.get("d_left")), num(d.get("d_right"))) {
        (Some(l), Some(r)) => vec![
            Marker {
                at: l,
                label: format!("deadzone [d_l, d_r] = [{l}, {r}] N m (scenario.toml)"),
            },
            Marker {
                at: r,
                label: String::new(),
            },
        ],
        _ => Vec::new(),
    }
}

/// The last `seconds` of a time column, as an x range.
fn last_window(t: &[f64], seconds: f64) -> Option<(f64, f64)> {
    let end = *t.last()?;
    Some(((end - seconds).max(t[0]), end))
}

fn control_inputs(folder: &RunFolder, v: &Variant, j: &str, short: &str) -> Result<Panel, String> {
    let t = col(v, "t")?;
    let cmd = col(v, &format!("tau_cmd.{j}"))?;
    let applied = col(v, &format!("tau_applied.{j}"))?;
    let mut p = panel(
        format!("joint {short}, variant {}, last 6 s", v.name),
        "torque (N m)",
        vec![
            line("commanded tau (controller output)", t, cmd, 0, false),
            line("applied D(tau) (after the deadzone)", t, applied, 1, true),
        ],
    );
    p.hlines = deadzone_band(folder, &v.name, j);
    p.x_range = last_window(t, 6.0);
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
        .map(|j| col(v, &format!("{prefix}.{j}")))
        .collect::<Result<_, _>>()?;
    let mut data = Data::new(model);
    let mut q = vec![0.0; joints.len()];
    let mut out = [Vec::new(), Vec::new(), Vec::new()];
    for k in 0..v.table.rows() {
        for (qi, c) in q.iter_mut().zip(&cols) {
            *qi = c[k];
        }
        forward_kinematics(model, &mut data, &q).map_err(|e| e.to_string())?;
        let p = data.frame_placements[model.tip_frame].translation;
        for a in 0..3 {
            out[a].push(p[a]);
        }
    }
    Ok(out)
}

fn fig7(folder: &RunFolder, arm: Arm<'_>) -> Result<Figure, String> {
    let v = variant(folder, "nn_compensated")?;
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
    let t = col(v, "t")?;
    let desired = ee_positions(model, v, &folder.joints, "q_d")?;
    let actual = ee_positions(model, v, &folder.joints, "q")?;
    let panels = ["x", "y", "z"]
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

fn plan_a(folder: &RunFolder, arm: Arm<'_>) -> Vec<Planned> {
    let j = joint0(folder);
    let with = || variant(folder, "nn_compensated");
    let without = || variant(folder, "nn_uncompensated");
    let mut out = vec![planned(7, "end_effector", fig7(folder, arm))];
    out.push(planned(
        8,
        "end_effector_error",
        (|| {
            let w = with()?;
            let mut lines = vec![line(
                format!("|p_r - p|, {}", w.name),
                col(w, "t")?,
                col(w, "ee_error")?,
                1,
                false,
            )];
            if let Ok(wo) = without() {
                lines.push(line(
                    format!("|p_r - p|, {}", wo.name),
                    col(wo, "t")?,
                    col(wo, "ee_error")?,
                    0,
                    true,
                ));
            }
            Ok(figure(
                "Fig. 8: tracking error of the end-effector",
                vec![panel(
                    "hand position error (FK of q_r against FK of q)",
                    "error (m)",
                    lines,
                )],
            ))
        })(),
    ));
    out.push(planned(
        9,
        "s0_with_compensation",
        (|| {
            let (j, short) = j.clone()?;
            Ok(figure(
                format!("Fig. 9: tracking of joint {short} with NN compensation"),
                vec![tracking(with()?, j, &short, "q_d")?],
            ))
        })(),
    ));
    out.push(planned(
        10,
        "s0_without_compensation",
        (|| {
            let (j, short) = j.clone()?;
            Ok(figure(
                format!("Fig. 10: tracking of joint {short} without NN compensation"),
                vec![tracking(without()?, j, &short, "q_d")?],
            ))
        })(),
    ));
    let errors = |a: &str, b: &str, number: &str| -> Result<Figure, String> {
        let (j, short) = j.clone()?;
        let (va, vb) = (variant(folder, a)?, variant(folder, b)?);
        Ok(figure(
            format!("Fig. {number}: tracking errors of joint {short} with/without NN compensation"),
            vec![panel(
                format!("joint {short}"),
                "tracking error (rad)",
                vec![error_line(vb, j, 0, false)?, error_line(va, j, 1, true)?],
            )],
        ))
    };
    out.push(planned(
        11,
        "s0_errors",
        errors("nn_compensated", "nn_uncompensated", "11"),
    ));
    let inputs = |a: &str, b: &str, number: &str| -> Result<Figure, String> {
        let (j, short) = j.clone()?;
        let (va, vb) = (variant(folder, a)?, variant(folder, b)?);
        Ok(figure(
            format!("Fig. {number}: control inputs of joint {short}"),
            vec![
                control_inputs(folder, va, j, &short)?,
                control_inputs(folder, vb, j, &short)?,
            ],
        ))
    };
    out.push(planned(
        12,
        "s0_control_inputs",
        inputs("nn_compensated", "nn_uncompensated", "12"),
    ));
    // The wide-deadzone pair, when the run has it: Figs 11 and 12 again.
    if folder.variant("nn_compensated_wide").is_some()
        && folder.variant("nn_uncompensated_wide").is_some()
    {
        for (number, stem, fig) in [
            (
                "11b",
                "fig11b_s0_errors_wide",
                errors("nn_compensated_wide", "nn_uncompensated_wide", "11b"),
            ),
            (
                "12b",
                "fig12b_s0_control_inputs_wide",
                inputs("nn_compensated_wide", "nn_uncompensated_wide", "12b"),
            ),
        ] {
            out.push(Planned {
                id: number.into(),
                stem: stem.into(),
                caption: format!(
                    "Fig. {} for the wide deadzone pair (not in the paper).",
                    &number[..2]
                ),
                data: "the same columns of nn_compensated_wide, nn_uncompensated_wide".into(),
                figure: fig,
            });
        }
    }
    out
}

const JOINT_COLORS: usize = 8;
/// Palette indices for one line per variant beside a blue `q_d` (no blue, no grey).
const VARIANT_COLORS: [usize; 6] = [1, 2, 3, 4, 6, 7];

fn all_joints_panel(
    folder: &RunFolder,
    table: &crate::table::Table,
    source: &str,
    title: String,
    rows: std::ops::Range<usize>,
) -> Result<Panel, String> {
    let t = table
        .col("t")
        .ok_or_else(|| format!("column `t` is not in {source}"))?;
    let mut lines = Vec::new();
    for (k, j) in folder.joints.iter().enumerate() {
        let q = table
            .col(&format!("q.{j}"))
            .ok_or_else(|| format!("column `q.{j}` is not in {source}"))?;
        lines.push(line(
            j.clone(),
            &t[rows.clone()],
            &q[rows.clone()],
            k % JOINT_COLORS,
            false,
        ));
    }
    Ok(panel(title, "angle (rad)", lines))
}

/// Variant order for experiment B: the learned observers first (the paper's "proposed
/// observer"), then `hybrid`, the others, and `oracle` last.
fn b_variants(folder: &RunFolder) -> Vec<&Variant> {
    let mut v: Vec<&Variant> = folder.variants.iter().collect();
    v.sort_by_key(|x| match x.name.as_str() {
        n if n.starts_with("learned") => 0,
        "hybrid" => 1,
        "oracle" => 3,
        _ => 2,
    });
    v
}

fn first_of(value: Option<&toml::Value>) -> Option<f64> {
    let v = value?;
    let v = v.as_array().and_then(|a| a.first()).unwrap_or(v);
    v.as_float().or(v.as_integer().map(|i| i as f64))
}

/// Which run of experiment B a folder holds.
#[derive(Clone, Copy, PartialEq, Eq)]
enum BRun {
    /// `free_motion`: the observer's training data.
    Training,
    /// `free_motion_validation`: its validation data.
    Validation,
    /// `admittance`: the observers in the admittance loop.
    Admittance,
}

/// The joint angles of a free-motion run: its `free_motion*.csv`, else its variant's CSV.
fn free_motion_angles(folder: &RunFolder) -> Option<(String, &crate::table::Table)> {
    folder
        .free_motion
        .first()
        .map(|(n, t)| (n.clone(), t))
        .or_else(|| {
            folder
                .variants
                .first()
                .map(|v| (format!("{}.csv", v.name), &v.table))
        })
}

/// Fig 15: the network of a learned observer on its validation data, one panel per joint
/// (the paper's `learned` variant when the run has it).
fn validation_figure(folder: &RunFolder) -> Result<Figure, String> {
    let (name, table) = folder
        .observer_validation
        .iter()
        .find(|(n, _)| n == "learned")
        .or(folder.observer_validation.first())
        .ok_or("no validation_VARIANT.csv in the folder: it is written by runs with a learned observer (scenario admittance)")?;
    let t = table
        .col("t")
        .ok_or(format!("column `t` is not in validation_{name}.csv"))?;
    let what = if name == "hybrid" {
        "nominal-model residual"
    } else {
        "torque"
    };
    let mut panels = Vec::new();
    for j in &folder.joints {
        let get = |c: String| {
            table
                .col(&c)
                .ok_or(format!("column `{c}` is not in validation_{name}.csv"))
        };
        panels.push(panel(
            format!("joint {j}, variant {name}"),
            "torque (N m)",
            vec![
                line(
                    format!("{what} (validation data)"),
                    t,
                    get(format!("target.{j}"))?,
                    1,
                    false,
                ),
                line(
                    "network prediction",
                    t,
                    get(format!("prediction.{j}"))?,
                    0,
                    true,
                ),
            ],
        ));
    }
    Ok(figure(
        "Fig. 15: the observer's network on the validation data",
        panels,
    ))
}

/// `q_d` of joint `j` (from the first variant) and every variant's `q_r` (Figs 18, 20).
fn adaptation_lines(variants: &[&Variant], j: &str) -> Result<Vec<Line>, String> {
    let first = variants.first().ok_or("the run has no variants")?;
    let mut lines = vec![line(
        "desired q_d",
        col(first, "t")?,
        col(first, &format!("q_d.{j}"))?,
        0,
        false,
    )];
    for (k, v) in variants.iter().enumerate() {
        lines.push(line(
            format!("compliant q_r, {}", v.name),
            col(v, "t")?,
            col(v, &format!("q_r.{j}"))?,
            VARIANT_COLORS[k % VARIANT_COLORS.len()],
            true,
        ));
    }
    Ok(lines)
}

fn plan_b(folder: &RunFolder, run: BRun) -> Vec<Planned> {
    let angles = |title: &str, wanted: BRun, elsewhere: &str| -> Result<Figure, String> {
        let found = if run == wanted {
            free_motion_angles(folder)
        } else {
            folder.free_motion.first().map(|(n, t)| (n.clone(), t))
        };
        let (name, table) = found.ok_or_else(|| elsewhere.to_string())?;
        Ok(figure(
            title,
            vec![all_joints_panel(
                folder,
                table,
                &name,
                format!("joint angles, {name}"),
                0..table.rows(),
            )?],
        ))
    };
    let mut out = vec![planned(13, "free_motion_training", angles(
        "Fig. 13: free-motion training trajectory",
        BRun::Training,
        "the training data are in the folder of `admittance run scenarios/free_motion.toml` (a run of scenario admittance simulates them without writing them)",
    ))];
    out.push(planned(14, "validation_trajectory", angles(
        "Fig. 14: validation trajectory",
        BRun::Validation,
        "the validation data are in the folder of `admittance run scenarios/free_motion_validation.toml`",
    )));
    out.push(planned(
        15,
        "validation_performance",
        validation_figure(folder),
    ));
    if run != BRun::Admittance {
        return out;
    }
    let variants = b_variants(folder);
    let j = joint0(folder);
    out.push(planned(
        16,
        "test_trajectory",
        (|| {
            let v = variants.first().ok_or("the run has no variants")?;
            Ok(figure(
                "Fig. 16: test trajectory",
                vec![all_joints_panel(
                    folder,
                    &v.table,
                    &format!("{}.csv", v.name),
                    format!("joint angles, variant {}", v.name),
                    0..v.table.rows(),
                )?],
            ))
        })(),
    ));
    out.push(planned(
        17,
        "test_performance",
        (|| {
            let (j, short) = j.clone()?;
            // One panel per variant: the true torque depends on how that variant's arm moved.
            let panels = variants
                .iter()
                .map(|v| {
                    let t = col(v, "t")?;
                    Ok(panel(
                        format!("joint {short}, variant {}", v.name),
                        "torque (N m)",
                        vec![
                            line(
                                "true tau_ext",
                                t,
                                col(v, &format!("tau_ext.{j}"))?,
                                0,
                                false,
                            ),
                            line(
                                "estimate tau_ext_hat",
                                t,
                                col(v, &format!("tau_ext_hat.{j}"))?,
                                1,
                                true,
                            ),
                        ],
                    ))
                })
                .collect::<Result<Vec<_>, String>>()?;
            if panels.is_empty() {
                return Err("the run has no variants".into());
            }
            Ok(figure(
                format!("Fig. 17: external torque on {short} and its estimate"),
                panels,
            ))
        })(),
    ));
    out.push(planned(
        18,
        "s0_adaptation",
        (|| {
            let (j, short) = j.clone()?;
            let lines = adaptation_lines(&variants, j)?;
            Ok(figure(
                format!("Fig. 18: trajectory adaptation of joint {short}"),
                vec![panel(format!("joint {short}"), "angle (rad)", lines)],
            ))
        })(),
    ));
    out.push(planned(
        19,
        "s0_tracking",
        (|| {
            let (j, short) = j.clone()?;
            let panels = variants
                .iter()
                .map(|v| tracking(v, j, &short, "q_r"))
                .collect::<Result<Vec<_>, _>>()?;
            if panels.is_empty() {
                return Err("the run has no variants".into());
            }
            Ok(figure(
                format!("Fig. 19: tracking of the compliant reference, joint {short}"),
                panels,
            ))
        })(),
    ));
    out.push(planned(
        20,
        "s0_constraint",
        (|| {
            let (j, short) = j.clone()?;
            let lines = adaptation_lines(&variants, j)?;
            let mut p = panel(format!("joint {short}"), "angle (rad)", lines);
            let centre =
                first_of(folder.scenario_value("admittance.saturation.centre")).unwrap_or(0.0);
            match first_of(folder.scenario_value("admittance.saturation.half_range")) {
                Some(c) if c.is_finite() => {
                    p.hlines.push(Marker {
                        at: centre + c,
                        label: format!("bound c + C = {}", centre + c),
                    });
                    p.hlines.push(Marker {
                        at: centre - c,
                        label: format!("bound c - C = {}", centre - c),
                    });
                }
                _ => p
                    .title
                    .push_str(" (no finite saturation bound in scenario.toml)"),
            }
            Ok(figure(
                format!("Fig. 20: trajectory constraint on joint {short}"),
                vec![p],
            ))
        })(),
    ));
    out
}

/// Times at which the node count first falls (discard) and first rises (growth).
pub fn node_events(t: &[f64], nodes: &[f64]) -> (Option<f64>, Option<f64>) {
    let mut discard = None;
    let mut grow = None;
    for k in 1..nodes.len().min(t.len()) {
        if discard.is_none() && nodes[k] < nodes[k - 1] {
            discard = Some(t[k]);
        }
        if grow.is_none() && nodes[k] > nodes[k - 1] {
            grow = Some(t[k]);
        }
    }
    (discard, grow)
}

/// The node count at the last sample before `time`.
fn nodes_before(t: &[f64], nodes: &[f64], time: f64) -> f64 {
    let k = t
        .partition_point(|&x| x < time)
        .saturating_sub(1)
        .min(nodes.len().saturating_sub(1));
    nodes.get(k).copied().unwrap_or(f64::NAN)
}

fn approx_panel(
    v: &Variant,
    j: &str,
    short: &str,
    range: (f64, f64),
    what: &str,
) -> Result<Panel, String> {
    let t = col(v, "t")?;
    let nodes = col(v, "nodes.f")?;
    let n = nodes_before(t, nodes, range.1);
    let mut p = panel(
        format!(
            "joint {short}, {what}: {:.0} nodes, {:.0}-{:.0} s",
            n, range.0, range.1
        ),
        "f (N m)",
        vec![
            line(
                "f = M alpha' + C alpha + G (true arm)",
                t,
                col(v, &format!("f.{j}"))?,
                1,
                false,
            ),
            line(
                "f_hat (network)",
                t,
                col(v, &format!("f_hat.{j}"))?,
                0,
                true,
            ),
        ],
    );
    p.x_range = Some(range);
    Ok(p)
}

fn plan_c(folder: &RunFolder) -> Vec<Planned> {
    let v = folder
        .variant("dynamic")
        .or(folder.variants.first())
        .ok_or_else(|| "the run has no variants".to_string());
    let window =
        first_of(folder.scenario_value("dynamic_nodes.approximation_window")).unwrap_or(12.0);
    let j = joint0(folder);
    let events = || -> Result<(&Variant, f64, Option<f64>, f64), String> {
        let v = v.clone()?;
        let t = col(v, "t")?;
        let (discard, grow) = node_events(t, col(v, "nodes.f")?);
        let discard =
            discard.ok_or("`nodes.f` never falls: no nodes were discarded in this run")?;
        Ok((v, discard, grow, *t.last().unwrap_or(&0.0)))
    };
    let mut out = vec![planned(
        21,
        "approximation_discard",
        (|| {
            let (j, short) = j.clone()?;
            let (v, discard, grow, end) = events()?;
            let before_growth = grow.unwrap_or(end);
            Ok(figure(
                format!("Fig. 21: approximation of f on {short} before and after the discard"),
                vec![
                    approx_panel(
                        v,
                        j,
                        &short,
                        (discard - window, discard),
                        "all initial nodes",
                    )?,
                    approx_panel(
                        v,
                        j,
                        &short,
                        (before_growth - window, before_growth),
                        "after the discard",
                    )?,
                ],
            ))
        })(),
    )];
    let weights = || -> Result<(&crate::table::Table, f64, Option<f64>, f64), String> {
        let (v, discard, grow, end) = events()?;
        let table = folder
            .node_weights
            .iter()
            .find(|(name, _)| *name == v.name)
            .map(|(_, t)| t)
            .ok_or(NO_WEIGHTS)?;
        Ok((table, discard, grow, end))
    };
    out.push(planned(
        22,
        "weights_initial",
        (|| {
            let (table, discard, _, _) = weights()?;
            Ok(figure(
                "Fig. 22: weights of the initial nodes until the discard",
                vec![weights_panel(
                    table,
                    (0.0, discard - 1e-6), // the last sample before the discard
                    NodeSelection::Initial,
                    "initial nodes",
                )?],
            ))
        })(),
    ));
    out.push(planned(
        23,
        "weights_after_discard",
        (|| {
            let (table, discard, grow, end) = weights()?;
            Ok(figure(
                "Fig. 23: weights of the nodes kept by the discard",
                vec![weights_panel(
                    table,
                    (discard, grow.unwrap_or(end)),
                    NodeSelection::Initial,
                    "kept nodes",
                )?],
            ))
        })(),
    ));
    out.push(planned(
        24,
        "approximation_growth",
        (|| {
            let (j, short) = j.clone()?;
            let (v, _, grow, end) = events()?;
            grow.ok_or("`nodes.f` never rises: no nodes were grown in this run")?;
            Ok(figure(
                format!("Fig. 24: approximation of f on {short} after growth"),
                vec![approx_panel(
                    v,
                    j,
                    &short,
                    (end - window, end),
                    "after growth",
                )?],
            ))
        })(),
    ));
    out.push(planned(
        25,
        "weights_kept_after_growth",
        (|| {
            let (table, _, grow, end) = weights()?;
            let grow = grow.ok_or("`nodes.f` never rises: no nodes were grown in this run")?;
            Ok(figure(
                "Fig. 25: weights of the kept initial nodes while and after nodes grow",
                vec![weights_panel(
                    table,
                    (grow, end),
                    NodeSelection::Initial,
                    "kept initial nodes",
                )?],
            ))
        })(),
    ));
    out.push(planned(
        26,
        "weights_new_nodes",
        (|| {
            let (table, _, grow, end) = weights()?;
            let grow = grow.ok_or("`nodes.f` never rises: no nodes were grown in this run")?;
            // New nodes appear one by one from `grow` on: show them once they all exist.
            let w_t = table
                .col("t")
                .ok_or("column `t` is not in the weights file")?;
            let all_added = table
                .columns
                .iter()
                .filter(|c| c.starts_with("w."))
                .filter_map(|c| table.col(c))
                .filter(|w| !w.first().is_some_and(|v| v.is_finite()))
                .filter_map(|w| w.iter().position(|v| v.is_finite()).map(|k| w_t[k]))
                .fold(grow, f64::max);
            Ok(figure(
                "Fig. 26: weights of the grown nodes",
                vec![weights_panel(
                    table,
                    (all_added, end),
                    NodeSelection::New,
                    "grown nodes",
                )?],
            ))
        })(),
    ));
    out.push(Planned {
        id: "S1".into(),
        stem: "s1_node_count".into(),
        caption: "Node count of the f network over the run (not in the paper).".into(),
        data: "nodes.f".into(),
        figure: (|| {
            let (v, discard, grow, _) = events()?;
            let t = col(v, "t")?;
            let mut p = panel(
                format!("variant {}", v.name),
                "nodes",
                vec![line(
                    "nodes of the f network",
                    t,
                    col(v, "nodes.f")?,
                    0,
                    false,
                )],
            );
            p.vlines.push(Marker {
                at: discard,
                label: format!("discard at {discard:.1} s"),
            });
            if let Some(g) = grow {
                p.vlines.push(Marker {
                    at: g,
                    label: format!("growth from {g:.1} s"),
                });
            }
            Ok(figure("Node count of the f network", vec![p]))
        })(),
    });
    out
}

fn plan_generic(folder: &RunFolder) -> Vec<Planned> {
    let j = joint0(folder);
    let mut out = Vec::new();
    out.push(Planned {
        id: "S1".into(),
        stem: "s1_joint0_tracking".into(),
        caption: "Tracking of the first joint, every variant (the scenario is not one of the paper's experiments).".into(),
        data: "q_r and q of the first joint".into(),
        figure: (|| {
            let (j, short) = j.clone()?;
            let panels = folder.variants.iter().map(|v| tracking(v, j, &short, "q_r")).collect::<Result<Vec<_>, _>>()?;
            if panels.is_empty() {
                return Err("the run has no variants".into());
            }
            Ok(figure(format!("Tracking of joint {short}"), panels))
        })(),
    });
    out.push(Planned {
        id: "S2".into(),
        stem: "s2_joint0_torque".into(),
        caption: "Commanded torque of the first joint, every variant.".into(),
        data: "tau_cmd of the first joint".into(),
        figure: (|| {
            let (j, short) = j.clone()?;
            let lines = folder
                .variants
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    Ok(line(
                        v.name.clone(),
                        col(v, "t")?,
                        col(v, &format!("tau_cmd.{j}"))?,
                        k % JOINT_COLORS,
                        false,
                    ))
                })
                .collect::<Result<Vec<_>, String>>()?;
            Ok(figure(
                format!("Commanded torque of joint {short}"),
                vec![panel(format!("joint {short}"), "torque (N m)", lines)],
            ))
        })(),
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::Table;

    const J: [&str; 2] = ["left_s0", "left_s1"];

    fn table(prefixes: &[&str], extra: &[&str], rows: usize) -> Table {
        let mut names = vec!["t".to_string()];
        for p in prefixes {
            for j in J {
                names.push(format!("{p}.{j}"));
            }
        }
        names.extend(extra.iter().map(|s| s.to_string()));
        let data = (0..names.len())
            .map(|c| {
                (0..rows)
                    .map(|k| {
                        if c == 0 {
                            k as f64 * 0.1
                        } else {
                            (k as f64 * 0.3 + c as f64).sin()
                        }
                    })
                    .collect()
            })
            .collect();
        Table::from_columns(names, data)
    }

    fn folder(scenario: &str, variants: &[(&str, Table)]) -> RunFolder {
        RunFolder {
            dir: ".".into(),
            scenario: scenario.into(),
            joints: J.iter().map(|s| s.to_string()).collect(),
            variants: variants
                .iter()
                .map(|(n, t)| Variant { name: n.to_string(), metrics: Default::default(), table: t.clone() })
                .collect(),
            scenario_toml: Some(
                "[[plant.deadzones]]\njoint = \"left_s0\"\nd_left = -0.49\nd_right = 0.49\n\
                 [variants.nn_uncompensated]\nplant.deadzones = [{ joint = \"left_s0\", d_left = -5.0, d_right = 5.0 }]\n"
                    .parse()
                    .unwrap(),
            ),
            free_motion: Vec::new(),
            node_weights: Vec::new(),
            observer_validation: Vec::new(),
        }
    }

    const ALL: [&str; 9] = [
        "q_d",
        "q_r",
        "q",
        "qdot",
        "q_meas",
        "tau_cmd",
        "tau_applied",
        "tau_ext",
        "tau_ext_hat",
    ];

    #[test]
    fn catalogue_covers_figs_7_to_26_once() {
        let numbers: Vec<u32> = PAPER_FIGURES.iter().map(|f| f.number).collect();
        assert_eq!(numbers, (7..=26).collect::<Vec<_>>());
        for f in PAPER_FIGURES {
            let expected = match f.number {
                7..=12 => "deadzone",
                13..=20 => "admittance",
                _ => "dynamic_nodes",
            };
            assert_eq!(f.scenario, expected, "Fig {}", f.number);
        }
    }

    #[test]
    fn experiment_a_maps_figures_to_columns() {
        let t = table(&ALL, &["ee_error"], 100);
        let f = folder(
            "deadzone",
            &[("nn_compensated", t.clone()), ("nn_uncompensated", t)],
        );
        let plan = plan(&f, Err("no URDF in this test".into()));
        let ids: Vec<&str> = plan.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(ids, ["7", "8", "9", "10", "11", "12"]);
        assert_eq!(plan[0].figure.as_ref().unwrap_err(), "no URDF in this test");
        for p in &plan[1..] {
            assert!(
                p.figure.is_ok(),
                "Fig {}: {:?}",
                p.id,
                p.figure.as_ref().err()
            );
        }
        // Fig 11: the error line is q_r - q of s0, computed row by row.
        let fig11 = plan[4].figure.as_ref().unwrap();
        let v = f.variant("nn_compensated").unwrap();
        let expected: Vec<f64> = v
            .table
            .col("q_r.left_s0")
            .unwrap()
            .iter()
            .zip(v.table.col("q.left_s0").unwrap())
            .map(|(a, b)| a - b)
            .collect();
        let compensated = fig11.panels[0]
            .lines
            .iter()
            .find(|l| l.label.contains("nn_compensated"))
            .unwrap();
        assert_eq!(compensated.y, expected);
        // Fig 12 carries the deadzone band from scenario.toml and the last 6 s.
        let fig12 = plan[5].figure.as_ref().unwrap();
        let band: Vec<f64> = fig12.panels[0].hlines.iter().map(|m| m.at).collect();
        assert_eq!(band, [-0.49, 0.49]);
        // ... as the variant sees it: its own override.
        let band: Vec<f64> = fig12.panels[1].hlines.iter().map(|m| m.at).collect();
        assert_eq!(band, [-5.0, 5.0]);
        let r = fig12.panels[0].x_range.unwrap();
        let t_end = *v.table.col("t").unwrap().last().unwrap();
        assert!(
            (r.1 - t_end).abs() < 1e-12 && (r.1 - r.0 - 6.0).abs() < 1e-9,
            "{r:?}"
        );
    }

    #[test]
    fn missing_column_makes_a_figure_unavailable_with_the_column_named() {
        let full = table(&ALL, &["ee_error"], 20);
        let keep: Vec<usize> = (0..full.columns.len())
            .filter(|&k| full.columns[k] != "tau_applied.left_s0")
            .collect();
        let partial = Table::from_columns(
            keep.iter().map(|&k| full.columns[k].clone()).collect(),
            keep.iter().map(|&k| full.data[k].clone()).collect(),
        );
        let f = folder(
            "deadzone",
            &[("nn_compensated", partial), ("nn_uncompensated", full)],
        );
        let plan = plan(&f, Err("no URDF".into()));
        let fig12 = plan.iter().find(|p| p.id == "12").unwrap();
        let reason = fig12.figure.as_ref().unwrap_err();
        assert!(
            reason.contains("tau_applied.left_s0") && reason.contains("nn_compensated.csv"),
            "{reason}"
        );
        // The other figures are unaffected.
        assert!(plan.iter().find(|p| p.id == "11").unwrap().figure.is_ok());
    }

    #[test]
    fn missing_variant_is_named() {
        let f = folder("deadzone", &[("pd", table(&ALL, &["ee_error"], 10))]);
        let plan = plan(&f, Err("no URDF".into()));
        let reason = plan
            .iter()
            .find(|p| p.id == "9")
            .unwrap()
            .figure
            .as_ref()
            .unwrap_err()
            .clone();
        assert!(
            reason.contains("nn_compensated") && reason.contains("pd"),
            "{reason}"
        );
    }

    #[test]
    fn experiment_c_finds_discard_and_growth_from_node_counts() {
        let t: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let nodes: Vec<f64> = t
            .iter()
            .map(|&x| {
                if x < 40.0 {
                    512.0
                } else if x < 60.0 {
                    300.0
                } else {
                    300.0 + (x - 59.0).min(10.0)
                }
            })
            .collect();
        assert_eq!(node_events(&t, &nodes), (Some(40.0), Some(60.0)));
        let f_col: Vec<f64> = t.iter().map(|x| x.sin()).collect();
        let tab = Table::from_columns(
            vec![
                "t".into(),
                "f.left_s0".into(),
                "f_hat.left_s0".into(),
                "nodes.f".into(),
            ],
            vec![t.clone(), f_col.clone(), f_col, nodes],
        );
        let f = folder("dynamic_nodes", &[("dynamic", tab)]);
        let plan = plan(&f, Err("unused".into()));
        let fig21 = plan
            .iter()
            .find(|p| p.id == "21")
            .unwrap()
            .figure
            .as_ref()
            .unwrap();
        assert_eq!(fig21.panels[0].x_range, Some((28.0, 40.0)));
        assert_eq!(fig21.panels[1].x_range, Some((48.0, 60.0)));
        assert!(
            fig21.panels[0].title.contains("512 nodes"),
            "{}",
            fig21.panels[0].title
        );
        assert!(
            fig21.panels[1].title.contains("300 nodes"),
            "{}",
            fig21.panels[1].title
        );
        let fig24 = plan
            .iter()
            .find(|p| p.id == "24")
            .unwrap()
            .figure
            .as_ref()
            .unwrap();
        assert!(
            fig24.panels[0].title.contains("310 nodes"),
            "{}",
            fig24.panels[0].title
        );
        for n in ["22", "23", "25", "26"] {
            assert!(plan.iter().find(|p| p.id == n).unwrap().figure.is_err());
        }
        assert!(plan.iter().find(|p| p.id == "24").unwrap().figure.is_ok());

        // With per-node weights: 4 initial nodes, 2 of them discarded at 40 s, 3 grown at
        // 60, 61 and 62 s.
        let mut f = f;
        let nan = f64::NAN;
        let w = |alive: &dyn Fn(f64) -> bool| -> Vec<f64> {
            t.iter()
                .map(|&x| if alive(x) { 0.1 * x } else { nan })
                .collect()
        };
        let mut names = vec!["t".to_string()];
        let mut cols = vec![t.clone()];
        for id in 0..4 {
            names.push(format!("w.{id}"));
            cols.push(w(&|x| id < 2 || x < 40.0));
        }
        for (id, from) in [(4, 60.0), (5, 61.0), (6, 62.0)] {
            names.push(format!("w.{id}"));
            cols.push(w(&|x| x >= from));
        }
        f.node_weights = vec![("dynamic".into(), Table::from_columns(names, cols))];
        let with_weights = super::plan(&f, Err("unused".into()));
        let lines = |id: &str| -> usize {
            let fig = with_weights.iter().find(|p| p.id == id).unwrap();
            fig.figure
                .as_ref()
                .map_err(|e| format!("{id}: {e}"))
                .unwrap()
                .panels[0]
                .lines
                .len()
        };
        assert_eq!(lines("22"), 4, "all initial nodes until the discard");
        assert_eq!(lines("23"), 2, "the kept nodes");
        assert_eq!(lines("25"), 2, "the kept nodes after growth");
        assert_eq!(lines("26"), 3, "the grown nodes");
        let fig26 = with_weights.iter().find(|p| p.id == "26").unwrap();
        assert_eq!(
            fig26.figure.as_ref().unwrap().panels[0].x_range,
            Some((62.0, 99.0))
        );
    }

    #[test]
    fn experiment_b_training_and_validation_runs() {
        let t = table(&ALL, &[], 30);
        let training = plan(
            &folder("free_motion", &[("base", t.clone())]),
            Err("unused".into()),
        );
        let ids: Vec<(&str, bool)> = training
            .iter()
            .map(|p| (p.id.as_str(), p.figure.is_ok()))
            .collect();
        assert_eq!(ids, [("13", true), ("14", false), ("15", false)]);
        let validation = plan(
            &folder("free_motion_validation", &[("base", t.clone())]),
            Err("unused".into()),
        );
        assert!(validation[0]
            .figure
            .as_ref()
            .unwrap_err()
            .contains("scenarios/free_motion.toml"));
        assert_eq!(
            validation[1].figure.as_ref().unwrap().panels[0].lines.len(),
            J.len()
        );
        let admittance = plan(
            &folder("admittance", &[("momentum", t.clone()), ("learned", t)]),
            Err("unused".into()),
        );
        let ids: Vec<&str> = admittance.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(ids, ["13", "14", "15", "16", "17", "18", "19", "20"]);
        assert!(admittance[2].figure.is_err(), "no validation file yet");
        // With the learned observer's validation predictions: one panel per joint.
        let mut with_validation = folder("admittance", &[("learned", table(&[], &[], 5))]);
        let columns: Vec<String> = std::iter::once("t".to_string())
            .chain(J.iter().map(|j| format!("target.{j}")))
            .chain(J.iter().map(|j| format!("prediction.{j}")))
            .collect();
        let data = (0..columns.len())
            .map(|c| (0..10).map(|k| (k * c) as f64).collect())
            .collect();
        with_validation.observer_validation =
            vec![("learned".into(), Table::from_columns(columns, data))];
        let fig15 = super::plan(&with_validation, Err("unused".into()));
        let fig15 = fig15.iter().find(|p| p.id == "15").unwrap();
        let panels = &fig15.figure.as_ref().unwrap().panels;
        assert_eq!(panels.len(), J.len());
        assert_eq!(panels[1].lines.len(), 2);
        // The learned observer (the paper's) comes first.
        let fig17 = admittance[4].figure.as_ref().unwrap();
        assert!(
            fig17.panels[0].title.contains("learned"),
            "{}",
            fig17.panels[0].title
        );
        assert!(admittance[0].figure.is_err() && admittance[7].figure.is_ok());
    }
}
