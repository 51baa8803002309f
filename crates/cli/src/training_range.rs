//! The joints a recording takes outside the identification's training range
//! (`summary.training_range`): there its springs, offsets and gravity extrapolate, and its
//! expected false torque does not hold.

use admittance_dynamics::{Identification, Model};

/// One line per joint that `q` (row-major, the identification's conditioning applied)
/// takes outside the range; empty when none does, or the file records no range.
pub fn lines(ident: &Identification, arm: &Model, q: &[f64]) -> Vec<String> {
    let samples = q.len() / arm.nq().max(1);
    ident
        .range_excursions(q)
        .iter()
        .zip(arm.joint_names())
        .zip(&ident.summary.training_range)
        .filter(|((e, _), _)| e.samples_outside > 0)
        .map(|((e, name), [low, high])| {
            format!(
                "{name}: {:.1} % of the samples, {:.3} to {:.3} against {low:.3} to {high:.3} trained ({:.3} beyond)",
                100.0 * e.samples_outside as f64 / samples.max(1) as f64,
                e.lowest,
                e.highest,
                e.furthest
            )
        })
        .collect()
}

/// [`lines`] under a heading that says what they mean and what to do (empty when none).
pub fn report(ident: &Identification, arm: &Model, q: &[f64]) -> String {
    under_heading(
        "outside the identification's training range (its springs, offsets and gravity extrapolate there; \
         record motion that covers these positions and identify again):",
        lines(ident, arm, q),
    )
}

/// `lines`, indented, below `heading`; empty when there are none.
pub fn under_heading(heading: &str, lines: Vec<String>) -> String {
    if lines.is_empty() {
        return String::new();
    }
    let mut text = format!("{heading}\n");
    for line in lines {
        text += &format!("  {line}\n");
    }
    text
}
