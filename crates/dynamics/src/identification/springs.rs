//! Which joints keep spring terms (`k_1 sin q + k_2 cos q + k_3 sin 2q + k_4 cos 2q`,
//! docs/method.md section 1): a spring is kept where it lowers the held-out error by 1 % (of
//! the middle held-out stretch, or of the validation recording), and dropped again when it
//! would exceed what the joint's motor can hold anywhere in its range.

use nalgebra::DVector;

use crate::error::DynamicsError;
use crate::identification::held_out::{median_ratio, Fitter, Held, Signals};
use crate::identification::joint_terms::{JointTerms, FIRST_SPRING_FEATURE, JOINT_FEATURES};
use crate::identification::samples::Samples;
use crate::identification::Identification;
use crate::model::Model;

/// The columns of the fit and the ridge chosen on them, with their held-out score.
pub(super) struct Choice {
    /// The active columns.
    pub active: Vec<bool>,
    /// The ridge weight.
    pub ridge: f64,
    /// The held-out mean squared error.
    pub best: f64,
}

/// The column of joint `i`'s feature `f` among `n` joints.
pub(super) fn joint_column(n: usize, i: usize, f: usize) -> usize {
    crate::algorithms::regressor::PARAMETERS_PER_BODY * n + JOINT_FEATURES * i + f
}

fn set_springs(active: &mut [bool], n: usize, i: usize, on: bool) {
    (FIRST_SPRING_FEATURE..JOINT_FEATURES).for_each(|f| active[joint_column(n, i, f)] = on);
}

/// The joints that keep springs, updating `choice` (columns, ridge, score) as they are
/// taken and dropped; `choose_ridge` rechooses the ridge on a set of columns.
#[allow(clippy::too_many_arguments)]
pub(super) fn choose_springs(
    model: &Model,
    train: &Samples,
    width: f64,
    held: &Held<'_>,
    fitter: Fitter<'_>,
    prior: &DVector<f64>,
    signals: &Signals,
    choice: &mut Choice,
    choose_ridge: impl Fn(&[bool], &Signals) -> (f64, f64),
) -> Result<Vec<bool>, DynamicsError> {
    let n = model.nq();
    let mut springs = vec![false; n];
    let mut current = held.fold_errors(fitter, &choice.active, prior, choice.ridge, signals);
    for i in 0..n {
        let mut trial = choice.active.clone();
        set_springs(&mut trial, n, i, true);
        let trial_folds = held.fold_errors(fitter, &trial, prior, choice.ridge, signals);
        let score = match &trial_folds {
            Some((_, mean)) => *mean,
            None => held.score(fitter, &trial, prior, choice.ridge, signals),
        };
        let keep = match (&current, &trial_folds) {
            (Some((before, _)), Some((after, _))) => median_ratio(before, after) < 0.99,
            // A validation recording: its one error.
            _ => score < 0.99 * choice.best,
        };
        if keep {
            choice.active = trial;
            choice.best = score;
            current = trial_folds;
            springs[i] = true;
        }
    }
    if springs.iter().any(|&s| s) {
        (choice.ridge, choice.best) = choose_ridge(&choice.active, signals);
    }
    // A kept spring must stay a force the joint could meet: cancelling spring terms
    // fit the training range and can reach several times the effort limit outside it
    // (measured: a Panda shoulder spring of up to 800 N m against 87 N m, whose false
    // torque on an unseen excitation was 63 N m rms).
    while springs.iter().any(|&s| s) {
        let all = held.all_training(signals);
        let Some(x) = fitter.fit(&all, &choice.active, prior, choice.ridge) else {
            break;
        };
        // Judged on the series itself, not on its tangents beyond the training range: a
        // series that leaves the motor's effort within the joint's range is a cancelling
        // fit, however it is continued (with the tangents judged instead, the Baxter fit on
        // 30-90 s kept a spring on `e1` whose series was refused, and its false torque 0.76
        // rad beyond the range rose from 0.92 to 2.83 times least squares').
        let trial = Identification::from_solution(model, &x, width)?;
        let wild: Vec<usize> = (0..n)
            .filter(|&i| springs[i] && !spring_within(&trial, train, i))
            .collect();
        if wild.is_empty() {
            break;
        }
        for i in wild {
            springs[i] = false;
            set_springs(&mut choice.active, n, i, false);
        }
        (choice.ridge, choice.best) = choose_ridge(&choice.active, signals);
    }
    Ok(springs)
}

/// Whether joint `i`'s offset and springs stay within what its motor can hold over its
/// range: the URDF's effort limit (twice the largest training torque when the URDF gives
/// none), across its position limits (one turn when it has none).
fn spring_within(identified: &Identification, train: &Samples<'_>, i: usize) -> bool {
    let model = &identified.model;
    let n = model.nq();
    let effort = model.effort_limits().nth(i).unwrap_or(f64::INFINITY);
    let bound = if effort.is_finite() && effort > 0.0 {
        effort
    } else {
        2.0 * train
            .tau
            .iter()
            .skip(i)
            .step_by(n.max(1))
            .fold(0.0, |m: f64, t| m.max(t.abs()))
    };
    let limits = model
        .position_limits()
        .nth(i)
        .unwrap_or((f64::NAN, f64::NAN));
    position_torque_within(&identified.joint_terms[i], limits, bound)
}

/// Whether `|offset + springs(q)|` stays at most `bound` at 256 angles across `limits` (one
/// turn when they are not finite).
fn position_torque_within(terms: &JointTerms, limits: (f64, f64), bound: f64) -> bool {
    let (lower, upper) = match limits {
        (l, u) if l.is_finite() && u.is_finite() && u > l => (l, u),
        _ => (-std::f64::consts::PI, std::f64::consts::PI),
    };
    (0..256).all(|k| {
        let q = lower + (upper - lower) * k as f64 / 255.0;
        terms.velocity_and_position_torque(q, 0.0).abs() <= bound
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spring_is_judged_by_the_middle_stretch_not_by_one_that_extrapolates() {
        // The real Baxter's first 60 s at 4 Hz, mean squares per held-out stretch without and
        // with the shoulder's spring: the last stretch lies beyond the others' positions.
        let without = [1.63, 1.19, 1.31, 0.84, 12.2];
        let with = [1.57, 1.07, 1.45, 0.72, 22.0];
        assert!(with.iter().sum::<f64>() > without.iter().sum::<f64>());
        assert!(median_ratio(&without, &with) < 0.99);
        // One stretch alone gaining is not enough.
        assert!(median_ratio(&[1.0; 5], &[1.0, 1.0, 1.0, 1.0, 0.1]) >= 0.99);
        assert!(median_ratio(&[], &[]).is_infinite());
    }

    #[test]
    fn a_spring_beyond_the_motor_is_refused_and_a_gravity_assist_is_kept() {
        // Fitted on the Panda's multi-sine recording (joint 2, limits +-1.7628 rad, 87 N m):
        // cancelling terms, small near -0.8 rad and hundreds of N m elsewhere.
        let wild = JointTerms {
            offset: 236.787,
            spring: [261.565, -190.710, -83.475, -27.014],
            spring_range: None,
            coulomb_width: 0.01,
            ..JointTerms::default()
        };
        assert!(wild.velocity_and_position_torque(-0.8, 0.0).abs() < 87.0);
        assert!(!position_torque_within(&wild, (-1.7628, 1.7628), 87.0));
        // A counterbalance of 30 N m peak on a 50 N m joint (Baxter's s1 kind).
        let assist = JointTerms {
            spring: [30.0, 5.0, 0.0, 0.0],
            spring_range: None,
            coulomb_width: 0.01,
            ..JointTerms::default()
        };
        assert!(position_torque_within(&assist, (-2.147, 1.047), 50.0));
        // Without limits, one turn.
        assert!(!position_torque_within(
            &assist,
            (f64::NEG_INFINITY, f64::INFINITY),
            20.0
        ));
    }
}
