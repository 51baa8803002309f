//! Least-squares identification of an arm from free motion (docs/method.md section 1):
//! `tau = Y(q, q', q'') pi + tau_joint`, regularised toward the URDF, every choice made on
//! motion the fit did not see.

use nalgebra::DVector;

use crate::algorithms::regressor::{inertial_parameters, PARAMETERS_PER_BODY};
use crate::error::DynamicsError;
use crate::identification::base::BaseParameters;
use crate::identification::constrained::solve_consistent;
use crate::identification::joint_terms::{FIRST_SPRING_FEATURE, JOINT_FEATURES};
use crate::identification::normal::{accumulate, columns, solve, Normal};
use crate::identification::samples::Samples;
use crate::identification::settings::IdentificationSettings;
use crate::identification::{Identification, IdentificationSummary};
use crate::model::Model;

/// Ridge weights tried when none is given: 1e-8 to 1e2, half a decade apart.
fn ridge_grid() -> impl Iterator<Item = f64> {
    (0..=20).map(|k| 10f64.powf(-8.0 + 0.5 * k as f64))
}

/// Where settings are scored: a separate recording, or held-out contiguous stretches.
enum Held<'a> {
    Recording {
        train: Normal,
        validation: Normal,
        samples: Samples<'a>,
    },
    Folds {
        blocks: Vec<Normal>,
        total: Normal,
    },
}

/// The least-squares solution on `normal` with these columns and ridge: over physically
/// possible bodies only, or unconstrained.
#[derive(Clone, Copy)]
struct Fitter {
    physical: bool,
    bodies: usize,
}

impl Fitter {
    fn fit(
        &self,
        normal: &Normal,
        active: &[bool],
        prior: &DVector<f64>,
        ridge: f64,
    ) -> Option<DVector<f64>> {
        if self.physical {
            solve_consistent(normal, active, prior, ridge, self.bodies)
        } else {
            solve(normal, active, prior, ridge)
        }
    }
}

impl Held<'_> {
    /// Mean squared error on held-out motion of the fit with these columns and ridge.
    fn score(&self, fitter: Fitter, active: &[bool], prior: &DVector<f64>, ridge: f64) -> f64 {
        match self {
            Held::Recording {
                train, validation, ..
            } => match fitter.fit(train, active, prior, ridge) {
                Some(x) => validation.squared_error(&x) / validation.rows as f64,
                None => f64::INFINITY,
            },
            Held::Folds { blocks, total } => {
                let mut sse = 0.0;
                for b in blocks {
                    let mut rest = total.clone();
                    rest.sub(b);
                    match fitter.fit(&rest, active, prior, ridge) {
                        Some(x) => sse += b.squared_error(&x),
                        None => return f64::INFINITY,
                    }
                }
                sse / total.rows as f64
            }
        }
    }

    fn all_training(&self) -> &Normal {
        match self {
            Held::Recording { train, .. } => train,
            Held::Folds { total, .. } => total,
        }
    }
}

/// Identifies `model`'s inertial parameters and joint terms from free-motion `train`
/// samples (see [`IdentificationSettings`]); `validation`, when given, is another
/// recording on which every setting is chosen and the expected error measured, else
/// blocked cross-validation over contiguous stretches of `train` does both.
pub fn identify(
    model: &Model,
    train: &Samples,
    validation: Option<&Samples>,
    settings: &IdentificationSettings,
) -> Result<Identification, DynamicsError> {
    settings.validate()?;
    let n = model.nq();
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
    let width = settings.coulomb_width;
    let p = columns(n);
    let mut prior = DVector::zeros(p);
    prior
        .rows_mut(0, PARAMETERS_PER_BODY * n)
        .copy_from_slice(&inertial_parameters(model));
    let weights = joint_weights(model, train, width, settings.friction, &prior)?;
    let held = match validation {
        Some(v) => Held::Recording {
            train: accumulate(model, train, width, 1, &weights)?.remove(0),
            validation: accumulate(model, v, width, 1, &weights)?.remove(0),
            samples: *v,
        },
        None => {
            let blocks = accumulate(model, train, width, settings.folds, &weights)?;
            let mut total = Normal::zeros(columns(n));
            blocks.iter().for_each(|b| total.add(b));
            Held::Folds { blocks, total }
        }
    };
    let joint_col = |i: usize, f: usize| PARAMETERS_PER_BODY * n + JOINT_FEATURES * i + f;
    let mut active: Vec<bool> = (0..p)
        .map(|c| c < PARAMETERS_PER_BODY * n || settings.friction)
        .collect();
    for i in 0..n {
        for f in FIRST_SPRING_FEATURE..JOINT_FEATURES {
            active[joint_col(i, f)] = false;
        }
    }
    let fitter = Fitter {
        physical: settings.physical_consistency,
        bodies: n,
    };
    let choose_ridge = |active: &[bool]| -> (f64, f64) {
        match settings.ridge {
            Some(r) => (r, held.score(fitter, active, &prior, r)),
            None => ridge_grid()
                .map(|r| (r, held.score(fitter, active, &prior, r)))
                .fold((f64::NAN, f64::INFINITY), |best, c| {
                    if c.1 < best.1 {
                        c
                    } else {
                        best
                    }
                }),
        }
    };
    let (mut ridge, mut best) = choose_ridge(&active);
    let mut springs = vec![false; n];
    if settings.springs {
        for i in 0..n {
            let mut trial = active.clone();
            (FIRST_SPRING_FEATURE..JOINT_FEATURES).for_each(|f| trial[joint_col(i, f)] = true);
            let score = held.score(fitter, &trial, &prior, ridge);
            if score < 0.99 * best {
                active = trial;
                best = score;
                springs[i] = true;
            }
        }
        if springs.iter().any(|&s| s) {
            (ridge, best) = choose_ridge(&active);
        }
    }
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
    let (x, projected) = fit(held.all_training())?;
    let identified = Identification::from_solution(model, &x, width)?;
    let (per_joint, held_out) = match &held {
        Held::Recording { samples, .. } => (
            identified.joint_errors(samples)?.rms,
            "validation recording".to_string(),
        ),
        Held::Folds { blocks, total } => {
            // The reported error of each stretch comes from a fit that never saw it.
            let mut sq = vec![0.0; n];
            let mut count = 0;
            for (b, normal) in blocks.iter().enumerate() {
                let mut rest = total.clone();
                rest.sub(normal);
                let (xb, _) = fit(&rest)?;
                let id = Identification::from_solution(model, &xb, width)?;
                let (s, e) = (
                    b * train.len() / blocks.len(),
                    (b + 1) * train.len() / blocks.len(),
                );
                let part = train.slice(s, e);
                let errs = id.joint_errors(&part)?;
                for (s, e) in sq.iter_mut().zip(&errs.rms) {
                    *s += e.powi(2) * part.len() as f64;
                }
                count += part.len();
            }
            let rms: Vec<f64> = sq.iter().map(|s| (s / count as f64).sqrt()).collect();
            (
                rms,
                format!(
                    "blocked cross-validation, {} contiguous stretches",
                    blocks.len()
                ),
            )
        }
    };
    // The URDF's own error on the same held-out motion (it was fitted to nothing).
    let prior_model = Identification::from_solution(model, &prior, width)?;
    let prior_rms = match &held {
        Held::Recording { samples, .. } => prior_model.joint_errors(samples)?.rms,
        Held::Folds { .. } => prior_model.joint_errors(train)?.rms,
    };
    let base = BaseParameters::new(model, 100, 1)?;
    let summary = IdentificationSummary {
        held_out,
        ridge,
        springs,
        projected_bodies: projected,
        expected_false_torque_rms: per_joint,
        prior_false_torque_rms: prior_rms,
        base_parameters: base.rank(),
        condition_number: base_condition(&base, held.all_training()),
        training_samples: train.len(),
        validation_samples: validation.map_or(0, |v| v.len()),
        settings: settings.clone(),
    };
    Ok(Identification {
        summary,
        ..identified
    })
}

/// Each joint's weight in the least squares: one over its residual rms after a plain
/// fit (weighted least squares: a joint with small torques counts as much as one with
/// large torques, relative to how well it can be explained).
fn joint_weights(
    model: &Model,
    train: &Samples,
    width: f64,
    friction: bool,
    prior: &DVector<f64>,
) -> Result<Vec<f64>, DynamicsError> {
    let n = model.nq();
    let ones = vec![1.0; n];
    let normal = accumulate(model, train, width, 1, &ones)?.remove(0);
    let active: Vec<bool> = (0..prior.len())
        .map(|c| {
            c < PARAMETERS_PER_BODY * n
                || (friction
                    && (c - PARAMETERS_PER_BODY * n) % JOINT_FEATURES < FIRST_SPRING_FEATURE)
        })
        .collect();
    let x = solve(&normal, &active, prior, 1e-6).ok_or_else(|| DynamicsError::InvalidArgument("identification: the least-squares system is singular (does the recording move every joint?)".into()))?;
    let rms = Identification::from_solution(model, &x, width)?
        .joint_errors(train)?
        .rms;
    let largest = rms.iter().copied().fold(0.0, f64::max);
    Ok(rms
        .iter()
        .map(|r| 1.0 / r.max(1e-3 * largest).max(1e-12))
        .collect())
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
