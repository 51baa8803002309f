//! The positions an identification was fitted on, and how far other motion leaves them.
//! Inside that range the fitted springs, offsets and gravity were checked against the
//! recording; outside it they extrapolate, and no held-out stretch of the same recording
//! says how well (docs/experiments.md, "Stretches that leave the training range").

use std::f64::consts::{PI, TAU};

use crate::identification::{Identification, Samples};
use crate::model::{JointKind, Model};

/// How far beyond its training range a position may lie before it counts as outside, as a
/// share of the range's span: positions that close to the fitted ones are checked by
/// them (a second excitation of the same envelope leaves it by 1e-4 rad), so only motion
/// that really extrapolates is flagged.
pub const TRAINING_RANGE_MARGIN: f64 = 0.02;

/// How far `x` lies beyond `range` (rad or m; 0 inside); it counts as outside when that is
/// more than [`TRAINING_RANGE_MARGIN`] of the span.
#[inline]
pub fn beyond_training_range([low, high]: [f64; 2], x: f64) -> (f64, bool) {
    let beyond = (low - x).max(x - high).max(0.0);
    (beyond, beyond > TRAINING_RANGE_MARGIN * (high - low))
}

/// [`beyond_training_range`] of a joint that may turn without limit (`continuous`): its
/// dynamics repeat every turn, so its angle counts on the turn nearest the range (a range a
/// turn wide or wider holds every angle), whichever branch the recording and the motion were
/// read on.
#[inline]
pub fn beyond_training_range_of(range: [f64; 2], x: f64, continuous: bool) -> (f64, bool) {
    let [low, high] = range;
    if !continuous {
        return beyond_training_range(range, x);
    }
    if high - low >= TAU {
        return (0.0, false);
    }
    let middle = 0.5 * (low + high);
    let turns = ((x - middle) / TAU).round();
    beyond_training_range(range, x - turns * TAU)
}

/// Whether any joint's position `q` is outside its training range (beyond the margin), the
/// joints flagged in `continuous` counted on their nearest turn
/// ([`beyond_training_range_of`]; a missing flag is false); false for an empty range (none
/// recorded) and for NaN. Allocation-free.
#[inline]
pub fn outside_training_range(range: &[[f64; 2]], q: &[f64], continuous: &[bool]) -> bool {
    range.iter().zip(q).enumerate().any(|(i, (r, &x))| {
        beyond_training_range_of(*r, x, continuous.get(i).copied().unwrap_or(false)).1
    })
}

/// How one joint's positions in other motion leave the training range.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RangeExcursion {
    /// Samples whose position is outside the training range.
    pub samples_outside: usize,
    /// The furthest any sample lies beyond the range (rad or m; 0: none outside).
    pub furthest: f64,
    /// The lowest position of the motion.
    pub lowest: f64,
    /// The highest position of the motion.
    pub highest: f64,
}

/// Per joint, the lowest and highest position of `samples`.
pub(crate) fn training_range(samples: &Samples) -> Vec<[f64; 2]> {
    let n = samples.dof;
    let mut range = vec![[f64::INFINITY, f64::NEG_INFINITY]; n];
    for row in samples.q.chunks_exact(n) {
        for (r, &q) in range.iter_mut().zip(row) {
            r[0] = r[0].min(q);
            r[1] = r[1].max(q);
        }
    }
    range
}

/// Per joint, the range beyond which its springs continue along their tangent
/// ([`crate::identification::JointTerms::spring_range`]): `range`'s where it spans less than
/// half a turn. Over half a turn or more the series' four terms are told apart by the data
/// and the rest of the turn lies between two fitted ends, so the series itself is kept (on
/// the real Baxter a wrist spring fitted over 4.7 rad held better so: its contact floor
/// raised 5 false events in 29 s at 60 per hour, 7 with the tangent); over less they look
/// alike (a polynomial of degree 4 near the range) and their continuation is arbitrary. A
/// continuous joint keeps the series too: its springs repeat every turn.
pub(crate) fn spring_ranges(model: &Model, range: &[[f64; 2]]) -> Vec<Option<[f64; 2]>> {
    model
        .joints
        .iter()
        .zip(range)
        .map(|(j, &[low, high])| {
            let tangent = j.kind != JointKind::Continuous
                && low.is_finite()
                && high.is_finite()
                && low <= high
                && high - low < PI;
            tangent.then_some([low, high])
        })
        .collect()
}

impl Identification {
    /// Makes each joint's springs, where it has any, continue linearly beyond `range` (per
    /// joint, where they were fitted; [`spring_ranges`]).
    pub(crate) fn continue_springs_beyond(&mut self, range: &[[f64; 2]]) {
        let ranges = spring_ranges(&self.model, range);
        for (terms, r) in self.joint_terms.iter_mut().zip(ranges) {
            terms.spring_range = r.filter(|_| terms.spring.iter().any(|&k| k != 0.0));
        }
    }

    /// Per joint, how the positions `q` (row-major, one row of `n` per sample) leave the
    /// summary's `training_range` by more than [`TRAINING_RANGE_MARGIN`] of its span (a
    /// continuous joint on its nearest turn: [`beyond_training_range_of`]); empty when the
    /// identification records none (files written before it was recorded, or `from_model`)
    /// or `q` is not whole rows.
    pub fn range_excursions(&self, q: &[f64]) -> Vec<RangeExcursion> {
        let range = &self.summary.training_range;
        let n = range.len();
        if n == 0 || n != self.model.nq() || !q.len().is_multiple_of(n) {
            return Vec::new();
        }
        let mut out = vec![
            RangeExcursion {
                lowest: f64::INFINITY,
                highest: f64::NEG_INFINITY,
                ..Default::default()
            };
            n
        ];
        let continuous: Vec<bool> = self
            .model
            .joints
            .iter()
            .map(|j| j.kind == JointKind::Continuous)
            .collect();
        for row in q.chunks_exact(n) {
            for (((e, r), &x), &turns) in out.iter_mut().zip(range).zip(row).zip(&continuous) {
                e.lowest = e.lowest.min(x);
                e.highest = e.highest.max(x);
                let (beyond, outside) = beyond_training_range_of(*r, x, turns);
                if outside {
                    e.samples_outside += 1;
                    e.furthest = e.furthest.max(beyond);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;

    fn two_link() -> Model {
        Model::from_urdf_str(
            r#"<robot name="r"><link name="a"/><link name="b"><inertial><mass value="1"/>
            <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
            <link name="c"><inertial><mass value="1"/>
            <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
            <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
            <limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
            <joint name="j2" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 1 0"/>
            <limit lower="-3" upper="3" effort="10" velocity="1"/></joint></robot>"#,
            "two_link",
            None,
            None,
        )
        .unwrap()
    }

    #[test]
    fn the_range_and_what_leaves_it() {
        let q = [0.1, -0.5, -0.2, 0.4, 0.3, 0.0];
        let zeros = [0.0; 6];
        let samples = Samples {
            q: &q,
            qdot: &zeros,
            qddot: &zeros,
            tau: &zeros,
            dof: 2,
        };
        assert_eq!(training_range(&samples), vec![[-0.2, 0.3], [-0.5, 0.4]]);
        let mut ident = Identification::from_model(two_link());
        // No range recorded: nothing to report.
        assert!(ident.range_excursions(&q).is_empty());
        ident.summary.training_range = training_range(&samples);
        let inside = ident.range_excursions(&q);
        assert!(inside
            .iter()
            .all(|e| e.samples_outside == 0 && e.furthest == 0.0));
        let other = [0.5, 0.0, -0.7, 0.1, 0.2, 0.0];
        let e = ident.range_excursions(&other);
        assert_eq!(e[0].samples_outside, 2);
        assert!((e[0].furthest - 0.5).abs() < 1e-15);
        assert_eq!((e[0].lowest, e[0].highest), (-0.7, 0.5));
        assert_eq!(e[1].samples_outside, 0);
        // Within the margin (2 % of joint 0's 0.5 rad span, 0.01 rad): not outside.
        let near = [0.3 + 0.009, 0.0, -0.2 - 0.011, 0.0];
        let e = ident.range_excursions(&near);
        assert_eq!(e[0].samples_outside, 1);
        assert!((e[0].furthest - 0.011).abs() < 1e-12);
        assert!(!outside_training_range(
            &ident.summary.training_range,
            &near[..2],
            &[]
        ));
        assert!(outside_training_range(
            &ident.summary.training_range,
            &near[2..],
            &[]
        ));
        // Not whole rows: nothing.
        assert!(ident.range_excursions(&other[..5]).is_empty());
    }

    #[test]
    fn springs_take_a_tangent_beyond_less_than_half_a_turn_only() {
        let mut ident = Identification::from_model(two_link());
        ident.joint_terms[0].spring = [5.0, 1.0, 0.0, 0.0];
        ident.joint_terms[1].spring = [5.0, 1.0, 0.0, 0.0];
        ident.continue_springs_beyond(&[[-0.5, 1.0], [-2.0, 1.2]]);
        assert_eq!(ident.joint_terms[0].spring_range, Some([-0.5, 1.0]));
        // 3.2 rad: the series is kept.
        assert_eq!(ident.joint_terms[1].spring_range, None);
        // No springs: no range.
        ident.joint_terms[0].spring = [0.0; 4];
        ident.continue_springs_beyond(&[[-0.5, 1.0], [-0.5, 1.0]]);
        assert_eq!(ident.joint_terms[0].spring_range, None);
        assert_eq!(ident.joint_terms[1].spring_range, Some([-0.5, 1.0]));
        // An empty range (a fold without samples) is none either.
        let none = [f64::INFINITY, f64::NEG_INFINITY];
        ident.continue_springs_beyond(&[none, none]);
        assert_eq!(ident.joint_terms[1].spring_range, None);
    }
}

#[cfg(test)]
mod continuous_tests {
    use super::*;

    #[test]
    fn a_continuous_joint_counts_on_the_turn_nearest_its_range() {
        let range = [2.5, 3.5];
        // A turn away, the same angle: inside for a continuous joint, outside for another.
        for x in [3.0 - TAU, 3.0 + TAU, 3.0 + 3.0 * TAU] {
            assert!(!beyond_training_range_of(range, x, true).1, "{x}");
            assert!(beyond_training_range_of(range, x, false).1, "{x}");
        }
        // Beyond the range on every turn: outside by the same amount on each.
        let (beyond, outside) = beyond_training_range_of(range, 4.0 - TAU, true);
        assert!(outside && (beyond - 0.5).abs() < 1e-12, "{beyond}");
        // A range a turn wide holds every angle.
        assert!(!beyond_training_range_of([-4.0, 2.5], 40.0, true).1);
        assert!(!outside_training_range(
            &[range, range],
            &[3.0, 3.0 + TAU],
            &[false, true]
        ));
        assert!(outside_training_range(
            &[range, range],
            &[3.0 + TAU, 3.0],
            &[false, true]
        ));
    }
}
