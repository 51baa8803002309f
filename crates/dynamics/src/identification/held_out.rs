//! Where the identification's settings are scored: a separate recording, or blocked
//! cross-validation over contiguous stretches of the training motion (docs/method.md
//! section 1), and the held-out errors that choose the acceleration gain.

use nalgebra::DVector;

use crate::error::DynamicsError;
use crate::identification::constrained::{solve_physical, BodyExtent};
use crate::identification::normal::{shifted_torque, solve, Normal, NormalParts};
use crate::identification::samples::Samples;
use crate::identification::Identification;
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
            Held::Folds { blocks, total } => {
                let total = at(total);
                let errors = parallel_map(blocks, |b| {
                    let b = at(b);
                    let mut rest = total.clone();
                    rest.sub(&b);
                    fitter
                        .fit(&rest, active, prior, ridge)
                        .map_or(f64::INFINITY, |x| b.squared_error(&x))
                });
                if errors.len() != blocks.len() {
                    return f64::INFINITY;
                }
                errors.iter().sum::<f64>() / total.rows as f64
            }
        }
    }

    /// The normal equations of all the training motion.
    pub fn all_training(&self, signals: &Signals) -> Normal {
        match self {
            Held::Recording { train, .. } => train.at(signals),
            Held::Folds { total, .. } => total.at(signals),
        }
    }
}

/// The candidate with the lowest score (`(NaN, inf)` when none is finite).
pub(super) fn best_of<T>(candidates: impl Iterator<Item = (T, f64)>, none: T) -> (T, f64) {
    candidates.fold(
        (none, f64::INFINITY),
        |best, c| if c.1 < best.1 { c } else { best },
    )
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
            let errors = parallel_map(&folds, |&b| {
                let mut rest = total.clone();
                rest.sub(&blocks[b].at(signals));
                let id = refit(&rest)?;
                let (s, e) = (
                    b * train.len() / blocks.len(),
                    (b + 1) * train.len() / blocks.len(),
                );
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
