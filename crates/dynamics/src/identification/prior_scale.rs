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
    // Per stretch, side by side: the normal equations and the torque's squares. Sample `k`
    // is in stretch `k STRETCHES / len`.
    let ranges: Vec<(usize, usize)> = (0..STRETCHES)
        .map(|b| {
            (
                (b * len).div_ceil(STRETCHES),
                ((b + 1) * len).div_ceil(STRETCHES),
            )
        })
        .collect();
    let parts: Vec<(DMatrix<f64>, DVector<f64>, f64)> =
        crate::parallel::parallel_map(&ranges, |&(start, end)| {
            stretch_sums(samples, urdf, width, n, start, end)
        });
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

/// Row `[h_i, (M q'')_i, features of joint i]` of every joint and sample of `start..end`:
/// the normal equations over the columns `[h, M q'', JOINT_FEATURES per joint]` and the
/// torque's squares. Each joint's rows touch the two shared columns and its own features
/// only, so those blocks are summed per joint (each element over the same rows in the same
/// order as a dense accumulation, and its lower triangle mirrored: the same values).
fn stretch_sums(
    samples: &Samples,
    urdf: &UrdfTorques,
    width: f64,
    n: usize,
    start: usize,
    end: usize,
) -> (DMatrix<f64>, DVector<f64>, f64) {
    const ROW: usize = 2 + JOINT_FEATURES;
    let mut shared = [[0.0; 2]; 2];
    let mut shared_rhs = [0.0; 2];
    let mut blocks = vec![[[0.0; ROW]; ROW]; n];
    let mut block_rhs = vec![[0.0; ROW]; n];
    let mut tau_sq = 0.0;
    let mut row = [0.0; ROW];
    let mut f = [0.0; JOINT_FEATURES];
    for k in start..end {
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
            let tau = samples.tau[k * n + i];
            tau_sq += tau * tau;
            for a in 0..2 {
                shared_rhs[a] += row[a] * tau;
                for b in 0..=a {
                    shared[a][b] += row[a] * row[b];
                }
            }
            let (block, rhs) = (&mut blocks[i], &mut block_rhs[i]);
            for a in 2..ROW {
                rhs[a] += row[a] * tau;
                for b in 0..=a {
                    block[a][b] += row[a] * row[b];
                }
            }
        }
    }
    let m = 2 + JOINT_FEATURES * n;
    let mut gram = DMatrix::<f64>::zeros(m, m);
    let mut rhs = DVector::<f64>::zeros(m);
    for a in 0..2 {
        rhs[a] = shared_rhs[a];
        for b in 0..=a {
            gram[(a, b)] = shared[a][b];
        }
    }
    for (i, (block, block_rhs)) in blocks.iter().zip(&block_rhs).enumerate() {
        let col = |c: usize| {
            if c < 2 {
                c
            } else {
                2 + JOINT_FEATURES * i + c - 2
            }
        };
        for a in 2..ROW {
            rhs[col(a)] = block_rhs[a];
            for b in 0..=a {
                gram[(col(a), col(b))] = block[a][b];
            }
        }
    }
    gram.fill_upper_triangle_with_lower_triangle();
    (gram, rhs, tau_sq)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The per-joint blocks equal a dense accumulation of every row over every column, bit for
    /// bit, and the stretches split the samples at `k STRETCHES / len`.
    #[test]
    fn stretch_sums_equal_the_dense_sums_bit_for_bit() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = Model::from_urdf_file(&root.join("../../models/franka_panda.urdf"), None, None)
            .expect("model");
        let n = model.nq();
        let count = 53; // not a multiple of STRETCHES
        let wave = |k: usize, f: f64| ((k as f64) * f).sin() * (1 + k % 4) as f64;
        let q: Vec<f64> = (0..count * n).map(|k| wave(k, 0.37)).collect();
        let qd: Vec<f64> = (0..count * n).map(|k| 0.1 * wave(k, 1.13)).collect();
        let qdd: Vec<f64> = (0..count * n).map(|k| 3.0 * wave(k, 0.71)).collect();
        let tau: Vec<f64> = (0..count * n).map(|k| 5.0 * wave(k, 0.29)).collect();
        let samples = Samples {
            q: &q,
            qdot: &qd,
            qddot: &qdd,
            tau: &tau,
            dof: n,
        };
        let urdf = UrdfTorques::new(&model, &samples, true);
        let width = 0.005;
        let m = 2 + JOINT_FEATURES * n;
        let mut dense =
            vec![(DMatrix::<f64>::zeros(m, m), DVector::<f64>::zeros(m), 0.0); STRETCHES];
        let mut f = [0.0; JOINT_FEATURES];
        for k in 0..count {
            let (gram, rhs, tau_sq) = &mut dense[(k * STRETCHES / count).min(STRETCHES - 1)];
            for i in 0..n {
                let at = k * n + i;
                features(q[at], qd[at], qdd[at], width, None, &mut f);
                let mut row = vec![(0, urdf.bias[at]), (1, urdf.total[at] - urdf.bias[at])];
                row.extend(
                    f.iter()
                        .enumerate()
                        .map(|(c, &v)| (2 + JOINT_FEATURES * i + c, v)),
                );
                *tau_sq += tau[at] * tau[at];
                for &(a, x) in &row {
                    rhs[a] += x * tau[at];
                    for &(b, y) in &row {
                        gram[(a, b)] += x * y;
                    }
                }
            }
        }
        let ranges: Vec<(usize, usize)> = (0..STRETCHES)
            .map(|b| {
                (
                    (b * count).div_ceil(STRETCHES),
                    ((b + 1) * count).div_ceil(STRETCHES),
                )
            })
            .collect();
        for (&(start, end), (gram, rhs, tau_sq)) in ranges.iter().zip(&dense) {
            let (g, r, t) = stretch_sums(&samples, &urdf, width, n, start, end);
            assert_eq!(t.to_bits(), tau_sq.to_bits());
            assert!(g
                .iter()
                .zip(gram.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits()));
            assert!(r
                .iter()
                .zip(rhs.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits()));
            assert!(*tau_sq > 0.0);
        }
    }
}
