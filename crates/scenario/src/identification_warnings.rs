//! What an identification's own summary says about the recording it came from, said to the
//! user by every front end (`admittance identify`, `adm.identify`): joints the recording
//! barely moved, and joints the fit predicts worse than the URDF alone.

use admittance_dynamics::{Identification, Model};

/// A joint whose training positions span less than this share of its URDF limits (or of one
/// turn, without limits) leaves its offset, springs and the bodies beyond it to the URDF.
const LEAST_TRAVEL: f64 = 0.05;

/// A fit that predicts a joint this much worse than the URDF, which it starts from, on
/// held-out motion is not estimation noise.
const WORSE_THAN_URDF: f64 = 1.05;

/// Warnings about `ident`, fitted on a recording of `arm`: joints that moved less than
/// [`LEAST_TRAVEL`] of their range, and joints whose expected false torque on held-out
/// motion exceeds the URDF's own there by [`WORSE_THAN_URDF`] (a torque of the opposite sign or another unit on a
/// joint the URDF's gravity does not load, which the sign check cannot see).
pub fn identification_warnings(arm: &Model, ident: &Identification) -> Vec<String> {
    let s = &ident.summary;
    let names: Vec<&str> = arm.joint_names().collect();
    let mut warnings = Vec::new();
    let still: Vec<String> = s
        .training_range
        .iter()
        .zip(arm.position_limits())
        .zip(&names)
        .filter_map(|(([low, high], (lower, upper)), name)| {
            let span = if lower.is_finite() && upper.is_finite() && upper > lower {
                upper - lower
            } else {
                2.0 * std::f64::consts::PI
            };
            (high - low < LEAST_TRAVEL * span)
                .then(|| format!("{name} ({:.3} of {span:.2})", high - low))
        })
        .collect();
    if !still.is_empty() {
        warnings.push(format!(
            "the recording barely moves {}: less than {:.0} % of the joint's range, so their \
             offsets, springs and the bodies they carry rest on the URDF and the expected false \
             torque says little about other positions; record motion over the range \
             (`admittance excite`)",
            still.join(", "),
            100.0 * LEAST_TRAVEL
        ));
    }
    for (i, name) in names.iter().enumerate() {
        let (Some(&urdf), Some(&fitted)) = (
            s.prior_false_torque_rms.get(i),
            s.expected_false_torque_rms.get(i),
        ) else {
            continue;
        };
        // Differences below a thousandth of a N m are rounding, not a model (an exact URDF
        // on simulated torques).
        if fitted > WORSE_THAN_URDF * urdf && fitted - urdf > 1e-3 {
            warnings.push(format!(
                "{name}: the identification predicts its torque worse than the URDF alone on \
                 held-out motion ({fitted:.3} against {urdf:.3} N m rms): is its torque the one \
                 the joint applies (its sign), in N m, and is it the URDF's joint?"
            ));
        }
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joints_barely_moved_and_joints_worse_than_the_urdf_are_named() {
        let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../models/baxter_left_arm.urdf");
        let arm = Model::from_urdf_file(&urdf, None, None).unwrap();
        let mut ident = Identification::from_model(arm.clone());
        // s0 (limits +-1.7016) moved 0.1 rad: under 5 % of 3.40; the others over their range.
        ident.summary.training_range = arm
            .position_limits()
            .enumerate()
            .map(|(i, (lower, upper))| if i == 0 { [0.0, 0.1] } else { [lower, upper] })
            .collect();
        ident.summary.prior_false_torque_rms = vec![1.0; 7];
        ident.summary.expected_false_torque_rms = vec![0.5, 1.2, 1.04, 0.5, 0.5, 0.5, 0.5];
        let warnings = identification_warnings(&arm, &ident);
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(warnings[0].starts_with("the recording barely moves left_s0 (0.100 of 3.40)"));
        // s1 is 20 % worse than the URDF; e0's 4 % is within estimation noise.
        assert!(warnings[1].starts_with("left_s1: the identification predicts its torque worse"));
    }
}
