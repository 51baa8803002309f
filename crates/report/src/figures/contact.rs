//! Runs with contact detection (`[contact]`, issue 31): per variant, each joint's
//! estimate against its contact level and the true external torque, with the stretches
//! the detector flagged shaded (K1 for the first such variant, K2... for the others).

use admittance_runfolder::columns;

use super::common::{
    col, dashed, extra, intervals, joint_col, labelled_spans, line, panel, short, time,
};
use super::model::{Figure, Planned, Span};
use crate::folder::{RunFolder, Variant};

fn contact_variants(folder: &RunFolder) -> Vec<&Variant> {
    folder
        .variants
        .iter()
        .filter(|v| v.table.has(columns::CONTACT))
        .collect()
}

/// The stretches the detector flagged as contact, as spans.
fn flagged_spans(v: &Variant) -> Vec<Span> {
    let (Ok(t), Ok(flag)) = (time(v), col(v, columns::CONTACT)) else {
        return Vec::new();
    };
    labelled_spans(intervals(t, |k| flag[k] > 0.5), "contact flagged")
}

fn absolute(x: &[f64]) -> Vec<f64> {
    x.iter().map(|v| v.abs()).collect()
}

fn variant_figure(folder: &RunFolder, v: &Variant) -> Result<Figure, String> {
    let t = time(v)?;
    let spans = flagged_spans(v);
    let mut panels = Vec::new();
    for j in &folder.joints {
        let level = joint_col(v, columns::CONTACT_LEVEL, j)?;
        let lines = vec![
            dashed(
                "|true tau_ext|",
                t,
                &absolute(joint_col(v, columns::EXTERNAL, j)?),
                5,
            ),
            line(
                "|estimate tau_ext_hat|",
                t,
                &absolute(joint_col(v, columns::EXTERNAL_ESTIMATE, j)?),
                0,
                false,
            ),
            dashed("contact level", t, level, 1),
        ];
        let mut p = panel(format!("joint {}", short(j)), "torque (N m)", lines);
        p.spans = spans.clone();
        p.y_fit_from = Some(folder.evaluation_start());
        panels.push(p);
    }
    Ok(super::common::figure(
        format!(
            "Contact detection, variant {}: the estimate against the contact level",
            v.name
        ),
        panels,
    ))
}

/// K1, K2, ...: one figure per variant with contact columns.
pub fn plan(folder: &RunFolder) -> Vec<Planned> {
    contact_variants(folder)
        .into_iter()
        .enumerate()
        .map(|(k, v)| {
            extra(
                &format!("K{}", k + 1),
                &format!("k{}_contact_{}", k + 1, v.name),
                &format!(
                    "Contact detection in variant `{}`: each joint's |estimate| against its contact level (the floor's threshold, grown with speed) and the true external torque; shaded where the detector flagged contact (not in the paper).",
                    v.name
                ),
                "tau_ext.JOINT (dashed), tau_ext_hat.JOINT, contact_level.JOINT, contact",
                variant_figure(folder, v),
            )
        })
        .collect()
}
