//! Identification of a recording as every front end runs it (issue 30): the raw columns
//! through the observers' input conditioning (`InputConditioner`, docs/method.md section 7),
//! the cut-off chosen on held-out motion when the caller gives none, the delay of the torque
//! behind the motion and the acceleration gain chosen by [`admittance_dynamics::identify`],
//! and the choices written into the identification's summary, so that every consumer
//! conditions its inputs the same way. Without a validation recording, a recording whose
//! motion repeats (a periodic excitation) is fitted without spring terms and delay: its
//! held-out stretches are motion the fit has seen, and cannot judge them.

use admittance_dynamics::{identify, Identification, IdentificationSettings, Model, Samples};

use crate::even_sampling::{evenly_sampled, rows_until};
use crate::free_motion::{observer_training_arrays, FreeMotionData};

/// Cut-offs tried when the caller gives none (Hz; 0: the signals as recorded). None is
/// slower than 4 Hz: a slower filter hides contact for longer than it saves false torque.
pub const CUTOFF_CANDIDATES_HZ: [f64; 4] = [4.0, 6.0, 10.0, 0.0];

/// How far above the input conditioning's cut-off the fit's acceleration low-pass stays at
/// least (`IdentificationSettings::fit_acceleration_hz` is raised to it).
const FIT_ACCELERATION_ABOVE_CONDITIONING: f64 = 2.0;

/// A recording's samples through the input conditioning at one cut-off.
pub struct ConditionedSamples {
    /// Conditioned angles, row-major (n per sample).
    pub q: Vec<f64>,
    /// Their derivative.
    pub qdot: Vec<f64>,
    /// Their second derivative.
    pub qddot: Vec<f64>,
    /// Conditioned torques.
    pub tau: Vec<f64>,
    /// Joints.
    pub dof: usize,
}

impl ConditionedSamples {
    /// `data` through the conditioning at `input_filter_hz` (0: as recorded).
    pub fn new(data: &FreeMotionData, input_filter_hz: f64) -> Result<Self, String> {
        let n = data.dof();
        let (x, tau) =
            observer_training_arrays(data, input_filter_hz).map_err(|e| e.to_string())?;
        let mut out = ConditionedSamples {
            q: Vec::with_capacity(tau.len()),
            qdot: Vec::with_capacity(tau.len()),
            qddot: Vec::with_capacity(tau.len()),
            tau,
            dof: n,
        };
        for row in x.chunks_exact(3 * n) {
            out.q.extend_from_slice(&row[..n]);
            out.qdot.extend_from_slice(&row[n..2 * n]);
            out.qddot.extend_from_slice(&row[2 * n..]);
        }
        Ok(out)
    }

    /// As identification samples.
    pub fn samples(&self) -> Samples<'_> {
        Samples {
            q: &self.q,
            qdot: &self.qdot,
            qddot: &self.qddot,
            tau: &self.tau,
            dof: self.dof,
        }
    }

    /// Pairs each motion sample with each joint's torque `delay_s[i]` later (linear
    /// interpolation, held at the ends), as an identification with those delays expects
    /// (`IdentificationSummary::delay_s`; empty: none); `rate_hz` the samples'.
    pub fn delay_torque(&mut self, delay_s: &[f64], rate_hz: f64) {
        if delay_s.iter().all(|d| *d == 0.0) || !(rate_hz > 0.0) {
            return;
        }
        let n = self.dof;
        let len = self.tau.len() / n.max(1);
        if len == 0 {
            return;
        }
        let old = self.tau.clone();
        for (i, delay) in delay_s.iter().enumerate().take(n) {
            let shift = delay * rate_hz;
            if shift == 0.0 || !shift.is_finite() {
                continue;
            }
            for k in 0..len {
                let at = (k as f64 + shift).clamp(0.0, (len - 1) as f64);
                let k0 = at.floor() as usize;
                let k1 = (k0 + 1).min(len - 1);
                let w = at - k0 as f64;
                self.tau[k * n + i] = old[k0 * n + i] * (1.0 - w) + old[k1 * n + i] * w;
            }
        }
    }
}

/// The lag (rows) after which the first `rows` rows of `data` repeat their motion, looked
/// for up to the length of all but one of `folds` stretches; `None` when they do not.
fn repeat_period(data: &FreeMotionData, rows: usize, folds: usize) -> Option<usize> {
    let n = data.dof();
    admittance_learning::broad::repeat_period(&data.q[..rows * n], n, rows - rows / folds.max(2))
}

/// How many rows of `validation` equal one of the first `rows` rows of `train` in every
/// position and torque, bit for bit.
fn shared_rows(train: &FreeMotionData, rows: usize, validation: &FreeMotionData) -> usize {
    let n = train.dof();
    if n == 0 || validation.dof() != n {
        return 0;
    }
    let key = |data: &FreeMotionData, k: usize| -> Vec<u64> {
        let r = k * n..(k + 1) * n;
        data.q[r.clone()]
            .iter()
            .chain(&data.tau[r])
            .map(|v| v.to_bits())
            .collect()
    };
    let seen: std::collections::HashSet<Vec<u64>> = (0..rows).map(|k| key(train, k)).collect();
    (0..validation.len())
        .filter(|&k| seen.contains(&key(validation, k)))
        .count()
}

/// The sample rate of `data` (Hz) from its time column.
pub fn sample_rate_hz(data: &FreeMotionData) -> f64 {
    let span = data.t.last().copied().unwrap_or(0.0) - data.t.first().copied().unwrap_or(0.0);
    if data.len() > 1 && span > 0.0 {
        (data.len() - 1) as f64 / span
    } else {
        0.0
    }
}

/// 90 % step-response time (s) of the conditioning at `cutoff_hz` sampled at `rate_hz` (0
/// when it passes the signal through).
pub fn conditioning_step_response_s(cutoff_hz: f64, rate_hz: f64) -> f64 {
    if cutoff_hz <= 0.0 || rate_hz <= 0.0 || cutoff_hz >= 0.5 * rate_hz {
        return 0.0;
    }
    let Ok(mut filter) = admittance_loop::LowPass::butterworth2(cutoff_hz, rate_hz, 1) else {
        return 0.0;
    };
    // From rest at 0, a unit step: the filter starts in steady state at its first sample.
    filter.update(0, 0.0);
    for k in 1..(100.0 * rate_hz) as usize {
        if filter.update(0, 1.0) >= 0.9 {
            return k as f64 / rate_hz;
        }
    }
    f64::INFINITY
}

/// One cut-off tried: its cut-off and the expected false torque (N m rms over joints).
#[derive(Clone, Debug)]
pub struct CutoffTrial {
    /// Cut-off (Hz; 0: as recorded).
    pub input_filter_hz: f64,
    /// Expected false torque on held-out motion, rms over joints and samples (N m).
    pub expected_false_torque_rms: f64,
}

/// The ridge tolerance (`IdentificationSettings::ridge_tolerance`) when the training motion
/// repeats and no validation recording is given.
pub const REPEAT_RIDGE_TOLERANCE: f64 = 0.05;

/// Identifies `arm` from the first `rows` rows of `train` (all of `validation`, when
/// given, chooses and scores), conditioned at `input_filter_hz`, or, when `None`, at the
/// cut-off of [`CUTOFF_CANDIDATES_HZ`] with the lowest expected false torque. Returns the
/// identification (its summary holding the cut-off, delay and step-response time) and
/// every cut-off tried.
pub fn identify_recording(
    arm: &Model,
    train: &FreeMotionData,
    rows: usize,
    validation: Option<&FreeMotionData>,
    settings: &IdentificationSettings,
    input_filter_hz: Option<f64>,
) -> Result<(Identification, Vec<CutoffTrial>), String> {
    if let Some(v) = validation {
        let shared = shared_rows(train, rows.min(train.len()), v);
        // A few equal rows can be two recordings starting at rest at the same pose; a
        // hundredth of the validation is the training's motion itself.
        if shared > 10 && shared * 100 >= v.len() {
            return Err(format!(
                "the validation recording repeats {shared} of its {} rows from the training rows \
                 (the same file, or overlapping stretches of it): settings chosen there would be \
                 chosen on motion the fit has seen; give a recording of other motion, or none \
                 (blocked cross-validation over the training rows)",
                v.len()
            ));
        }
    }
    // Dropped samples put back on an even grid: the conditioning is a fixed-rate filter.
    let even_train = evenly_sampled(train);
    let rows = match &even_train {
        Some((even, found)) if rows > 0 => {
            let last = train.t[rows.min(train.len()) - 1];
            rows_until(even.t[0], found.step_s, last).min(even.len())
        }
        _ => rows,
    };
    let train = even_train.as_ref().map_or(train, |(even, _)| even);
    let even_validation = validation.and_then(evenly_sampled);
    let validation = match &even_validation {
        Some((even, _)) => Some(even),
        None => validation,
    };
    let rate = sample_rate_hz(train);
    let candidates: Vec<f64> = match input_filter_hz {
        Some(f) => vec![f],
        None => CUTOFF_CANDIDATES_HZ
            .iter()
            .copied()
            .filter(|&f| f < 0.5 * rate)
            .collect(),
    };
    let mut settings = IdentificationSettings {
        sample_rate_hz: (rate > 0.0).then_some(rate),
        ..settings.clone()
    };
    // Held-out stretches of a motion that repeats are motion the fit has seen: they cannot
    // judge terms that fit one motion's particulars. On the simulated arms, springs and a
    // delay chosen on such stretches raised the error on new motion by up to 2.6 times.
    let repeats = match validation {
        Some(_) => None,
        None => repeat_period(train, rows.min(train.len()), settings.folds),
    };
    if repeats.is_some() {
        settings.springs = false;
        settings.delay = false;
        // Nor can they tell ridges apart: on the ten simulated arms the held-out error of the
        // weakest and the strongest ridge differed by 4 % or less, while on new motion the
        // strongest was better on 19 of 20 (arm, motion) pairs and 2.7 % worse on one (the
        // UR10's false torque: 0.286 against 0.310 N m; docs/experiments.md).
        if settings.ridge.is_none() && settings.ridge_tolerance == 0.0 {
            settings.ridge_tolerance = REPEAT_RIDGE_TOLERANCE;
        }
    }
    // The candidates are independent fits: on as many threads as there are cores, then
    // judged in their order (the same choice and values as one after the other).
    let fit_at = |cutoff: f64| -> Result<Result<Identification, String>, String> {
        let conditioned = ConditionedSamples::new(train, cutoff)
            .map_err(|e| format!("input filter {cutoff} Hz: {e}"))?;
        let samples = conditioned.samples().slice(0, rows.min(train.len()));
        let held = match validation {
            Some(v) => Some(
                ConditionedSamples::new(v, cutoff)
                    .map_err(|e| format!("input filter {cutoff} Hz, validation: {e}"))?,
            ),
            None => None,
        };
        // The fit's acceleration low-pass stays above the band the conditioning keeps: the
        // conditioned torque carries inertial torque up to its cut-off.
        let settings = IdentificationSettings {
            fit_acceleration_hz: settings
                .fit_acceleration_hz
                .map(|hz| hz.max(FIT_ACCELERATION_ABOVE_CONDITIONING * cutoff)),
            ..settings.clone()
        };
        Ok(identify(
            arm,
            &samples,
            held.as_ref().map(|h| h.samples()).as_ref(),
            &settings,
        )
        .map_err(|e| e.to_string()))
    };
    let fits = admittance_dynamics::parallel_map(&candidates, |&cutoff| fit_at(cutoff));
    let mut best: Option<(f64, Identification)> = None;
    let mut tried = Vec::new();
    let mut last_error = String::new();
    for (cutoff, fitted) in candidates.into_iter().zip(fits) {
        let fitted = fitted?;
        let mut ident = match fitted {
            Ok(i) => i,
            Err(e) if input_filter_hz.is_none() => {
                last_error = e;
                continue;
            }
            Err(e) => return Err(e),
        };
        let e = &ident.summary.expected_false_torque_rms;
        let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len().max(1) as f64).sqrt();
        tried.push(CutoffTrial {
            input_filter_hz: cutoff,
            expected_false_torque_rms: rms,
        });
        ident.summary.input_filter_hz = cutoff;
        if let Some(period) = repeats {
            ident.summary.held_out = format!(
                "{} (the motion repeats every {period} samples: no spring terms and no delay \
                 offered, and the strongest ridge within {:.0} % of the best held-out error \
                 taken; give a recording of other motion as validation to have them judged)",
                ident.summary.held_out,
                100.0 * settings.ridge_tolerance
            );
        }
        for (which, found) in [("training", &even_train), ("validation", &even_validation)] {
            if let Some((_, found)) = found {
                ident.summary.held_out += &format!("; {which} recording: {}", found.describe());
            }
        }
        ident.summary.step_response_s = conditioning_step_response_s(cutoff, rate)
            + ident.summary.delay_s.iter().copied().fold(0.0, f64::max);
        if best.as_ref().is_none_or(|(b, _)| rms < *b) {
            best = Some((rms, ident));
        }
    }
    match best {
        Some((_, ident)) => Ok((ident, tried)),
        None => Err(last_error),
    }
}
