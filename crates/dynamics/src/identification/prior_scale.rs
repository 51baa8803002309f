//! The size of the URDF's inertial parameters that the recorded torque asks for.
//!
//! The ridge pulls every body toward the URDF. When the torque signal and the URDF disagree
//! in scale (a motor's torque constant or a gear ratio off by some percent, a torque in other
//! units, masses uniformly off in the URDF) the strong ridges that hold poorly excited
//! directions in place pull toward the wrong size, and held-out motion then chooses a weak
//! ridge and an overfitted arm. A prior scaled by one factor keeps the URDF's shape (mass
//! distribution, relative inertias) at the torque's size; scaling by `s > 0` keeps a
//! physically consistent body consistent.

use nalgebra::{DMatrix, DVector};

use crate::algorithms::regressor::PARAMETERS_PER_BODY;
use crate::error::DynamicsError;
use crate::identification::joint_terms::{features, JOINT_FEATURES};
use crate::identification::samples::Samples;
use crate::identification::urdf_torques::UrdfTorques;
use crate::model::Model;

/// Scales outside this range are not a calibration error but a wrong model or signal; the
/// URDF's prior is kept.
const SCALE_RANGE: std::ops::RangeInclusive<f64> = 0.25..=4.0;

/// Within this fraction of 1 the URDF's prior is kept: a fit of a torque at the URDF's size
/// stays the one before the scale existed, and smaller differences are below the estimate's
/// own spread (0.95 to 1.035 at 4 and 10 Hz on simulated arms whose torque has the URDF's
/// size exactly).
const MIN_DEVIATION: f64 = 0.01;

/// Contiguous stretches left out in turn to see how far the scale moves with the motion.
const STRETCHES: usize = 5;
/// Student's t for a two-sided 95 % interval with `STRETCHES - 1` degrees of freedom: a scale
/// is read, or refused, only when it lies that many jackknife errors from 1 (or the range).
const T_95: f64 = 2.776;

/// The least-squares `s` of `tau ~ s h(q, q') + a M(q) q'' + J x` on `samples`, with `h` the
/// URDF's gravity and Coriolis torque, `M q''` its inertial torque and every joint feature
/// `J` (friction, offsets, springs: not the URDF's to scale) as nuisance terms; `None` when
/// it is within [`MIN_DEVIATION`] of 1 or within [`T_95`] of its own standard errors of 1, the
/// system is singular, or `s h` explains too little of the torque to tell (below
/// [`EXPLAINED`]: `s` is then noise). The standard error is the delete-a-stretch jackknife's
/// over [`STRETCHES`] contiguous stretches: a recording that barely moves its joints leaves
/// `h` nearly constant, where the offsets take it and `s` is whatever the noise makes it
/// (measured: 3 s and 10 s of the simulated Panda's excitation read 0.67 to 2.47, and -0.37,
/// for a torque of the URDF's size). A scale outside [`SCALE_RANGE`] by more than as many errors
/// that explains the torque is refused: the torque is in other units, has the opposite
/// sign, or the URDF is not the arm's. The inertial torque has its own factor because a
/// measured `q''` is noisy: sharing `s` with it, the noise pulled the scale of simulated arms
/// whose torque has the URDF's size down to 0.54-0.86 on unfiltered signals.
pub(super) fn prior_scale(
    model: &Model,
    samples: &Samples,
    urdf: &UrdfTorques,
    width: f64,
) -> Result<Option<f64>, DynamicsError> {
    let n = model.nq();
    let m = 2 + JOINT_FEATURES * n;
    let len = samples.len();
    if urdf.bias.len() != urdf.total.len() || urdf.total.len() != len * n {
        return Ok(None);
    }
    // Per stretch: the normal equations and the torque's squares.
    let mut parts = vec![(DMatrix::<f64>::zeros(m, m), DVector::<f64>::zeros(m), 0.0); STRETCHES];
    let mut row = vec![0.0; 2 + JOINT_FEATURES];
    let mut f = [0.0; JOINT_FEATURES];
    for k in 0..len {
        let (gram, rhs, tau_sq) = &mut parts[(k * STRETCHES / len.max(1)).min(STRETCHES - 1)];
        let r = k * n..(k + 1) * n;
        let (q, qd, qdd) = (
            &samples.q[r.clone()],
            &samples.qdot[r.clone()],
            &samples.qddot[r.clone()],
        );
        let (bias, total) = (&urdf.bias[r.clone()], &urdf.total[r]);
        for i in 0..n {
            features(q[i], qd[i], qdd[i], width, None, &mut f);
            row[0] = bias[i];
            row[1] = total[i] - bias[i];
            row[2..].copy_from_slice(&f);
            // Columns of this row: 0, 1 and joint i's features.
            let col = |c: usize| {
                if c < 2 {
                    c
                } else {
                    2 + JOINT_FEATURES * i + c - 2
                }
            };
            let tau = samples.tau[k * n + i];
            *tau_sq += tau * tau;
            for (a, &x) in row.iter().enumerate() {
                rhs[col(a)] += x * tau;
                for (b, &y) in row.iter().enumerate() {
                    gram[(col(a), col(b))] += x * y;
                }
            }
        }
    }
    let mut gram = DMatrix::<f64>::zeros(m, m);
    let mut rhs = DVector::<f64>::zeros(m);
    let mut tau_sq = 0.0;
    for (g, r, t) in &parts {
        gram += g;
        rhs += r;
        tau_sq += t;
    }
    let urdf_sq = gram[(0, 0)];
    if !(urdf_sq > 0.0 && tau_sq > 0.0) {
        return Ok(None);
    }
    let Some(s) = scale_of(&gram, &rhs) else {
        return Ok(None);
    };
    if s * s * urdf_sq < EXPLAINED * tau_sq {
        return Ok(None);
    }
    let error = jackknife_error(&gram, &rhs, &parts);
    if !SCALE_RANGE.contains(&s)
        && (s - SCALE_RANGE.start()).min(SCALE_RANGE.end() - s).abs() > T_95 * error
        && error.is_finite()
    {
        return Err(DynamicsError::InvalidArgument(format!(
            "training samples: the recorded torque is {s:.3} times what the URDF's arm needs (gravity and \
             Coriolis): give it in N m, with the sign of the torque the joints apply, and a URDF \
             with the arm's masses"
        )));
    }
    let deviation = (s - 1.0).abs();
    Ok(
        (SCALE_RANGE.contains(&s) && deviation > MIN_DEVIATION && deviation > T_95 * error)
            .then_some(s),
    )
}

/// The scale of the normal equations' first column, the others as nuisance (`None` when the
/// system is singular or the scale not finite).
fn scale_of(gram: &DMatrix<f64>, rhs: &DVector<f64>) -> Option<f64> {
    let mut gram = gram.clone();
    for c in 1..gram.nrows() {
        // A negligible ridge, as the fit gives joint terms: constant features of a joint
        // that hardly moves must not make the system singular.
        gram[(c, c)] += 1e-9 * gram[(c, c)].max(1e-300);
    }
    let s = gram.cholesky()?.solve(rhs)[0];
    s.is_finite().then_some(s)
}

/// The delete-a-stretch jackknife's standard error of the scale,
/// `sqrt((g - 1) / g sum (s_-b - mean)^2)` over the `g` stretches with samples (infinite when
/// a scale without one of them cannot be read).
fn jackknife_error(
    gram: &DMatrix<f64>,
    rhs: &DVector<f64>,
    parts: &[(DMatrix<f64>, DVector<f64>, f64)],
) -> f64 {
    let mut scales = Vec::with_capacity(parts.len());
    for (g, r, t) in parts {
        if *t == 0.0 {
            continue;
        }
        match scale_of(&(gram - g), &(rhs - r)) {
            Some(s) => scales.push(s),
            None => return f64::INFINITY,
        }
    }
    let count = scales.len() as f64;
    if count < 2.0 {
        return f64::INFINITY;
    }
    let mean = scales.iter().sum::<f64>() / count;
    ((count - 1.0) / count * scales.iter().map(|s| (s - mean).powi(2)).sum::<f64>()).sqrt()
}

/// The share of the recorded torque's mean square that the scaled URDF torque must reach for
/// its scale to be read (a horizontal arm's gravity-free torque tells no scale). The simulated
/// arms' gravity and Coriolis torque reach 0.21 (SO-101, friction-heavy) to 1.00 (UR10).
const EXPLAINED: f64 = 0.1;

/// `prior` with its inertial parameters (the first `10 bodies`) times `scale`.
pub(super) fn scaled(prior: &DVector<f64>, scale: f64, bodies: usize) -> DVector<f64> {
    let mut out = prior.clone();
    out.rows_mut(0, PARAMETERS_PER_BODY * bodies)
        .iter_mut()
        .for_each(|p| *p *= scale);
    out
}
