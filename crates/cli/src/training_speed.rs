//! The joints a recording moves faster than the identification was trained at
//! (`summary.training_speed`): there its friction extrapolates, and its expected false torque
//! does not hold.

use admittance_dynamics::{Identification, Model};

/// One line per joint that `qdot` (row-major, the identification's conditioning applied)
/// moves faster than trained (beyond `TRAINING_SPEED_MARGIN`); empty when none does, or the
/// file records no speeds.
pub fn lines(ident: &Identification, arm: &Model, qdot: &[f64]) -> Vec<String> {
    let samples = qdot.len() / arm.nq().max(1);
    ident
        .speed_excursions(qdot)
        .iter()
        .zip(arm.joint_names())
        .zip(&ident.summary.training_speed)
        .filter(|((e, _), _)| e.samples_faster > 0)
        .map(|((e, name), highest)| {
            format!(
                "{name}: {:.1} % of the samples, up to {:.3} against {highest:.3} trained",
                100.0 * e.samples_faster as f64 / samples.max(1) as f64,
                e.fastest,
            )
        })
        .collect()
}

/// [`lines`] under a heading that says what they mean and what to do (empty when none).
pub fn report(ident: &Identification, arm: &Model, qdot: &[f64]) -> String {
    crate::training_range::under_heading(
        "faster than the identification's training speeds (over half again as fast: its friction \
         extrapolates there; record motion that reaches these speeds and identify again):",
        lines(ident, arm, qdot),
    )
}
