//! Task-space runs (a hand touching a wall, a push on the hand): the hand force estimated
//! without a force sensor against the true one (H1), the hand's path against the wall of
//! `[[plant.environment.walls]]` (H2), and the joint references the admittance model
//! made (H3). Drawn for every variant whose series has the hand columns.

use admittance_runfolder::columns;

use super::common::{compared, dashed, extra, joint_col, line, panel, short, time, VARIANT_COLORS};
use super::model::{Figure, Marker, Panel, Planned, Span};
use crate::folder::{RunFolder, Variant};

/// A joint whose reference departs from `q_d` by less than this (rad) is left out of H3.
const STILL: f64 = 1e-6;

fn hand_variants(folder: &RunFolder) -> Vec<&Variant> {
    folder
        .variants
        .iter()
        .filter(|v| {
            columns::AXES
                .iter()
                .all(|a| v.table.has(&columns::axis(columns::HAND_FORCE, a)))
        })
        .collect()
}

fn axis_col<'a>(v: &'a Variant, prefix: &str, axis: &str) -> Result<&'a [f64], String> {
    super::common::col(v, &columns::axis(prefix, axis))
}

/// The samples where the true hand force is not zero, as spans.
fn hand_contact_spans(v: &Variant) -> Vec<Span> {
    let (Ok(t), Ok(f)) = (
        time(v),
        columns::AXES
            .iter()
            .map(|a| axis_col(v, columns::HAND_FORCE, a))
            .collect::<Result<Vec<_>, _>>(),
    ) else {
        return Vec::new();
    };
    let on = |k: usize| f.iter().any(|c| c[k].is_finite() && c[k] != 0.0);
    super::common::labelled_spans(
        super::common::intervals(t, on),
        "hand in contact (f_hand non-zero)",
    )
}

fn force_figure(variants: &[&Variant]) -> Result<Figure, String> {
    let panels = variants
        .iter()
        .map(|v| {
            let t = time(v)?;
            let mut lines = Vec::new();
            for (k, a) in columns::AXES.iter().enumerate() {
                lines.push(dashed(
                    format!("true f_hand.{a}"),
                    t,
                    axis_col(v, columns::HAND_FORCE, a)?,
                    k,
                ));
                lines.push(line(
                    format!("estimate f_hand_hat.{a}"),
                    t,
                    axis_col(v, columns::HAND_FORCE_ESTIMATE, a)?,
                    k,
                    true,
                ));
            }
            let mut p = panel(format!("variant {}", v.name), "force (N)", lines);
            p.spans = hand_contact_spans(v);
            Ok(p)
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(compared(
        "Hand force: the estimate J^+T tau_ext_hat against the true contact force",
        panels,
    ))
}

/// The signed distance of the hand columns `prefix.*` from `wall`, per sample.
fn distances(
    v: &Variant,
    prefix: &str,
    wall: &crate::scenario_file::Wall,
) -> Result<Vec<f64>, String> {
    let c: Vec<&[f64]> = columns::AXES
        .iter()
        .map(|a| axis_col(v, prefix, a))
        .collect::<Result<_, _>>()?;
    Ok((0..v.table.rows())
        .map(|k| wall.distance([c[0][k], c[1][k], c[2][k]]))
        .collect())
}

fn vector(v: [f64; 3]) -> String {
    format!("[{}]", v.map(crate::number::setting).join(", "))
}

fn wall_figure(folder: &RunFolder, variants: &[&Variant]) -> Result<Figure, String> {
    let mut panels = Vec::new();
    for v in variants {
        let walls = folder.walls(&v.name);
        let wall = walls.first().ok_or_else(|| {
            format!(
                "the run has no wall ([[plant.environment.walls]]) for variant `{}`",
                v.name
            )
        })?;
        let t = time(v)?;
        let mut lines = Vec::new();
        if v.table.has(&columns::axis(columns::HAND_DESIRED, "x")) {
            lines.push(dashed(
                "desired FK(q_d)",
                t,
                &distances(v, columns::HAND_DESIRED, wall)?,
                0,
            ));
        }
        if v.table.has(&columns::axis(columns::HAND_REFERENCE, "x")) {
            lines.push(line(
                "compliant reference FK(q_r)",
                t,
                &distances(v, columns::HAND_REFERENCE, wall)?,
                2,
                false,
            ));
        }
        lines.push(line(
            "actual hand",
            t,
            &distances(v, columns::HAND_POSITION, wall)?,
            1,
            true,
        ));
        let mut p = panel(
            format!(
                "variant {}: signed distance from the wall through {} with normal {}{}, > 0 in free space",
                v.name,
                vector(wall.point),
                vector(wall.normal),
                if walls.len() > 1 {
                    " (the first wall)"
                } else {
                    ""
                }
            ),
            "distance (m)",
            lines,
        );
        p.hlines.push(Marker {
            at: 0.0,
            label: "wall surface".into(),
        });
        p.spans = hand_contact_spans(v);
        panels.push(p);
    }
    Ok(compared("Hand path against the wall", panels))
}

/// H3: how far the admittance model moved each joint's reference, `q_r - q_d`.
fn references_figure(folder: &RunFolder, variants: &[&Variant]) -> Result<Figure, String> {
    let offset = |v: &Variant, j: &str| -> Result<Vec<f64>, String> {
        let d = joint_col(v, columns::DESIRED, j)?;
        let r = joint_col(v, columns::REFERENCE, j)?;
        Ok(r.iter().zip(d).map(|(a, b)| a - b).collect())
    };
    let departs = |j: &str| {
        variants
            .iter()
            .any(|v| offset(v, j).is_ok_and(|o| o.iter().any(|x| x.abs() > STILL)))
    };
    let mut panels: Vec<Panel> = Vec::new();
    for j in folder.joints.iter().filter(|j| departs(j)) {
        let mut lines = Vec::new();
        for (k, v) in variants.iter().enumerate() {
            lines.push(line(
                format!("q_r - q_d, {}", v.name),
                time(v)?,
                &offset(v, j)?,
                VARIANT_COLORS[k % VARIANT_COLORS.len()],
                k > 0,
            ));
        }
        let mut p = panel(format!("joint {}", short(j)), "q_r - q_d (rad)", lines);
        if let Some(first) = variants.first() {
            p.spans = hand_contact_spans(first);
        }
        panels.push(p);
    }
    if panels.is_empty() {
        return Err(format!(
            "q_r equals q_d (within {STILL} rad) on every joint of every variant: nothing adapted"
        ));
    }
    Ok(super::common::figure(
        "Joint references: how far the admittance model moved them from q_d",
        panels,
    ))
}

/// H1-H3.
pub fn plan(folder: &RunFolder) -> Vec<Planned> {
    let variants = hand_variants(folder);
    vec![
        extra(
            "H1",
            "h1_hand_force",
            "The force on the hand estimated without a force sensor against the true contact force, per axis (not in the paper).",
            "f_hand.{x,y,z} (dashed) and f_hand_hat.{x,y,z}, one panel per variant, one y range",
            force_figure(&variants),
        ),
        extra(
            "H2",
            "h2_hand_wall",
            "The hand's path against the wall: signed distance from the wall plane (not in the paper).",
            "x_hand_d, x_hand_r, x_hand against the first wall of the run (settings.json)",
            wall_figure(folder, &variants),
        ),
        extra(
            "H3",
            "h3_joint_references",
            "The joint references made by the admittance model from the estimated force: their offset from the desired trajectory (not in the paper).",
            "q_r.JOINT - q_d.JOINT of every variant, joints whose q_r departs from q_d",
            references_figure(folder, &variants),
        ),
    ]
}
