//! What a run's contact detector did against the true external torque (issue 31, item 4):
//! false alarms while nothing touches the arm, pushes detected by size, the delay after a
//! push's true torque crosses twice a joint's contact level, and the named link.
//!
//! A push is a stretch of steps where the true external torque is not zero on some joint.
//! Its detection window runs to [`DETECT_WINDOW_S`] after it ends (the estimate lags the true
//! torque); a contact event (rising edge of the flag) outside every such window is a false
//! alarm, counted per hour of the time outside them.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// How long after a push ends its flag still counts as its detection (s), and the bar on
/// the delay after the 2x crossing.
pub const DETECT_WINDOW_S: f64 = 0.05;

/// The push sizes reported, as the peak of `|true torque| / contact level` over joints.
const SIZE_EDGES: [f64; 4] = [0.0, 1.0, 2.0, 4.0];

/// One step's flags.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StepFlags {
    pub t: f64,
    pub contact: bool,
    pub collision: bool,
    pub link: i32,
}

/// `summary.json`'s contact metrics, flattened into the variant's (docs/outputs.md).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactMetrics {
    /// The floor's promise: false contact events per hour.
    pub contact_promised_false_alarms_per_hour: f64,
    /// Contact levels at rest per joint (N m).
    pub contact_thresholds: Vec<f64>,
    /// Collision levels at rest per joint (N m).
    pub collision_thresholds: Vec<f64>,
    /// Time of the window outside every push's detection window (s).
    pub contact_untouched_s: f64,
    /// Contact events raised in that time.
    pub contact_false_events: usize,
    /// Collision events raised in that time.
    pub collision_false_events: usize,
    /// `contact_false_events` per hour of `contact_untouched_s` (`null` without untouched
    /// time).
    pub contact_false_alarms_per_hour: Option<f64>,
    /// Pushes in the window.
    pub contact_pushes: usize,
    /// Pushes flagged as contact during them or within 50 ms after.
    pub contact_pushes_detected: usize,
    /// Pushes by size (`"0-1x"`, `"1-2x"`, `"2-4x"`, `">=4x"`: the peak of |true torque| /
    /// contact level over joints).
    pub contact_pushes_by_size: BTreeMap<String, usize>,
    /// Fraction of the pushes of each size detected (`null`: none of that size).
    pub contact_detected_by_size: BTreeMap<String, Option<f64>>,
    /// Pushes whose true torque exceeded twice a joint's contact level.
    pub contact_over_twice: usize,
    /// Of those, flagged within 50 ms of the first crossing.
    pub contact_over_twice_within_50ms: usize,
    /// Median delay from the crossing to the flag (s; negative: flagged before it).
    pub contact_delay_median_s: Option<f64>,
    /// Largest such delay (s).
    pub contact_delay_max_s: Option<f64>,
    /// Fraction of the detected pushes whose touched part of the chain was named right (50
    /// ms after the true torque's peak, the observer's lag), among those with a joint above
    /// its level: the named joint is no earlier than the last joint whose true torque exceeds
    /// its level and no later than the last joint the push loads at all (a joint loaded below
    /// its level may be named: its child link, or one after it, was touched).
    pub contact_isolation: Option<f64>,
    /// The same share when only the last joint above its level counts as right.
    pub contact_isolation_strict: Option<f64>,
    /// Largest `|q_r - q_d|` per joint over the window (rad): with nobody touching, the
    /// admittance's drift.
    pub reference_offset_max_abs: Vec<f64>,
}

/// The label of size bin `i`.
fn size_label(i: usize) -> String {
    match SIZE_EDGES.get(i + 1) {
        Some(to) => format!("{}-{}x", SIZE_EDGES[i], to),
        None => format!(">={}x", SIZE_EDGES[i]),
    }
}

/// The scores of the window's steps; `true_torque` and `level` hold `n` values per step.
pub(crate) fn score(
    steps: &[StepFlags],
    true_torque: &[f64],
    level: &[f64],
    n: usize,
) -> ContactMetrics {
    let pushes = push_spans(true_torque, n);
    let dt = mean_dt(steps);
    let window = (DETECT_WINDOW_S / dt.max(f64::MIN_POSITIVE)).round() as usize;
    let mut touched = vec![false; steps.len()];
    for &(a, b) in &pushes {
        touched[a..(b + window).min(steps.len())].fill(true);
    }
    let mut m = ContactMetrics {
        contact_pushes: pushes.len(),
        ..ContactMetrics::default()
    };
    let mut by_size = [(0usize, 0usize); SIZE_EDGES.len()];
    false_alarms(steps, &touched, dt, &mut m);
    let (mut delays, mut named, mut named_right, mut named_exactly) =
        (Vec::new(), 0usize, 0usize, 0usize);
    for &(a, b) in &pushes {
        let end = (b + window).min(steps.len());
        let first = (a..end).find(|&k| steps[k].contact);
        let ratio = |k: usize, i: usize| true_torque[k * n + i].abs() / level[k * n + i];
        let peak_ratio = (a..b)
            .flat_map(|k| (0..n).map(move |i| (k, i)))
            .map(|(k, i)| ratio(k, i))
            .fold(0.0, f64::max);
        let bin = SIZE_EDGES
            .iter()
            .rposition(|&e| peak_ratio >= e)
            .unwrap_or(0);
        by_size[bin].0 += 1;
        if first.is_some() {
            m.contact_pushes_detected += 1;
            by_size[bin].1 += 1;
        }
        if let Some(cross) = (a..b).find(|&k| (0..n).any(|i| ratio(k, i) > 2.0)) {
            m.contact_over_twice += 1;
            if let Some(f) = first {
                let delay = steps[f].t - steps[cross].t;
                m.contact_over_twice_within_50ms += usize::from(delay <= DETECT_WINDOW_S + 1e-9);
                delays.push(delay);
            }
        }
        // The first sample of the largest true torque (a plateau's start, not its end).
        let peak = (a..b).fold(a, |best, k| {
            if row_max(true_torque, k, n) > row_max(true_torque, best, n) {
                k
            } else {
                best
            }
        });
        let true_last = (0..n).rev().find(|&i| ratio(peak, i) > 1.0);
        // Joints beyond the touched link carry no torque of the push at all.
        let largest = row_max(true_torque, peak, n);
        let last_loaded = (0..n)
            .rev()
            .find(|&i| true_torque[peak * n + i].abs() > 1e-6 * largest);
        if let (Some(_), Some(j), Some(l)) = (first, true_last, last_loaded) {
            let link = steps[(peak + window).min(steps.len() - 1)].link;
            named += 1;
            named_exactly += usize::from(link == j as i32);
            named_right += usize::from((j as i32..=l as i32).contains(&link));
        }
    }
    for (i, &(count, detected)) in by_size.iter().enumerate() {
        m.contact_pushes_by_size.insert(size_label(i), count);
        m.contact_detected_by_size.insert(
            size_label(i),
            (count > 0).then(|| detected as f64 / count as f64),
        );
    }
    delays.sort_by(f64::total_cmp);
    m.contact_delay_median_s = (!delays.is_empty()).then(|| delays[delays.len() / 2]);
    m.contact_delay_max_s = delays.last().copied();
    m.contact_isolation = (named > 0).then(|| named_right as f64 / named as f64);
    m.contact_isolation_strict = (named > 0).then(|| named_exactly as f64 / named as f64);
    m
}

/// Rising edges of the flags outside the pushes' windows, and the time outside them.
fn false_alarms(steps: &[StepFlags], touched: &[bool], dt: f64, m: &mut ContactMetrics) {
    let mut last: Option<&StepFlags> = None;
    let mut untouched = 0usize;
    for (s, &t) in steps.iter().zip(touched) {
        if !t {
            untouched += 1;
            let (was_contact, was_collision) =
                last.map_or((false, false), |l| (l.contact, l.collision));
            m.contact_false_events += usize::from(s.contact && !was_contact);
            m.collision_false_events += usize::from(s.collision && !was_collision);
        }
        last = Some(s);
    }
    m.contact_untouched_s = untouched as f64 * dt;
    m.contact_false_alarms_per_hour = (m.contact_untouched_s > 0.0)
        .then(|| m.contact_false_events as f64 * 3600.0 / m.contact_untouched_s);
}

/// `[start, end)` of each stretch where some joint's true torque is not zero.
fn push_spans(true_torque: &[f64], n: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    let len = true_torque.len() / n.max(1);
    for k in 0..len {
        let touched = row_max(true_torque, k, n) > 0.0;
        match (touched, start) {
            (true, None) => start = Some(k),
            (false, Some(a)) => {
                out.push((a, k));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(a) = start {
        out.push((a, len));
    }
    out
}

fn row_max(values: &[f64], k: usize, n: usize) -> f64 {
    values[k * n..(k + 1) * n]
        .iter()
        .fold(0.0, |m, v| m.max(v.abs()))
}

fn mean_dt(steps: &[StepFlags]) -> f64 {
    match (steps.first(), steps.last()) {
        (Some(a), Some(b)) if steps.len() > 1 => (b.t - a.t) / (steps.len() - 1) as f64,
        _ => 1e-3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(flags: &[(bool, i32)], torque: &[[f64; 2]]) -> ContactMetrics {
        let steps: Vec<StepFlags> = flags
            .iter()
            .enumerate()
            .map(|(k, &(c, link))| StepFlags {
                t: k as f64 * 0.01,
                contact: c,
                collision: false,
                link,
            })
            .collect();
        let true_torque: Vec<f64> = torque.iter().flatten().copied().collect();
        let level = vec![1.0; true_torque.len()];
        score(&steps, &true_torque, &level, 2)
    }

    #[test]
    fn a_flag_outside_every_push_is_a_false_alarm_and_one_inside_a_detection() {
        // 20 steps of 10 ms: a push of 3x the level on joint 1 at steps 10-13, flagged at 11;
        // a flag at step 3 with nothing touching.
        let mut flags = vec![(false, -1); 20];
        flags[3] = (true, 0);
        for f in flags.iter_mut().skip(11) {
            *f = (true, 1);
        }
        let mut torque = vec![[0.0; 2]; 20];
        for t in torque.iter_mut().take(14).skip(10) {
            *t = [0.5, 3.0];
        }
        let m = run(&flags, &torque);
        assert_eq!(m.contact_pushes, 1);
        assert_eq!(m.contact_pushes_detected, 1);
        assert_eq!(m.contact_false_events, 1);
        assert_eq!(m.contact_over_twice, 1);
        assert_eq!(m.contact_over_twice_within_50ms, 1);
        assert!((m.contact_delay_median_s.unwrap() - 0.01).abs() < 1e-12);
        assert_eq!(m.contact_isolation, Some(1.0));
        assert_eq!(m.contact_pushes_by_size["2-4x"], 1); // peak ratio 3
        assert_eq!(m.contact_detected_by_size["1-2x"], None);
        // 20 steps, of which 4 pushed and 5 after (50 ms): 11 untouched.
        assert!((m.contact_untouched_s - 0.11).abs() < 1e-9);
    }

    #[test]
    fn a_push_never_flagged_is_missed_and_the_wrong_link_is_not_isolation() {
        let flags = vec![(false, -1); 10];
        let mut torque = vec![[0.0; 2]; 10];
        torque[4] = [3.0, 0.0];
        let m = run(&flags, &torque);
        assert_eq!(
            (
                m.contact_pushes,
                m.contact_pushes_detected,
                m.contact_over_twice_within_50ms
            ),
            (1, 0, 0)
        );
        assert_eq!(m.contact_isolation, None);
        let mut flags = vec![(false, -1); 10];
        flags[4] = (true, 1);
        flags[5] = (true, 1);
        flags[6] = (true, 1);
        flags[7] = (true, 1);
        flags[8] = (true, 1);
        flags[9] = (true, 1);
        let m = run(&flags, &torque);
        assert_eq!(m.contact_isolation, Some(0.0)); // joint 0 loaded, joint 1 named
    }

    /// A push that loads joint 1 below its level and joint 0 above it: naming joint 1 (its
    /// child link was touched) is right, though not the strict answer; naming a joint the
    /// push does not load is wrong under both.
    #[test]
    fn a_loaded_joint_below_its_level_may_be_named() {
        let mut torque = vec![[0.0; 2]; 10];
        torque[4] = [3.0, 0.5];
        let mut flags = vec![(false, -1); 10];
        for f in flags.iter_mut().skip(4) {
            *f = (true, 1);
        }
        let m = run(&flags, &torque);
        assert_eq!(m.contact_isolation, Some(1.0));
        assert_eq!(m.contact_isolation_strict, Some(0.0));
        for f in flags.iter_mut().skip(4) {
            *f = (true, 0);
        }
        let m = run(&flags, &torque);
        assert_eq!(m.contact_isolation, Some(1.0));
        assert_eq!(m.contact_isolation_strict, Some(1.0));
    }

    /// A push held at its peak is scored at the plateau's start: 50 ms later it still
    /// loads the joint, though the plateau ends right after.
    #[test]
    fn a_plateau_is_scored_from_its_start() {
        let mut torque = vec![[0.0; 2]; 12];
        for t in torque.iter_mut().take(10).skip(3) {
            *t = [0.0, 3.0];
        }
        let mut flags = vec![(false, -1); 12];
        for f in flags.iter_mut().take(10).skip(3) {
            *f = (true, 1);
        }
        let m = run(&flags, &torque);
        assert_eq!(m.contact_isolation, Some(1.0));
    }
}
