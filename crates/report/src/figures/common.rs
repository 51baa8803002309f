//! Helpers shared by the figures of every experiment: finding variants and columns with
//! errors that name them, building lines and panels, the contact spans.

use admittance_runfolder::columns;

use super::catalogue::paper;
use super::model::{Figure, Line, Panel, Planned, Span};
use crate::folder::{RunFolder, Variant};

/// Palette size (one colour per joint).
pub const JOINT_COLORS: usize = 8;
/// Palette indices for one line per variant beside a blue reference (no blue, no grey).
pub const VARIANT_COLORS: [usize; 6] = [1, 2, 3, 4, 6, 7];

/// The variant `name`, or an error naming what the run has.
pub fn variant<'a>(folder: &'a RunFolder, name: &str) -> Result<&'a Variant, String> {
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

/// The column `name` of a variant's series, or an error naming the file.
pub fn col<'a>(v: &'a Variant, name: &str) -> Result<&'a [f64], String> {
    v.table
        .col(name)
        .ok_or_else(|| format!("column `{name}` is not in {}.csv", v.name))
}

/// The time column of a variant.
pub fn time(v: &Variant) -> Result<&[f64], String> {
    col(v, columns::TIME)
}

/// The per-joint column `PREFIX.JOINT` of a variant.
pub fn joint_col<'a>(v: &'a Variant, prefix: &str, joint: &str) -> Result<&'a [f64], String> {
    col(v, &columns::joint(prefix, joint))
}

/// A solid line.
pub fn line(label: impl Into<String>, x: &[f64], y: &[f64], color: usize, thin: bool) -> Line {
    Line {
        label: label.into(),
        x: x.to_vec(),
        y: y.to_vec(),
        color,
        thin,
        dashed: false,
    }
}

/// A dashed line.
pub fn dashed(label: impl Into<String>, x: &[f64], y: &[f64], color: usize) -> Line {
    Line {
        dashed: true,
        ..line(label, x, y, color, false)
    }
}

/// A panel over time.
pub fn panel(title: impl Into<String>, y_label: &str, lines: Vec<Line>) -> Panel {
    Panel {
        title: title.into(),
        x_label: "time (s)".into(),
        y_label: y_label.into(),
        lines,
        ..Panel::default()
    }
}

/// A figure of independent panels.
pub fn figure(title: impl Into<String>, panels: Vec<Panel>) -> Figure {
    Figure {
        title: title.into(),
        panels,
        shared_y: false,
    }
}

/// A figure whose panels are compared: one y range.
pub fn compared(title: impl Into<String>, panels: Vec<Panel>) -> Figure {
    Figure {
        shared_y: true,
        ..figure(title, panels)
    }
}

/// Fig `number` of the paper, planned from `figure`.
pub fn planned(number: u32, stem: &str, figure: Result<Figure, String>) -> Planned {
    let p = paper(number);
    Planned {
        id: number.to_string(),
        stem: format!("fig{number:02}_{stem}"),
        caption: p.caption.replace("s0", "s_0"),
        data: p.data.to_string(),
        figure,
    }
}

/// Fig `number` of the paper about joint `joint` (the paper's s0): the caption and the
/// data name that joint when it is not s0.
pub fn planned_joint(
    number: u32,
    stem: &str,
    joint: &str,
    figure: Result<Figure, String>,
) -> Planned {
    let mut p = planned(number, stem, figure);
    let s = short(joint);
    if !joint.is_empty() && s != "s0" {
        p.caption = p.caption.replace("s_0", s);
        p.data = p.data.replace("s0", s);
    }
    p
}

/// The joint an observer comparison is about (`crate::experiment::contact_joint`) and its
/// short name.
pub fn contact_joint(folder: &RunFolder) -> Result<(&str, &str), String> {
    let j = crate::experiment::contact_joint(folder)
        .ok_or_else(|| "summary.json lists no joints".to_string())?;
    Ok((j, short(j)))
}

/// The worst-tracked joint (`crate::experiment::worst_joint`) and its short name.
pub fn worst_joint(folder: &RunFolder) -> Result<(&str, &str), String> {
    let j = crate::experiment::worst_joint(folder)
        .ok_or_else(|| "summary.json lists no joints".to_string())?;
    Ok((j, short(j)))
}

/// A figure not in the paper.
pub fn extra(
    id: &str,
    stem: &str,
    caption: &str,
    data: &str,
    figure: Result<Figure, String>,
) -> Planned {
    Planned {
        id: id.into(),
        stem: stem.into(),
        caption: caption.into(),
        data: data.into(),
        figure,
    }
}

/// A joint's name without the arm's prefix (`left_s0` -> `s0`).
pub fn short(joint: &str) -> &str {
    joint
        .strip_prefix("left_")
        .or_else(|| joint.strip_prefix("right_"))
        .unwrap_or(joint)
}

/// The first joint (the paper's s0) and its short name.
pub fn joint0(folder: &RunFolder) -> Result<(&str, &str), String> {
    let j = folder
        .joints
        .first()
        .ok_or_else(|| "summary.json lists no joints".to_string())?;
    Ok((j.as_str(), short(j)))
}

/// A panel of joint `j`: `against` (`q_d` or `q_r`) and the true angle.
pub fn tracking(v: &Variant, j: &str, against: &str) -> Result<Panel, String> {
    let t = time(v)?;
    let name = if against == columns::DESIRED {
        "desired q_d"
    } else {
        "reference q_r"
    };
    Ok(panel(
        format!("joint {}, variant {}", short(j), v.name),
        "angle (rad)",
        vec![
            line(name, t, joint_col(v, against, j)?, 0, false),
            line("actual q", t, joint_col(v, columns::POSITION, j)?, 1, true),
        ],
    ))
}

/// The last `seconds` of a time column, as an x range (finite times only).
pub fn last_window(t: &[f64], seconds: f64) -> Option<(f64, f64)> {
    let end = t
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .reduce(f64::max)?;
    let start = t.iter().copied().find(|v| v.is_finite())?;
    Some(((end - seconds).max(start), end))
}

/// The intervals in which something acts on the arm of variant `v`: the windows of the
/// scenario's joint-space environments and profiles (a wall touches only part of its
/// window), else the samples where some `tau_ext` is non-zero.
pub fn contact_spans(folder: &RunFolder, v: &Variant) -> Vec<Span> {
    let t = v.table.col(columns::TIME).unwrap_or(&[]);
    let Some((t0, t1)) = last_window(t, f64::INFINITY) else {
        return Vec::new();
    };
    let windows: Vec<(f64, f64)> = folder
        .environment_windows(&v.name)
        .into_iter()
        .filter(|w| w.kind != "walls")
        .map(|w| (w.from.max(t0), w.to.min(t1)))
        .filter(|(a, b)| a < b)
        .collect();
    let (spans, label) = if windows.is_empty() {
        (touching(folder, v, t), "in contact (tau_ext non-zero)")
    } else {
        (windows, "environment acts (the run's settings)")
    };
    labelled_spans(spans, label)
}

/// Shaded spans of `intervals`, the first one carrying `label` in the legend.
pub fn labelled_spans(intervals: Vec<(f64, f64)>, label: &str) -> Vec<Span> {
    intervals
        .into_iter()
        .enumerate()
        .map(|(k, (from, to))| Span {
            from,
            to,
            label: if k == 0 {
                label.to_string()
            } else {
                String::new()
            },
        })
        .collect()
}

/// Intervals of `t` where some joint's `tau_ext` is non-zero.
fn touching(folder: &RunFolder, v: &Variant, t: &[f64]) -> Vec<(f64, f64)> {
    let cols: Vec<&[f64]> = folder
        .joints
        .iter()
        .filter_map(|j| v.table.col(&columns::joint(columns::EXTERNAL, j)))
        .collect();
    intervals(t, |k| cols.iter().any(|c| c[k].is_finite() && c[k] != 0.0))
}

/// The intervals of `t` over the samples where `on(k)` holds: consecutive samples form
/// one interval, and intervals less than 0.1 s apart are merged.
pub fn intervals(t: &[f64], on: impl Fn(usize) -> bool) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut previous_on = false;
    for (k, &tk) in t.iter().enumerate() {
        let now = tk.is_finite() && on(k);
        if now {
            match out.last_mut() {
                Some(last) if previous_on || tk - last.1 < 0.1 => last.1 = tk,
                _ => out.push((tk, tk)),
            }
        }
        previous_on = now;
    }
    out
}
