//! Checks shared by the configuration structs of this crate: numbers, time windows, and
//! joints and frames by name, each error a [`SimError`] at its key.

use admittance_dynamics::Model;

use crate::plant::error::SimError;

pub(crate) fn finite(key: impl FnOnce() -> String, v: f64) -> Result<(), SimError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SimError::config(
            key(),
            format!("must be a finite number, got {v}"),
        ))
    }
}

pub(crate) fn non_negative(key: impl FnOnce() -> String, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(SimError::config(
            key(),
            format!("must be a finite number >= 0, got {v}"),
        ))
    }
}

pub(crate) fn positive(key: impl FnOnce() -> String, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SimError::config(
            key(),
            format!("must be a finite number > 0, got {v}"),
        ))
    }
}

/// A time window `[t_start, t_end)`: `t_start` finite, `t_end > t_start` (may be `inf`).
pub(crate) fn window(prefix: &str, t_start: f64, t_end: f64) -> Result<(), SimError> {
    finite(|| format!("{prefix}.t_start"), t_start)?;
    if t_end.is_nan() || t_end <= t_start {
        return Err(SimError::config(
            format!("{prefix}.t_end"),
            format!("must be greater than t_start ({t_start}), got {t_end}; use inf for no end"),
        ));
    }
    Ok(())
}

pub(crate) fn known_joints(model: &Model) -> String {
    model.joint_names().collect::<Vec<_>>().join(", ")
}

/// Index of a joint by name, or a setting error naming the key.
pub(crate) fn joint_index(
    model: &Model,
    key: impl FnOnce() -> String,
    name: &str,
) -> Result<usize, SimError> {
    model
        .joint_index(name)
        .ok_or_else(|| SimError::unknown_name(key(), "joint", name, &known_joints(model)))
}

/// The joints an entry with `joint = NAME` or `"*"` applies to.
pub(crate) fn joint_selection(
    model: &Model,
    key: impl FnOnce() -> String,
    name: &str,
) -> Result<std::ops::Range<usize>, SimError> {
    if name == "*" {
        Ok(0..model.nq())
    } else {
        let i = joint_index(model, key, name)?;
        Ok(i..i + 1)
    }
}

/// Index of a frame by name (`None` = the tip frame).
pub(crate) fn frame_index(
    model: &Model,
    key: impl FnOnce() -> String,
    name: Option<&str>,
) -> Result<usize, SimError> {
    match name {
        None => Ok(model.tip_frame),
        Some(name) => model.frame_index(name).ok_or_else(|| {
            let known: Vec<&str> = model.frames.iter().map(|f| f.name.as_str()).collect();
            SimError::unknown_name(key(), "frame", name, &known.join(", "))
        }),
    }
}
