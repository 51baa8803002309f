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
