//! `admittance evaluate --contact-floor FILE`: the false alarms a contact floor raises on a
//! free-motion recording (every flag there is false), against the rate it promises
//! (issue 31, item 4).

use std::path::Path;

use admittance_control::{ContactFloor, JointValues, MomentumObserverConfig};
use admittance_dynamics::{
    faster_than_training, outside_training_range, Identification, JointKind,
};
use admittance_scenario::FreeMotionData;

use crate::CliError;

/// `evaluate`'s hook: the table of false alarms of the floor at `floor_path` on the rows of
/// `data` (read from `data_path`) with `t >= from`, with the momentum observer on `ident`
/// (conditioned at `input_filter_hz`) at the gain the floor records.
pub fn false_alarm_table(
    floor_path: &Path,
    data_path: &Path,
    data: &FreeMotionData,
    from: f64,
    ident: Option<&Identification>,
    input_filter_hz: f64,
) -> Result<String, CliError> {
    let Some(ident) = ident else {
        return Err(CliError::usage(
            "--contact-floor needs --identification (the floor is for the momentum observer on it)",
        ));
    };
    let data = &crate::calibrate_cmd::rows_between(data_path, data.clone(), from, None, 100)?;
    let floor = ContactFloor::load(floor_path).map_err(|e| CliError::input(e.to_string()))?;
    if !floor.joints.is_empty() && floor.joints != data.joints {
        return Err(CliError::input(format!(
            "{}: is for the joints [{}], the recording has [{}]",
            floor_path.display(),
            floor.joints.join(", "),
            data.joints.join(", ")
        )));
    }
    let gain: JointValues = floor
        .source
        .get("observer_gain")
        .and_then(|v| serde_json::from_value(v.clone()).ok())
        .unwrap_or(JointValues::Uniform(50.0));
    let mut ident = ident.clone();
    ident.summary.input_filter_hz = input_filter_hz;
    let observer = MomentumObserverConfig { gain };
    let e = admittance_scenario::momentum_estimates(data, &ident, &observer)
        .map_err(|e| CliError::input(e.to_string()))?
        .after(admittance_scenario::CONTACT_WARM_UP_S);
    let fa = admittance_scenario::count_false_alarms(&floor, &e)
        .map_err(|e| CliError::input(format!("{}: {e}", floor_path.display())))?;
    let mut s = format!(
        "contact floor {} on {:.1} min of free motion (after {} s warm-up):\n",
        floor_path.display(),
        fa.duration_s / 60.0,
        admittance_scenario::CONTACT_WARM_UP_S
    );
    s += &format!(
        "{:<22} {:>8} {:>10} {:>10}\n",
        "flag", "events", "per hour", "promised"
    );
    s += &format!(
        "{:<22} {:>8} {:>10.2} {:>10.3}\n",
        "contact",
        fa.contact_events,
        fa.contact_per_hour(),
        floor.false_alarms_per_hour
    );
    s += &format!(
        "{:<22} {:>8} {:>10.2} {:>10.3}\n",
        "collision",
        fa.collision_events,
        fa.collision_per_hour(),
        floor.collision_false_alarms_per_hour
    );
    s += &format!(
        "contact events by last loaded joint: {:?}; {:.3} % of samples flagged\n",
        fa.contact_events_by_link,
        100.0 * fa.contact_fraction
    );
    if !ident.summary.training_range.is_empty() || !ident.summary.training_speed.is_empty() {
        let (events, share) = extrapolating_events(&floor, &e, &ident, data, input_filter_hz)?;
        s += &format!(
            "contact events starting where the motion leaves the identification's training range or \
             speeds: {events} of {} (there: {:.1} % of the samples, where its model extrapolates)\n",
            fa.contact_events,
            100.0 * share
        );
    }
    Ok(s)
}

/// Of the contact events of `floor` over the estimates `e` (the last samples of `data`,
/// after the warm-up), how many start on a sample outside `ident`'s training range (its
/// conditioned angle) or faster than its training speeds (the velocity the observer saw),
/// and the share of those samples.
fn extrapolating_events(
    floor: &ContactFloor,
    e: &admittance_scenario::FreeMotionEstimates,
    ident: &Identification,
    data: &FreeMotionData,
    input_filter_hz: f64,
) -> Result<(usize, f64), CliError> {
    let n = e.joints;
    let states =
        admittance_scenario::detect(floor, e).map_err(|err| CliError::input(err.to_string()))?;
    let conditioned = admittance_scenario::ConditionedSamples::new(data, input_filter_hz)
        .map_err(CliError::input)?;
    let rows = conditioned.q.len() / n.max(1);
    let first = rows.saturating_sub(states.len());
    let continuous: Vec<bool> = ident
        .model
        .joints
        .iter()
        .map(|j| j.kind == JointKind::Continuous)
        .collect();
    let (mut events, mut samples) = (0, 0);
    let mut last_contact = false;
    for (k, state) in states.iter().enumerate() {
        let q = conditioned
            .q
            .get((first + k) * n..(first + k + 1) * n)
            .unwrap_or(&[]);
        let qdot = &e.qdot[k * n..(k + 1) * n];
        let there = outside_training_range(&ident.summary.training_range, q, &continuous)
            || faster_than_training(&ident.summary.training_speed, qdot);
        samples += usize::from(there);
        events += usize::from(there && state.contact && !last_contact);
        last_contact = state.contact;
    }
    Ok((events, samples as f64 / states.len().max(1) as f64))
}
