//! Recordings that cannot be of the URDF's arm as it is written, refused with the joint named
//! and the fix: angles far outside the joint's limits (degrees, or another zero), or a joint
//! whose torque runs opposite to what the URDF's arm needs (a flipped sign convention). Each
//! of these was fitted without a word before: on a simulated Panda, a torque with joint 2's
//! sign flipped gave an expected false torque of 5.8 N m instead of 0.32, angles in degrees
//! 8.8 N m.

use crate::error::DynamicsError;
use crate::identification::samples::Samples;
use crate::model::Model;

/// How far beyond a joint's URDF limits an angle may read (rad): calibration offsets and
/// wrapped readings stay within it, degrees do not.
const LIMIT_MARGIN: f64 = 1.0;

/// A joint whose torque correlates with the URDF's torque below this is refused...
const OPPOSITE_CORRELATION: f64 = -0.8;
/// ...when the URDF's torque there is at least this fraction of the recorded one (rms): on
/// joints where friction dominates (a wrist), the correlation of clean recordings went down
/// to -0.47 on the simulated arms and means nothing.
const SIGNIFICANT_TORQUE: f64 = 0.25;

/// Refuses `samples` (`what` names them) whose angles leave a joint's URDF limits by more
/// than [`LIMIT_MARGIN`], or whose torque on a joint runs opposite to the URDF's
/// (`urdf_torque`: the URDF arm's torque on each sample, `n` per sample).
pub(super) fn check_against_urdf(
    model: &Model,
    samples: &Samples,
    urdf_torque: &[f64],
    what: &str,
) -> Result<(), DynamicsError> {
    let n = model.nq();
    let names: Vec<&str> = model.joint_names().collect();
    for (i, joint) in model.joints.iter().enumerate() {
        let (lo, hi) = (joint.limits.lower, joint.limits.upper);
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            continue;
        }
        let beyond = |q: f64| (lo - q).max(q - hi);
        if let Some(k) = (0..samples.len()).find(|&k| beyond(samples.q[k * n + i]) > LIMIT_MARGIN) {
            let q = samples.q[k * n + i];
            return Err(DynamicsError::InvalidArgument(format!(
                "{what}: joint {}'s angle is {q:.3} at sample {k}, {:.2} beyond its URDF limits \
                 [{lo:.3}, {hi:.3}] rad: angles must be in radians (degrees x 0.017453) with the \
                 URDF's zero",
                names[i],
                beyond(q)
            )));
        }
    }
    let (mut cross, mut urdf_sq, mut tau_sq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..samples.len() {
        let u = &urdf_torque[k * n..(k + 1) * n];
        for i in 0..n {
            let tau = samples.tau[k * n + i];
            cross[i] += u[i] * tau;
            urdf_sq[i] += u[i] * u[i];
            tau_sq[i] += tau * tau;
        }
    }
    for i in 0..n {
        let correlation = cross[i] / (urdf_sq[i] * tau_sq[i]).sqrt();
        let significant = urdf_sq[i] >= SIGNIFICANT_TORQUE * SIGNIFICANT_TORQUE * tau_sq[i];
        if correlation < OPPOSITE_CORRELATION && significant {
            return Err(DynamicsError::InvalidArgument(format!(
                "{what}: joint {}'s torque runs opposite to what the URDF's arm needs \
                 (correlation {correlation:.2}): flip its sign (the torque the joint applies, \
                 positive about its URDF axis)",
                names[i]
            )));
        }
    }
    Ok(())
}
