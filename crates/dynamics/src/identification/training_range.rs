//! The positions an identification was fitted on, and how far other motion leaves them.
//! Inside that range the fitted springs, offsets and gravity were checked against the
//! recording; outside it they extrapolate, and no held-out stretch of the same recording
//! says how well (docs/experiments.md, "Stretches that leave the training range").

use crate::identification::{Identification, Samples};

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

/// Whether any joint's position `q` is outside its training range (beyond the margin);
/// false for an empty range (none recorded) and for NaN. Allocation-free.
#[inline]
pub fn outside_training_range(range: &[[f64; 2]], q: &[f64]) -> bool {
    range
        .iter()
        .zip(q)
        .any(|(r, &x)| beyond_training_range(*r, x).1)
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

impl Identification {
    /// Per joint, how the positions `q` (row-major, one row of `n` per sample) leave the
    /// summary's `training_range` by more than [`TRAINING_RANGE_MARGIN`] of its span; empty when the identification records none (files
    /// written before it was recorded, or `from_model`) or `q` is not whole rows.
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
        for row in q.chunks_exact(n) {
            for ((e, r), &x) in out.iter_mut().zip(range).zip(row) {
                e.lowest = e.lowest.min(x);
                e.highest = e.highest.max(x);
                let (beyond, outside) = beyond_training_range(*r, x);
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
            &near[..2]
        ));
        assert!(outside_training_range(
            &ident.summary.training_range,
            &near[2..]
        ));
        // Not whole rows: nothing.
        assert!(ident.range_excursions(&other[..5]).is_empty());
    }
}
