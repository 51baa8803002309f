//! The admittance's deadband on the estimate (issue 31, item 3).

use crate::error::ConfigError;

/// The knee of [`soft_deadband`] as a fraction of the deadband.
pub const DEADBAND_KNEE: f64 = 0.5;

/// A soft threshold with a smooth knee: 0 inside `[-d, d]`; above, the excess `x = |e| - d`
/// through `x^2 / (2 w)` up to the knee `w = DEADBAND_KNEE d`, then `x - w / 2`, with the sign
/// of `e`. Continuous with a continuous slope (0 at the deadband's edge, 1 past the knee), so
/// no step in the admittance's input when a push starts; past the knee the output is the
/// excess less `w / 2`. `d <= 0` (or not finite) returns `e` unchanged.
#[inline]
pub fn soft_deadband(e: f64, d: f64) -> f64 {
    if !(d > 0.0 && d.is_finite()) {
        return e;
    }
    let x = e.abs() - d;
    if x <= 0.0 {
        return 0.0;
    }
    let w = DEADBAND_KNEE * d;
    let y = if x < w {
        x * x / (2.0 * w)
    } else {
        x - 0.5 * w
    };
    y.copysign(e)
}

/// A per-joint deadband checked for `n` joints (one finite value >= 0 each), as the
/// admittance models keep it: empty when every value is 0 (no deadband).
pub(crate) fn checked_deadband(deadband: &[f64], n: usize) -> Result<Vec<f64>, ConfigError> {
    if deadband.len() != n {
        return Err(ConfigError::new(
            "deadband",
            format!("has {} values for {n} joints", deadband.len()),
        )
        .hint("one value per joint in chain order, e.g. a contact floor's contact_thresholds"));
    }
    if let Some(i) = deadband.iter().position(|d| !(d.is_finite() && *d >= 0.0)) {
        return Err(ConfigError::new(
            format!("deadband[{i}]"),
            format!("is {}: must be finite and >= 0 (N m)", deadband[i]),
        )
        .hint("0 leaves the joint without a deadband"));
    }
    Ok(if deadband.iter().all(|d| *d == 0.0) {
        Vec::new()
    } else {
        deadband.to_vec()
    })
}
