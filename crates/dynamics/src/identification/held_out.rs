//! Where the identification's settings are scored: a separate recording, or blocked
//! cross-validation over contiguous stretches of the training motion (docs/method.md
//! section 1), from one pass over the samples at every candidate Coulomb width with the
//! joints' weights, and the held-out errors that choose the acceleration gain.

use nalgebra::DVector;

use crate::algorithms::regressor::PARAMETERS_PER_BODY;
use crate::error::DynamicsError;
use crate::identification::constrained::{solve_physical, BodyExtent};
use crate::identification::joint_terms::{FIRST_SPRING_FEATURE, JOINT_FEATURES};
use crate::identification::normal::{
    accumulate, shifted_torque, solve, JointSums, Normal, NormalParts,
};
use crate::identification::samples::Samples;
use crate::identification::settings::IdentificationSettings;
use crate::identification::training_range::{spring_ranges, training_range};
use crate::identification::Identification;
use crate::model::Model;
use crate::parallel::parallel_map;

/// Where settings are scored: a separate recording, or held-out contiguous stretches; the
/// normal equations as functions of the torque shift.
pub(super) enum Held<'a> {
    Recording {
        train: NormalParts,
        validation: NormalParts,
        samples: Samples<'a>,
    },
    Folds {
        blocks: Vec<NormalParts>,
        total: NormalParts,
    },
}

/// Per joint, the index of its torque's shift.
pub(super) type Signals = Vec<usize>;

/// The least-squares solution on `normal` with these columns and ridge: physical joint
/// terms always, physically possible bodies when `physical`.
#[derive(Clone, Copy)]
pub(super) struct Fitter<'a> {
    pub physical: bool,
    /// Where each body's mass may be, with `physical` (empty: anywhere possible).
    pub extents: &'a [BodyExtent],
    /// Unconstrained ridge least squares (one factorisation): for choices that physics
    /// does not bear on.
    pub plain: bool,
    pub bodies: usize,
}

impl Fitter<'_> {
    pub fn fit(
        &self,
        normal: &Normal,
        active: &[bool],
        prior: &DVector<f64>,
        ridge: f64,
    ) -> Option<DVector<f64>> {
        if self.plain {
            solve(normal, active, prior, ridge)
        } else {
            solve_physical(
                normal,
                active,
                prior,
                ridge,
                self.bodies,
                self.physical,
                self.extents,
            )
        }
    }
}

impl Held<'_> {
    /// Mean squared error on held-out motion of the fit with these columns, ridge and signals.
    pub fn score(
        &self,
        fitter: Fitter<'_>,
        active: &[bool],
        prior: &DVector<f64>,
        ridge: f64,
        signals: &Signals,
    ) -> f64 {
        let at = |p: &NormalParts| p.at(signals);
        match self {
            Held::Recording {
                train, validation, ..
            } => {
                let validation = at(validation);
                match fitter.fit(&at(train), active, prior, ridge) {
                    Some(x) => validation.squared_error(&x) / validation.rows as f64,
                    None => f64::INFINITY,
                }
            }
            Held::Folds { .. } => self
                .fold_errors(fitter, active, prior, ridge, signals)
                .map_or(f64::INFINITY, |(_, mean)| mean),
        }
    }

    /// Per held-out stretch, the squared error of the fit on the other stretches, and the
    /// mean squared error over all of them (`None` for a validation recording, or when a
    /// stretch's fit fails).
    pub fn fold_errors(
        &self,
        fitter: Fitter<'_>,
        active: &[bool],
        prior: &DVector<f64>,
        ridge: f64,
        signals: &Signals,
    ) -> Option<(Vec<f64>, f64)> {
        let Held::Folds { blocks, total } = self else {
            return None;
        };
        let total = total.at(signals);
        let errors = parallel_map(blocks, |b| {
            let b = b.at(signals);
            let mut rest = total.clone();
            rest.sub(&b);
            fitter
                .fit(&rest, active, prior, ridge)
                .map_or(f64::INFINITY, |x| b.squared_error(&x))
        });
        let mean = errors.iter().sum::<f64>() / total.rows as f64;
        (errors.len() == blocks.len() && mean.is_finite()).then_some((errors, mean))
    }

    /// The normal equations of all the training motion.
    pub fn all_training(&self, signals: &Signals) -> Normal {
        match self {
            Held::Recording { train, .. } => train.at(signals),
            Held::Folds { total, .. } => total.at(signals),
        }
    }
}

/// The per-joint sums of the training motion and of where settings are scored (a validation
/// recording, else the training's contiguous stretches): the normal equations at any
/// candidate Coulomb width, with any joint weights.
pub(super) struct HeldSums<'a> {
    train: Vec<JointSums>,
    validation: Option<(JointSums, Samples<'a>)>,
    friction: bool,
}

impl<'a> HeldSums<'a> {
    /// Where settings are scored, at the `width`-th candidate Coulomb width, each joint
    /// weighted by one over its residual after a plain fit at that width (`joint_weights`).
    pub fn at_width(&self, width: usize, prior: &DVector<f64>) -> Result<Held<'a>, DynamicsError> {
        let total = JointSums::sum(&self.train);
        let weights = joint_weights(&total, width, self.friction, prior)?;
        Ok(self.weighted(width, &weights))
    }

    pub fn weighted(&self, width: usize, weights: &[f64]) -> Held<'a> {
        let weighted = |s: &JointSums| s.weighted(weights, width);
        match &self.validation {
            Some((v, samples)) => Held::Recording {
                train: weighted(&self.train[0]),
                validation: weighted(v),
                samples: *samples,
            },
            None => {
                let blocks: Vec<NormalParts> = self.train.iter().map(weighted).collect();
                let total = NormalParts::sum(&blocks);
                Held::Folds { blocks, total }
            }
        }
    }

    pub fn widths(&self) -> usize {
        self.train[0].widths()
    }
}

/// One pass over the samples (per joint and stretch, in parallel) for [`HeldSums`].
/// `validation`: the recording whose sums score settings and the same recording as the
/// predictions of `errors_by_gain` see it (its acceleration as measured).
pub(super) fn held_sums<'a>(
    model: &Model,
    train: &Samples,
    validation: Option<(&Samples, &Samples<'a>)>,
    settings: &IdentificationSettings,
    shifts: &[f64],
    widths: &[f64],
) -> Result<HeldSums<'a>, DynamicsError> {
    let stretches = |s: &Samples,
                     blocks: usize,
                     springs: &[Option<[f64; 2]>]|
     -> Result<Vec<JointSums>, DynamicsError> {
        let ranges: Vec<(usize, usize)> = (0..blocks)
            .map(|b| (b * s.len() / blocks, (b + 1) * s.len() / blocks))
            .collect();
        parallel_map(&ranges, |&r| {
            accumulate(model, s, widths, r, shifts, springs)
        })
        .into_iter()
        .collect()
    };
    let blocks = match validation {
        Some(_) => 1,
        None => settings.folds,
    };
    // A validation recording is scored as the fitted springs will be used: beyond the
    // training motion's range, where that is less than half a turn, they continue linearly.
    let validation = match validation {
        Some((fitted, scored)) => {
            let springs = spring_ranges(model, &training_range(train));
            Some((stretches(fitted, 1, &springs)?.remove(0), *scored))
        }
        None => None,
    };
    Ok(HeldSums {
        train: stretches(train, blocks, &[])?,
        validation,
        friction: settings.friction,
    })
}

/// Each joint's weight in the least squares: one over its residual rms after a plain
/// fit (weighted least squares: a joint with small torques counts as much as one with
/// large torques, relative to how well it can be explained).
fn joint_weights(
    sums: &JointSums,
    width: usize,
    friction: bool,
    prior: &DVector<f64>,
) -> Result<Vec<f64>, DynamicsError> {
    let n = sums.joints();
    let normal = sums.weighted(&vec![1.0; n], width).at(&vec![0; n]);
    let active: Vec<bool> = (0..prior.len())
        .map(|c| {
            c < PARAMETERS_PER_BODY * n
                || (friction
                    && (c - PARAMETERS_PER_BODY * n) % JOINT_FEATURES < FIRST_SPRING_FEATURE)
        })
        .collect();
    let x = solve(&normal, &active, prior, 1e-6).ok_or_else(|| DynamicsError::InvalidArgument("identification: the least-squares system is singular (does the recording move every joint?)".into()))?;
    let rms = sums.rms_errors(&x, width);
    let largest = rms.iter().copied().fold(0.0, f64::max);
    Ok(rms
        .iter()
        .map(|r| 1.0 / r.max(1e-3 * largest).max(1e-12))
        .collect())
}

/// The median over held-out stretches of the error with a candidate (a spring, a delay) over
/// the error without. Over stretches a candidate is judged by the middle one, not by the
/// sum: the sum can be decided by one stretch whose motion the others do not cover (the
/// spring fitted without it extrapolates there, better or worse by chance; on the real
/// Baxter recording that one stretch refused the shoulder's gravity-assist spring,
/// docs/experiments.md, "Stretches that leave the training range").
pub(super) fn median_ratio(before: &[f64], after: &[f64]) -> f64 {
    let mut ratios: Vec<f64> = before
        .iter()
        .zip(after)
        .map(|(b, a)| a / b.max(f64::MIN_POSITIVE))
        .collect();
    ratios.sort_by(f64::total_cmp);
    ratios
        .get(ratios.len() / 2)
        .copied()
        .unwrap_or(f64::INFINITY)
}

/// The candidate with the lowest score (`(NaN, inf)` when none is finite).
pub(super) fn best_of<T>(candidates: impl Iterator<Item = (T, f64)>, none: T) -> (T, f64) {
    candidates.fold(
        (none, f64::INFINITY),
        |best, c| if c.1 < best.1 { c } else { best },
    )
}

/// Per joint, the range spanned by every stretch's range but the `skip`-th.
fn range_of_others(ranges: &[Vec<[f64; 2]>], skip: usize) -> Vec<[f64; 2]> {
    let n = ranges.first().map_or(0, Vec::len);
    let mut out = vec![[f64::INFINITY, f64::NEG_INFINITY]; n];
    for (_, r) in ranges.iter().enumerate().filter(|&(b, _)| b != skip) {
        for (o, x) in out.iter_mut().zip(r) {
            *o = [o[0].min(x[0]), o[1].max(x[1])];
        }
    }
    out
}

/// The torques of `s` paired with the motion as the chosen shifts pair them.
pub(super) fn shifted_torques(s: &Samples, shifts: &[f64], signals: &Signals) -> Vec<f64> {
    let n = signals.len();
    (0..s.len())
        .flat_map(|k| (0..n).map(move |i| (k, i)))
        .map(|(k, i)| shifted_torque(s, k, i, shifts[signals[i]]))
        .collect()
}

/// Held-out squared errors per candidate gain and joint, of models that never saw them
/// (`identified` on a validation recording; per fold, `refit` of the other folds), with the
/// number of samples they were summed over and where they were held out.
pub(super) fn errors_by_gain(
    held: &Held<'_>,
    train: &Samples,
    identified: &Identification,
    refit: impl Fn(&Normal) -> Result<Identification, DynamicsError> + Sync,
    gains: &[f64],
    shifts: &[f64],
    signals: &Signals,
) -> Result<(Vec<Vec<f64>>, usize, String), DynamicsError> {
    let n = signals.len();
    let mut sq = vec![vec![0.0; n]; gains.len()];
    let mut count = 0;
    let mut add_errors = |errors: Vec<Vec<f64>>, samples: usize| {
        for (total, part) in sq.iter_mut().zip(errors) {
            total.iter_mut().zip(part).for_each(|(t, e)| *t += e);
        }
        count += samples;
    };
    let held_out = match held {
        Held::Recording { samples, .. } => {
            let tau = shifted_torques(samples, shifts, signals);
            let part = Samples {
                tau: &tau,
                ..*samples
            };
            add_errors(identified.squared_errors_by_gain(&part, gains)?, part.len());
            "validation recording".to_string()
        }
        Held::Folds { blocks, total } => {
            let tau = shifted_torques(train, shifts, signals);
            let train = Samples {
                tau: &tau,
                ..*train
            };
            let total = total.at(signals);
            let folds: Vec<usize> = (0..blocks.len()).collect();
            let stretch = |b: usize| {
                (
                    b * train.len() / blocks.len(),
                    (b + 1) * train.len() / blocks.len(),
                )
            };
            let ranges: Vec<Vec<[f64; 2]>> = folds
                .iter()
                .map(|&b| {
                    let (s, e) = stretch(b);
                    training_range(&train.slice(s, e))
                })
                .collect();
            let errors = parallel_map(&folds, |&b| {
                let mut rest = total.clone();
                rest.sub(&blocks[b].at(signals));
                let mut id = refit(&rest)?;
                // The fold's springs continue beyond the range of the stretches it was
                // fitted on, as the final fit's do beyond the recording's.
                id.continue_springs_beyond(&range_of_others(&ranges, b));
                let (s, e) = stretch(b);
                id.squared_errors_by_gain(&train.slice(s, e), gains)
                    .map(|errors| (errors, e - s))
            });
            for result in errors {
                let (errors, samples) = result?;
                add_errors(errors, samples);
            }
            format!(
                "blocked cross-validation, {} contiguous stretches",
                blocks.len()
            )
        }
    };
    Ok((sq, count, held_out))
}
