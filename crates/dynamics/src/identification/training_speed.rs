//! The speeds an identification was fitted at, and how far other motion exceeds them.
//! Up to those speeds the fitted friction (viscous, Coulomb, its width) was checked against
//! the recording; faster it extrapolates: a joint trained slowly, where a soft dry friction
//! looks viscous, takes a viscous slope that over-predicts at speed (docs/experiments.md,
//! "Motion faster than the training").

use crate::identification::{Identification, Samples};

/// How far beyond its highest training speed a joint may move before it counts as faster
/// than trained, as a share of that speed: another stretch of the same kind of motion
/// passes its training peaks by tens of percent (on five MuJoCo arms, another seed of the
/// same excitation went beyond them by 10 % on 0 to 31 % of the rows, with no larger error
/// there, by half on 0 to 7 %), while motion several times faster than the training's is
/// where the fitted friction errs (docs/experiments.md, "Motion faster than the training").
pub const TRAINING_SPEED_MARGIN: f64 = 0.5;

/// How far the speed `|v|` lies above `highest` (rad/s or m/s; 0 below); it counts as
/// faster than trained when that is more than [`TRAINING_SPEED_MARGIN`] of `highest`.
#[inline]
pub fn beyond_training_speed(highest: f64, v: f64) -> (f64, bool) {
    let beyond = (v.abs() - highest).max(0.0);
    (beyond, beyond > TRAINING_SPEED_MARGIN * highest)
}

/// Whether any joint's velocity `qdot` exceeds its highest training speed by more than the
/// margin ([`beyond_training_speed`]); false for an empty list (none recorded) and for NaN.
/// Allocation-free.
#[inline]
pub fn faster_than_training(highest: &[f64], qdot: &[f64]) -> bool {
    highest
        .iter()
        .zip(qdot)
        .any(|(&h, &v)| beyond_training_speed(h, v).1)
}

/// How one joint's velocities in other motion exceed its training speeds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpeedExcursion {
    /// Samples faster than trained (beyond the margin).
    pub samples_faster: usize,
    /// The highest speed of the motion (rad/s or m/s).
    pub fastest: f64,
}

/// Per joint, the highest speed `|q'|` of `samples`.
pub(crate) fn training_speed(samples: &Samples) -> Vec<f64> {
    let n = samples.dof;
    let mut highest = vec![0.0_f64; n];
    for row in samples.qdot.chunks_exact(n) {
        for (h, &v) in highest.iter_mut().zip(row) {
            if v.is_finite() {
                *h = h.max(v.abs());
            }
        }
    }
    highest
}

impl Identification {
    /// Per joint, how the velocities `qdot` (row-major, one row of `n` per sample,
    /// conditioned as the identification was) exceed the summary's `training_speed` by more
    /// than [`TRAINING_SPEED_MARGIN`]; empty when the identification records none (files
    /// written before it was recorded, or `from_model`) or `qdot` is not whole rows.
    pub fn speed_excursions(&self, qdot: &[f64]) -> Vec<SpeedExcursion> {
        let highest = &self.summary.training_speed;
        let n = highest.len();
        if n == 0 || n != self.model.nq() || !qdot.len().is_multiple_of(n) {
            return Vec::new();
        }
        let mut out = vec![SpeedExcursion::default(); n];
        for row in qdot.chunks_exact(n) {
            for ((e, &h), &v) in out.iter_mut().zip(highest).zip(row) {
                e.fastest = e.fastest.max(v.abs());
                if beyond_training_speed(h, v).1 {
                    e.samples_faster += 1;
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

    fn one_joint() -> Model {
        Model::from_urdf_str(
            r#"<robot name="r"><link name="a"/><link name="b"><inertial><mass value="1"/>
            <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
            <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
            <limit lower="-3" upper="3" effort="10" velocity="1"/></joint></robot>"#,
            "one_joint",
            None,
            None,
        )
        .unwrap()
    }

    #[test]
    fn the_speeds_and_what_exceeds_them() {
        let qdot = [0.3, -0.8, 0.5, f64::NAN];
        let zeros = [0.0; 4];
        let samples = Samples {
            q: &zeros,
            qdot: &qdot,
            qddot: &zeros,
            tau: &zeros,
            dof: 1,
        };
        // Either sign counts; a NaN is not a speed.
        assert_eq!(training_speed(&samples), vec![0.8]);
        // Faster than trained beyond half again the highest training speed.
        assert_eq!(beyond_training_speed(0.8, -1.1), (1.1 - 0.8, false));
        let (beyond, faster) = beyond_training_speed(0.8, -1.3);
        assert!(faster && (beyond - 0.5).abs() < 1e-12);
        assert!(!faster_than_training(&[0.8], &[f64::NAN]));
        assert!(!faster_than_training(&[], &[5.0]));
        assert!(faster_than_training(&[0.8, 0.1], &[0.0, 0.2]));
        assert!(!faster_than_training(&[0.8, 0.1], &[0.0, 0.15]));

        let mut ident = Identification::from_model(one_joint());
        assert!(ident.speed_excursions(&[1.0]).is_empty());
        ident.summary.training_speed = training_speed(&samples);
        let e = ident.speed_excursions(&[0.2, -1.7, 1.1, 1.25]);
        assert_eq!(
            e,
            vec![SpeedExcursion {
                samples_faster: 2,
                fastest: 1.7
            }]
        );
    }
}
