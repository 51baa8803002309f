//! Least-squares identification of an arm from free motion (docs/method.md section 1):
//! `tau = Y(q, q', q'') pi + tau_joint`, regularised toward the URDF, every choice made on
//! motion the fit did not see (`held_out.rs`; the springs in `springs.rs`).

use nalgebra::DVector;

use crate::algorithms::regressor::{inertial_parameters, PARAMETERS_PER_BODY};
use crate::error::DynamicsError;
use crate::identification::base::BaseParameters;
use crate::identification::constrained::BodyExtent;
use crate::identification::fit_acceleration::smoothed_acceleration;
use crate::identification::held_out::{
    best_of, errors_by_gain, held_sums, median_ratio, Fitter, Held, HeldSums, Signals,
};
use crate::identification::joint_terms::{FIRST_SPRING_FEATURE, JOINT_FEATURES};
use crate::identification::normal::{columns, solve, Normal};
use crate::identification::prior_scale::{prior_scale, scaled};
use crate::identification::recording_checks::check_against_urdf;
use crate::identification::samples::Samples;
use crate::identification::settings::{IdentificationSettings, COULOMB_WIDTH_CANDIDATES};
use crate::identification::springs::{choose_springs, joint_column, Choice};
use crate::identification::training_range::training_range;
use crate::identification::training_speed::training_speed;
use crate::identification::urdf_torques::UrdfTorques;
use crate::identification::{Identification, IdentificationSummary};
use crate::model::Model;

/// Ridge weights tried first when none is given: 1e-8 to 1e2, a decade apart (the best is
/// then refined half a decade either side).
fn ridge_grid() -> impl Iterator<Item = f64> {
    (0..=10).map(|k| 10f64.powf(-8.0 + k as f64))
}

/// Acceleration gains tried when none is given: how much of the measured acceleration the
/// prediction trusts (a Wiener gain: 1 for clean accelerations, toward 0 when differentiation
/// noise swamps the inertial torque). Chosen on held-out motion for the fitted model, whose
/// inertias stay fitted to the accelerations as measured.
const GAIN_GRID: [f64; 9] = [1.0, 0.7, 0.5, 0.35, 0.25, 0.15, 0.1, 0.05, 0.0];
/// Largest delay of the torques behind (or ahead of) the motion tried (s), and at least
/// this many samples: series-elastic actuators and torque filters lag by some ms.
const MAX_DELAY_S: f64 = 0.03;
const MIN_DELAY_SAMPLES: f64 = 2.0;
/// At most this many candidate shifts (half a sample apart, or wider).
const MAX_SHIFTS: usize = 25;

/// Candidate shifts of the torques against the motion (samples), zero first.
fn shift_grid(rate_hz: Option<f64>) -> Vec<f64> {
    let Some(rate) = rate_hz else {
        return vec![0.0];
    };
    let reach = (MAX_DELAY_S * rate).max(MIN_DELAY_SAMPLES);
    let step = (2.0 * reach / (MAX_SHIFTS - 1) as f64).max(0.5);
    let steps = (reach / step).floor() as i64;
    let mut grid = vec![0.0];
    for k in 1..=steps {
        grid.push(k as f64 * step);
        grid.push(-(k as f64) * step);
    }
    grid
}
/// Ridge of the plain solves that choose the delay.
const DELAY_RIDGE: f64 = 1e-3;
/// Share of the held-out error a delay must remove to be kept. Smaller gains are model
/// error that a shift happens to mimic on that motion (a delay worth applying removes
/// more): on simulated arms
/// whose true delay is zero, 5 ms removed 4 % of a validation recording's error on the UR5,
/// and on other motion the momentum observer raised 142 false contact events in 10 min
/// instead of 16.
const MIN_DELAY_GAIN: f64 = 0.2;
/// Share of the held-out error another Coulomb width must remove to replace the first.
const MIN_WIDTH_GAIN: f64 = 0.01;

/// Identifies `model`'s inertial parameters and joint terms from free-motion `train`
/// samples (see [`IdentificationSettings`]); `validation`, when given, is another
/// recording on which every setting is chosen and the expected error measured, else
/// blocked cross-validation over contiguous stretches of `train` does both. Besides the
/// ridge and the springs, the held-out motion chooses how much of the measured acceleration
/// to trust (`acceleration_gain`) and, when the sample rate is given, the delay of the
/// torque behind the motion (`delay_s`). The result is physical whatever the settings:
/// joint terms always (`JointTerms::is_physical`), bodies with `physical_consistency`.
pub fn identify(
    model: &Model,
    train: &Samples,
    validation: Option<&Samples>,
    settings: &IdentificationSettings,
) -> Result<Identification, DynamicsError> {
    settings.validate()?;
    let n = model.nq();
    check_sizes(train, validation, settings, n)?;
    check_motion(model, train, "training samples")?;
    // The URDF arm's torque on the training samples serves the checks and the prior's scale.
    let urdf_train = UrdfTorques::new(model, train, true);
    check_against_urdf(model, train, &urdf_train.total, "training samples")?;
    let urdf_validation = match validation {
        Some(v) => {
            let torques = UrdfTorques::new(model, v, false);
            check_against_urdf(model, v, &torques.total, "validation samples")?;
            Some(torques)
        }
        None => None,
    };
    let widths: Vec<f64> = match settings.coulomb_width {
        Some(w) => vec![w],
        None if settings.friction => COULOMB_WIDTH_CANDIDATES.to_vec(),
        None => vec![COULOMB_WIDTH_CANDIDATES[0]],
    };
    let p = columns(n);
    let mut prior = DVector::zeros(p);
    prior
        .rows_mut(0, PARAMETERS_PER_BODY * n)
        .copy_from_slice(&inertial_parameters(model));
    let shifts = shift_grid(settings.sample_rate_hz.filter(|_| settings.delay));
    // The fit regresses on a smoothed acceleration (`fit_acceleration.rs`); everything
    // scored uses the acceleration as measured.
    let smoothed = |s: &Samples| match (settings.sample_rate_hz, settings.fit_acceleration_hz) {
        (Some(rate), Some(hz)) => smoothed_acceleration(s, rate, hz),
        _ => None,
    };
    let train_acceleration = smoothed(train);
    let validation_acceleration = validation.and_then(smoothed);
    let fit_train = fitted_on(train, &train_acceleration);
    let fit_validation = validation.map(|v| (fitted_on(v, &validation_acceleration), *v));
    let sums = held_sums(
        model,
        &fit_train,
        fit_validation
            .as_ref()
            .map(|(fitted, scored)| (fitted, scored)),
        settings,
        &shifts,
        &widths,
    )?;
    let mut active: Vec<bool> = (0..p)
        .map(|c| c < PARAMETERS_PER_BODY * n || settings.friction)
        .collect();
    for i in 0..n {
        for f in FIRST_SPRING_FEATURE..JOINT_FEATURES {
            active[joint_column(n, i, f)] = false;
        }
    }
    let gains: Vec<f64> = match settings.acceleration_gain {
        Some(g) => vec![g],
        None => GAIN_GRID.to_vec(),
    };
    // The model is fitted to the accelerations as measured (gain 1: its inertias are the
    // arm's); the gain that weights noisy accelerations in predictions is chosen after.
    let first = sums.at_width(0, &prior)?;
    let signals = choose_delay(&first, &active, &prior, shifts.len(), n);
    let chosen_width = choose_width(&sums, &active, &prior, &signals, n);
    let (held, width) = match chosen_width {
        0 => (first, widths[0]),
        w => (sums.at_width(w, &prior)?, widths[w]),
    };
    // The ridge pulls toward the URDF at the torque's size (`IdentificationSummary::
    // prior_scale`). Held-out motion is not asked: on one recording whose stretches repeat
    // its motion it scored both priors within 1 % and kept the URDF's on 7 of 10 simulated
    // arms whose torque was 1.05 times the URDF's, where the scaled prior lowered the false
    // torque on new motion by up to 19 % (docs/experiments.md).
    let urdf = prior;
    let (prior_scale, prior) = match prior_scale(model, train, &urdf_train, width)? {
        Some(s) => (s, scaled(&urdf, s, n)),
        None => (1.0, urdf.clone()),
    };
    let extents = match settings.max_mass_ratio {
        Some(ratio) if settings.physical_consistency => body_extents(model, &prior, ratio),
        _ => Vec::new(),
    };
    let fitter = Fitter {
        physical: settings.physical_consistency,
        extents: &extents,
        plain: false,
        bodies: n,
    };
    let choose_ridge = |active: &[bool], signals: &Signals| {
        let ridge = RidgeChoice {
            given: settings.ridge,
            tolerance: settings.ridge_tolerance,
        };
        ridge_for(ridge, &held, fitter, active, &prior, signals)
    };
    let (ridge, best) = choose_ridge(&active, &signals);
    let mut choice = Choice {
        active,
        ridge,
        best,
    };
    let springs = if settings.springs && best.is_finite() {
        choose_springs(
            model,
            train,
            width,
            &held,
            fitter,
            &prior,
            &signals,
            &mut choice,
            choose_ridge,
        )?
    } else {
        vec![false; n]
    };
    let Choice {
        active,
        ridge,
        best,
    } = choice;
    if !best.is_finite() {
        return Err(DynamicsError::InvalidArgument(
            "identification failed: no setting gave a finite fit (the samples may not move the arm: check the recording)".into(),
        ));
    }
    let fit = |normal: &Normal| -> Result<(DVector<f64>, Vec<usize>), DynamicsError> {
        let x = fitter.fit(normal, &active, &prior, ridge).ok_or_else(|| {
            DynamicsError::InvalidArgument(
                "identification: the least-squares system is singular".into(),
            )
        })?;
        // Bodies the unconstrained fit would have made impossible (the constrained fit
        // keeps them possible; listed so that a user sees where the data disagree).
        let impossible = match solve(normal, &active, &prior, ridge) {
            Some(free) if settings.physical_consistency => {
                (0..n).filter(|&b| !body_possible(&free, b)).collect()
            }
            _ => Vec::new(),
        };
        Ok((x, impossible))
    };
    let (x, projected) = fit(&held.all_training(&signals))?;
    let at_extent: Vec<usize> = extents
        .iter()
        .enumerate()
        .filter(|&(b, e)| {
            let mut p = [0.0; PARAMETERS_PER_BODY];
            p.copy_from_slice(
                &x.as_slice()[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY],
            );
            e.reached(&p)
        })
        .map(|(b, _)| b)
        .collect();
    let range = training_range(train);
    let mut identified = Identification::from_solution(model, &x, width)?;
    identified.continue_springs_beyond(&range);
    let refit = |normal: &Normal| {
        let (xb, _) = fit(normal)?;
        Identification::from_solution(model, &xb, width)
    };
    let (sq, count, held_out) =
        errors_by_gain(&held, train, &identified, refit, &gains, &shifts, &signals)?;
    let (g, _) = best_of(
        sq.iter()
            .enumerate()
            .map(|(g, s)| (g, s.iter().sum::<f64>())),
        0,
    );
    let acceleration_gain = gains[g];
    let per_joint: Vec<f64> = sq[g]
        .iter()
        .map(|s| (s / count.max(1) as f64).sqrt())
        .collect();
    // The URDF's own error on the same held-out motion (it was fitted to nothing): its
    // torque there was computed for the checks.
    let prior_rms = match (&held, &urdf_validation) {
        (Held::Recording { samples, .. }, Some(v)) => v.rms_errors(samples),
        _ => urdf_train.rms_errors(train),
    };
    let base = BaseParameters::new(model, 100, 1)?;
    let summary = IdentificationSummary {
        held_out,
        ridge,
        springs,
        projected_bodies: projected,
        bodies_at_extent: at_extent,
        expected_false_torque_rms: per_joint,
        prior_false_torque_rms: prior_rms,
        base_parameters: base.rank(),
        condition_number: base_condition(&base, &held.all_training(&signals)),
        training_samples: train.len(),
        validation_samples: validation.map_or(0, |v| v.len()),
        settings: settings.clone(),
        input_filter_hz: 0.0,
        delay_s: signals
            .iter()
            .map(|&s| settings.sample_rate_hz.map_or(0.0, |rate| shifts[s] / rate))
            .collect(),
        fit_acceleration_hz: match train_acceleration {
            Some(_) => settings.fit_acceleration_hz.unwrap_or(0.0),
            None => 0.0,
        },
        step_response_s: 0.0,
        acceleration_gain,
        prior_scale,
        training_range: range,
        training_speed: training_speed(train),
        // The motion the gain was chosen on: the validation recording, or the training's.
        acceleration_power: mean_square(validation.unwrap_or(train).qddot, n),
    };
    Ok(Identification {
        summary,
        ..identified
    })
}

/// Per column of rows of `n` values, the mean square of its finite values.
fn mean_square(values: &[f64], n: usize) -> Vec<f64> {
    let mut sums = vec![(0.0, 0usize); n];
    for row in values.chunks_exact(n.max(1)) {
        for (s, &v) in sums.iter_mut().zip(row) {
            if v.is_finite() {
                s.0 += v * v;
                s.1 += 1;
            }
        }
    }
    sums.iter().map(|&(s, c)| s / c.max(1) as f64).collect()
}

/// `samples` with the fit's acceleration in place of the measured one, when there is one.
fn fitted_on<'a>(samples: &Samples<'a>, acceleration: &'a Option<Vec<f64>>) -> Samples<'a> {
    Samples {
        qddot: acceleration.as_deref().unwrap_or(samples.qddot),
        ..*samples
    }
}

/// Enough training (and validation) samples for `n` joints.
fn check_sizes(
    train: &Samples,
    validation: Option<&Samples>,
    settings: &IdentificationSettings,
    n: usize,
) -> Result<(), DynamicsError> {
    train.check("training samples", n)?;
    let min_samples = 2 * settings.folds.max(2) * n;
    if train.len() < min_samples.max(20) {
        return Err(DynamicsError::InvalidArgument(format!(
            "training samples: {} samples are too few to identify {n} joints (need at least {})",
            train.len(),
            min_samples.max(20)
        )));
    }
    if let Some(v) = validation {
        v.check("validation samples", n)?;
        if v.len() < 10 {
            return Err(DynamicsError::InvalidArgument(format!(
                "validation samples: {} are too few (need 10)",
                v.len()
            )));
        }
    }
    Ok(())
}

/// The Coulomb width (index among the candidates): scored as the delay is, with plain
/// ridge solves, but on the held-out torque itself (every joint weighted alike, as the
/// expected false torque is: the joints' weights depend on the width), and another than the
/// first taken only where it removes `MIN_WIDTH_GAIN` of the first's error. Weighted by the
/// joints' residuals (with 0.02 among the candidates then), the choice differed on six of ten
/// simulated arms from the width whose identification had the lowest held-out expected false
/// torque, and left the UR3 and UR10 at 0.01 (docs/experiments.md).
fn choose_width(
    sums: &HeldSums<'_>,
    active: &[bool],
    prior: &DVector<f64>,
    signals: &Signals,
    n: usize,
) -> usize {
    if sums.widths() <= 1 {
        return 0;
    }
    let plain = Fitter {
        physical: false,
        extents: &[],
        plain: true,
        bodies: n,
    };
    let alike = vec![1.0; n];
    let score = |w: usize| {
        let held = sums.weighted(w, &alike);
        (w, held.score(plain, active, prior, DELAY_RIDGE, signals))
    };
    let first = score(0).1;
    let (best, lowest) = best_of((1..sums.widths()).map(score), 0);
    if lowest < (1.0 - MIN_WIDTH_GAIN) * first {
        best
    } else {
        0
    }
}

/// The delay of the torque behind the motion: one for all joints (the sensors' timing),
/// scanned with plain ridge solves (a factorisation each; timing is not a question of
/// physical consistency) and kept only where it removes `MIN_DELAY_GAIN` of the held-out
/// error. A delay per joint, or any gain taken, chose shifts of 12 ms on simulated arms
/// whose true delay is zero and doubled their error on new motion.
fn choose_delay(
    held: &Held<'_>,
    active: &[bool],
    prior: &DVector<f64>,
    shifts: usize,
    n: usize,
) -> Signals {
    let plain = Fitter {
        physical: false,
        extents: &[],
        plain: true,
        bodies: n,
    };
    if shifts <= 1 {
        return vec![0; n];
    }
    let score = |s: usize| {
        (
            s,
            held.score(plain, active, prior, DELAY_RIDGE, &vec![s; n]),
        )
    };
    let zero = score(0).1;
    let (best, lowest) = best_of((1..shifts).map(score), 0);
    // Over stretches the middle one decides, as for springs: a shift that mimics model error
    // on one stretch's motion is not a delay (measured: a TALOS arm's slow recording took
    // 22.5 ms from one stretch while three of five got worse, and the arm's second joint then
    // erred twice as much as plain least squares on fast motion).
    let gains = match (
        held.fold_errors(plain, active, prior, DELAY_RIDGE, &vec![0; n]),
        held.fold_errors(plain, active, prior, DELAY_RIDGE, &vec![best; n]),
    ) {
        (Some((without, _)), Some((with, _))) => {
            median_ratio(&without, &with) < 1.0 - MIN_DELAY_GAIN
        }
        _ => lowest < (1.0 - MIN_DELAY_GAIN) * zero,
    };
    if gains {
        vec![best; n]
    } else {
        vec![0; n]
    }
}

/// How the ridge is set: `given`, else chosen on held-out motion, the strongest within
/// `tolerance` of the best held-out error.
#[derive(Clone, Copy)]
struct RidgeChoice {
    given: Option<f64>,
    tolerance: f64,
}

/// The ridge with its held-out score: the given one, else from a decade grid refined half a
/// decade either side, the best or (with a tolerance) the strongest within it of the best.
fn ridge_for(
    choice: RidgeChoice,
    held: &Held<'_>,
    fitter: Fitter<'_>,
    active: &[bool],
    prior: &DVector<f64>,
    signals: &Signals,
) -> (f64, f64) {
    let score = |r: f64| (r, held.score(fitter, active, prior, r, signals));
    if let Some(r) = choice.given {
        return score(r);
    }
    let half = 10f64.sqrt();
    if choice.tolerance == 0.0 {
        // The first best on ties, as before the tolerance existed: fits without it unchanged.
        let coarse = best_of(ridge_grid().map(score), f64::NAN);
        if coarse.0.is_nan() {
            return coarse;
        }
        return best_of(
            [coarse, score(coarse.0 / half), score(coarse.0 * half)].into_iter(),
            f64::NAN,
        );
    }
    let mut scored: Vec<(f64, f64)> = ridge_grid().map(score).collect();
    let coarse = strongest_within(&scored, choice.tolerance);
    if coarse.0.is_nan() {
        return coarse;
    }
    scored.extend([score(coarse.0 / half), score(coarse.0 * half)]);
    strongest_within(&scored, choice.tolerance)
}

/// The largest ridge whose score is within `tolerance` of the best score (NaN when none is
/// finite).
fn strongest_within(scored: &[(f64, f64)], tolerance: f64) -> (f64, f64) {
    let best = scored.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return (f64::NAN, f64::INFINITY);
    }
    scored
        .iter()
        .copied()
        .filter(|s| s.1 <= best * (1.0 + tolerance))
        .fold((f64::NAN, f64::INFINITY), |a, s| {
            if a.0.is_nan() || s.0 > a.0 {
                s
            } else {
                a
            }
        })
}

/// Refuses samples that do not move the arm (a joint whose angle and velocity hardly
/// change cannot be identified, and the fit would only return the URDF with an infinite
/// condition number) or carry no torque (a joint at exactly 0 in every sample: a missing
/// column, which the fit would explain with a massless arm).
fn check_motion(model: &Model, samples: &Samples, what: &str) -> Result<(), DynamicsError> {
    let n = samples.dof;
    let names: Vec<&str> = model.joint_names().collect();
    for i in 0..n {
        let name = names.get(i).copied().unwrap_or("?");
        let (mut lo, mut hi, mut speed) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for k in 0..samples.len() {
            let q = samples.q[k * n + i];
            lo = lo.min(q);
            hi = hi.max(q);
            speed = speed.max(samples.qdot[k * n + i].abs());
        }
        if (0..samples.len()).all(|k| samples.tau[k * n + i] == 0.0) {
            return Err(DynamicsError::InvalidArgument(format!(
                "{what}: joint {name}'s torque is 0 in every sample: identification needs the \
                 torque the joints measured or were commanded (check the tau columns)"
            )));
        }
        if !(hi - lo > 1e-3 && speed > 1e-3) {
            return Err(DynamicsError::InvalidArgument(format!(
                "{what}: joint {name} does not move (range {:.2e} rad, top speed {speed:.2e} rad/s): \
                 identification needs free motion of every joint of the chain (record an \
                 excitation: `admittance excite`), or a chain that ends before it (--tip)",
                hi - lo
            )));
        }
    }
    Ok(())
}

/// How far beyond the prior's size a body's mass may spread: its rms distance from the
/// joint at most this many times the larger of the prior's and the next joint's distance.
const EXTENT_SIZE_FACTOR: f64 = 2.0;
/// A body may gain this share of the whole arm's prior mass beyond `max_mass_ratio` times
/// its own, so that a link the URDF gives next to nothing can still take a real mass.
const EXTENT_ARM_SHARE: f64 = 0.05;
/// The smallest radius (m) of a body's sphere.
const EXTENT_MIN_RADIUS: f64 = 0.02;

/// Each body's extent (`IdentificationSettings::max_mass_ratio`): mass at most `ratio`
/// times the prior's plus [`EXTENT_ARM_SHARE`] of the arm's, within a sphere about the
/// joint [`EXTENT_SIZE_FACTOR`] times the body's size. The prior is strictly inside both.
fn body_extents(model: &Model, prior: &DVector<f64>, ratio: f64) -> Vec<BodyExtent> {
    let n = model.nq();
    let body = |b: usize| {
        let mut p = [0.0; PARAMETERS_PER_BODY];
        p.copy_from_slice(
            &prior.as_slice()[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY],
        );
        crate::spatial::Inertia::from_parameters(&p)
    };
    let arm: f64 = (0..n).map(|b| body(b).mass.max(0.0)).sum();
    (0..n)
        .map(|b| {
            let inertia = body(b);
            // The mean square distance of the mass from the joint, tr(I_o) / (2 m).
            let spread = if inertia.mass > 0.0 {
                (0.5 * inertia.rotational.trace() / inertia.mass)
                    .max(0.0)
                    .sqrt()
            } else {
                0.0
            };
            let next = model
                .joints
                .get(b + 1)
                .map_or(0.0, |j| j.placement.translation.norm());
            BodyExtent {
                max_mass: ratio * inertia.mass.max(0.0) + EXTENT_ARM_SHARE * arm,
                centre: [0.0; 3],
                radius: EXTENT_SIZE_FACTOR * spread.max(next).max(EXTENT_MIN_RADIUS),
            }
        })
        .collect()
}

fn body_possible(x: &DVector<f64>, b: usize) -> bool {
    let mut p = [0.0; PARAMETERS_PER_BODY];
    p.copy_from_slice(&x.as_slice()[b * PARAMETERS_PER_BODY..(b + 1) * PARAMETERS_PER_BODY]);
    crate::identification::consistency::is_physically_consistent(
        &crate::spatial::Inertia::from_parameters(&p),
    )
}

/// Condition number of the training data's base regressor, from the Gram matrix of its
/// independent inertial columns scaled to unit norm.
fn base_condition(base: &BaseParameters, normal: &Normal) -> f64 {
    let idx = base.independent();
    let g = nalgebra::DMatrix::from_fn(idx.len(), idx.len(), |r, c| {
        let (a, b) = (idx[r], idx[c]);
        normal.gram[(a, b)]
            / (normal.gram[(a, a)] * normal.gram[(b, b)])
                .sqrt()
                .max(1e-300)
    });
    let e = g.symmetric_eigenvalues();
    if e.min() > 0.0 {
        (e.max() / e.min()).sqrt()
    } else {
        f64::INFINITY
    }
}
