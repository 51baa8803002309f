//! Excitation trajectories for identification (Swevers et al. 1997; Gaz et al. 2019): per
//! joint a finite Fourier series
//!
//! `q_i(t) = q0_i + sum_{l=1..L} a_il / (w l) sin(w l t) - b_il / (w l) cos(w l t)`,
//!
//! with base frequency `w = 2 pi / period`, the period the duration or a divisor of it, so
//! the motion repeats exactly. The first harmonic's coefficients are fixed by the others
//! (`a_i1 = -sum a_il`, `b_i1 = -sum l b_il`), which makes velocity and acceleration zero at
//! `t = 0` and at every multiple of the period: the motion starts and ends at rest with no
//! blending. Each joint's oscillation is then scaled down until its position stays inside
//! the envelope the user states (a range around a pose, by default +-0.5 rad around the
//! middle of the limits, inside the limits less a margin), its speed under a fraction
//! (default 30 %) of the URDF's velocity limit (1.5 rad/s where the URDF gives none) and
//! its acceleration under a fraction (default 30 %) of a set limit, all checked on the
//! output's sampling grid; the offset `q0` centres it in the envelope.
//!
//! The free coefficients are chosen for the condition number of the base inertial
//! regressor (the identifiable combinations of the 10 parameters per body, columns at
//! unit norm, as [`crate::BaseParameters::condition_number`]): random starts, then a
//! coordinate search with a shrinking step, deterministic for a seed. The joint terms
//! (friction, rotor inertia, offset, springs) are not part of the criterion.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

pub use super::excitation_settings::{
    ExcitationSettings, DEFAULT_EXCITATION_RANGE, DEFAULT_LIMIT_FRACTION, DEFAULT_VELOCITY_LIMIT,
};

use super::base::{BaseParameters, SplitMix};
use crate::algorithms::regressor::joint_torque_regressor;
use crate::data::Data;
use crate::error::DynamicsError;
use crate::model::Model;

/// Random coefficient sets tried before the local search.
const RESTARTS: usize = 16;
/// Samples per period on which the search evaluates the condition number.
const SEARCH_SAMPLES_PER_HARMONIC: usize = 20;

/// One joint's finite Fourier series (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FourierSeries {
    /// The offset `q0` (rad or m).
    pub offset: f64,
    /// `a_l`, harmonic `l = 1..L` (rad/s): the velocity's cosine amplitudes.
    pub a: Vec<f64>,
    /// `b_l` (rad/s): the velocity's sine amplitudes.
    pub b: Vec<f64>,
}

impl FourierSeries {
    /// Position, velocity and acceleration at time `t` for base frequency `w` (rad/s).
    pub fn evaluate(&self, w: f64, t: f64) -> [f64; 3] {
        let mut out = [self.offset, 0.0, 0.0];
        for (l, (a, b)) in self.a.iter().zip(&self.b).enumerate() {
            let wl = w * (l + 1) as f64;
            let (s, c) = (wl * t).sin_cos();
            out[0] += (a * s - b * c) / wl;
            out[1] += a * c + b * s;
            out[2] += wl * (b * c - a * s);
        }
        out
    }
}

/// An excitation trajectory: samples row-major (`N x n`), the series that made them, and
/// how well they excite the base parameters.
#[derive(Clone, Debug)]
pub struct Excitation {
    /// Sample times (s), from 0 to the duration.
    pub t: Vec<f64>,
    /// Joint positions (rad or m), `N x n`.
    pub q: Vec<f64>,
    /// Joint velocities.
    pub qdot: Vec<f64>,
    /// Joint accelerations.
    pub qddot: Vec<f64>,
    /// Joints per sample.
    pub dof: usize,
    /// Base frequency `w = 2 pi / period` (rad/s).
    pub base_frequency: f64,
    /// Each joint's series, scaled to the limits.
    pub series: Vec<FourierSeries>,
    /// Condition number of the base inertial regressor over all samples (columns at unit
    /// norm).
    pub condition_number: f64,
    /// The same for the first random start, scaled to the limits but not optimised.
    pub initial_condition_number: f64,
    /// Number of base parameters.
    pub base_parameters: usize,
}

/// How much of its envelope an excitation uses on a joint (1 = at the envelope's edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitUse {
    /// `max |q - centre| / half-width` of the envelope's position interval (the range
    /// around the pose inside the limits less the margin); NaN for a joint with neither.
    pub position: f64,
    /// `max |qdot| / (velocity_fraction * velocity limit)` (the URDF's limit, or
    /// [`DEFAULT_VELOCITY_LIMIT`]).
    pub velocity: f64,
    /// `max |qddot| / (acceleration_fraction * acceleration_limit)`.
    pub acceleration: f64,
}

impl Excitation {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Per joint, how much of each limit the samples use.
    pub fn limit_use(&self, model: &Model, settings: &ExcitationSettings) -> Vec<LimitUse> {
        let bounds = Bounds::of(model, settings);
        let n = self.dof;
        (0..n)
            .map(|i| {
                let col = |v: &[f64]| v.iter().skip(i).step_by(n).copied().collect::<Vec<_>>();
                let peak = |v: Vec<f64>, c: f64| v.iter().fold(0.0f64, |m, x| m.max((x - c).abs()));
                let b = &bounds[i];
                LimitUse {
                    position: if b.allowed.is_finite() {
                        peak(col(&self.q), b.middle) / b.allowed
                    } else {
                        f64::NAN
                    },
                    velocity: peak(col(&self.qdot), 0.0) / b.velocity,
                    acceleration: peak(col(&self.qddot), 0.0) / b.acceleration,
                }
            })
            .collect()
    }
}

/// A joint's envelope as the excitation uses it.
pub(super) struct Bounds {
    /// Centre of the position interval.
    middle: f64,
    /// Half-width of the position interval (infinite without limits or range).
    allowed: f64,
    /// The position interval: the range around the pose inside the limits less the margin.
    pub(super) lowest: f64,
    pub(super) highest: f64,
    velocity: f64,
    acceleration: f64,
}

impl Bounds {
    pub(super) fn of(model: &Model, settings: &ExcitationSettings) -> Vec<Bounds> {
        model
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let l = &j.limits;
                let limited = l.lower.is_finite() && l.upper.is_finite();
                let (lower, upper) = if limited {
                    let m = settings.position_margin * (l.upper - l.lower);
                    (l.lower + m, l.upper - m)
                } else {
                    (f64::NEG_INFINITY, f64::INFINITY)
                };
                let pose = settings.pose.get(i).copied().unwrap_or(if limited {
                    0.5 * (l.upper + l.lower)
                } else {
                    0.0
                });
                let range = match settings.range.as_slice() {
                    [one] => *one,
                    many => many.get(i).copied().unwrap_or(f64::INFINITY),
                };
                let lowest = (pose - range).max(lower);
                let highest = (pose + range).min(upper).max(lowest);
                let (middle, allowed) = if lowest.is_finite() && highest.is_finite() {
                    (0.5 * (lowest + highest), 0.5 * (highest - lowest))
                } else {
                    (pose, f64::INFINITY)
                };
                let velocity = if l.velocity.is_finite() && l.velocity > 0.0 {
                    l.velocity
                } else {
                    DEFAULT_VELOCITY_LIMIT
                };
                Bounds {
                    middle,
                    allowed,
                    lowest,
                    highest,
                    velocity: settings.velocity_fraction * velocity,
                    acceleration: settings.acceleration_fraction * settings.acceleration_limit,
                }
            })
            .collect()
    }
}

/// An excitation for `model` within the envelope of `settings` (a range around a pose,
/// fractions of the speed and acceleration limits), optimised for the condition number of
/// the base inertial regressor. Deterministic for a seed.
///
/// Per joint `q(t) = q0 + sum_l a_l / (w l) sin(w l t) - b_l / (w l) cos(w l t)`, `w = 2 pi /
/// period`, with `a_1`, `b_1` fixed so that the motion starts and ends at rest; each joint
/// scaled to its envelope on the output samples: `range` around `pose` inside the limits less
/// the margin, `velocity_fraction` of its velocity limit ([`DEFAULT_VELOCITY_LIMIT`] where
/// the URDF has none) and `acceleration_fraction` of `acceleration_limit`. The criterion is the base inertial regressor's condition number (columns at unit
/// norm; the joint terms are not included), lowered from 16 random starts by a coordinate
/// search of `iterations` evaluations.
///
/// ```no_run
/// use admittance_dynamics::{excitation, ExcitationSettings, Model};
/// let model = Model::from_urdf_file("models/baxter_left_arm.urdf".as_ref(), None, None).unwrap();
/// let e = excitation(&model, &ExcitationSettings { duration: 60.0, ..Default::default() }).unwrap();
/// println!("condition number {:.2} ({} samples)", e.condition_number, e.len());
/// ```
pub fn excitation(
    model: &Model,
    settings: &ExcitationSettings,
) -> Result<Excitation, DynamicsError> {
    settings.validate_for(model)?;
    if model.nq() == 0 {
        return Err(DynamicsError::InvalidArgument(
            "excitation needs an arm with at least one joint".into(),
        ));
    }
    let mut problem = Problem::new(model, settings)?;
    let mut rng = SplitMix(settings.seed);
    let starts: Vec<Vec<f64>> = (0..RESTARTS)
        .map(|_| problem.random_start(&mut rng))
        .collect();
    let mut best = (f64::INFINITY, starts[0].clone());
    for theta in &starts {
        let c = problem.cost(theta)?;
        if c < best.0 {
            best = (c, theta.clone());
        }
    }
    let theta = problem.coordinate_search(best.1, best.0, settings.iterations)?;
    let initial = problem.sample(&starts[0])?;
    let mut out = problem.sample(&theta)?;
    out.initial_condition_number = initial.condition_number;
    Ok(out)
}

/// What the search needs: limits, grids, base parameters, scratch.
struct Problem<'m> {
    model: &'m Model,
    settings: &'m ExcitationSettings,
    bounds: Vec<Bounds>,
    base: BaseParameters,
    w: f64,
    /// One period at the output rate: where the limits are checked.
    scale_grid: Grid,
    /// One period, coarser: where the search evaluates the condition number.
    search_grid: Grid,
    data: Data,
}

impl<'m> Problem<'m> {
    fn new(model: &'m Model, settings: &'m ExcitationSettings) -> Result<Self, DynamicsError> {
        let w = 2.0 * std::f64::consts::PI / settings.period;
        let l = settings.harmonics;
        let per_period = (settings.period * settings.rate_hz).round().max(1.0) as usize;
        let search = per_period.min(SEARCH_SAMPLES_PER_HARMONIC * l);
        Ok(Problem {
            model,
            settings,
            bounds: Bounds::of(model, settings),
            base: BaseParameters::new(model, 100, 1)?,
            w,
            scale_grid: Grid::new(w, l, settings.period, per_period),
            search_grid: Grid::new(w, l, settings.period, search),
            data: Data::new(model),
        })
    }

    /// Free coefficients per joint: `a_2..a_L, b_2..b_L`, each uniform in `+-1/l`.
    fn random_start(&self, rng: &mut SplitMix) -> Vec<f64> {
        let free = 2 * (self.settings.harmonics - 1);
        (0..self.model.nq() * free)
            .map(|k| (2.0 * rng.unit() - 1.0) / (2 + k % free / 2) as f64)
            .collect()
    }

    /// The condition number on the search grid of the series `theta` makes.
    fn cost(&mut self, theta: &[f64]) -> Result<f64, DynamicsError> {
        let series = self.series(theta);
        let [q, qdot, qddot] = self.search_grid.sample(&series);
        self.condition(&q, &qdot, &qddot)
    }

    /// Coordinate search from `theta`: each free coefficient up and down by the step (scaled
    /// by its harmonic); the step halves after a sweep with no gain.
    fn coordinate_search(
        &mut self,
        mut theta: Vec<f64>,
        mut cost: f64,
        budget: usize,
    ) -> Result<Vec<f64>, DynamicsError> {
        let free = 2 * (self.settings.harmonics - 1);
        let (mut step, mut used) = (0.5, 0);
        while used < budget && step > 1e-3 {
            let mut improved = false;
            for k in 0..theta.len() {
                for sign in [1.0, -1.0] {
                    if used >= budget {
                        return Ok(theta);
                    }
                    let old = theta[k];
                    theta[k] += sign * step / (2 + k % free / 2) as f64;
                    let c = self.cost(&theta)?;
                    used += 1;
                    if c < cost {
                        cost = c;
                        improved = true;
                        break;
                    }
                    theta[k] = old;
                }
            }
            if !improved {
                step *= 0.5;
            }
        }
        Ok(theta)
    }

    /// The series of `theta`: first harmonics fixed to start at rest, each joint scaled to
    /// its limits on the scale grid and centred.
    fn series(&self, theta: &[f64]) -> Vec<FourierSeries> {
        let free = 2 * (self.settings.harmonics - 1);
        theta
            .chunks_exact(free)
            .zip(&self.bounds)
            .map(|(c, bounds)| {
                let (a_rest, b_rest) = c.split_at(free / 2);
                let mut a = vec![-a_rest.iter().sum::<f64>()];
                a.extend_from_slice(a_rest);
                let mut b = vec![-b_rest
                    .iter()
                    .enumerate()
                    .map(|(l, b)| (l + 2) as f64 * b)
                    .sum::<f64>()];
                b.extend_from_slice(b_rest);
                self.scale_grid
                    .fit(FourierSeries { offset: 0.0, a, b }, bounds, f64::INFINITY)
            })
            .collect()
    }

    /// The excitation sampled at the output rate, every joint rescaled if a sample between
    /// the scale grid's points overshoots.
    fn sample(&mut self, theta: &[f64]) -> Result<Excitation, DynamicsError> {
        let s = self.settings;
        let count = (s.duration * s.rate_hz).round() as usize + 1;
        let t: Vec<f64> = (0..count).map(|k| k as f64 / s.rate_hz).collect();
        let output = Grid::at(self.w, s.harmonics, t.clone());
        let series: Vec<FourierSeries> = self
            .series(theta)
            .into_iter()
            .zip(&self.bounds)
            .map(|(f, b)| output.fit(f, b, 1.0))
            .collect();
        let [q, qdot, qddot] = output.sample(&series);
        let condition_number = self.condition(&q, &qdot, &qddot)?;
        let base_parameters = self.base.rank();
        Ok(Excitation {
            t,
            q,
            qdot,
            qddot,
            dof: self.model.nq(),
            base_frequency: self.w,
            series,
            condition_number,
            initial_condition_number: f64::NAN,
            base_parameters,
        })
    }

    /// Condition number of the stacked base regressor over the samples, from the Gram matrix
    /// of its independent columns scaled to unit norm.
    fn condition(&mut self, q: &[f64], qdot: &[f64], qddot: &[f64]) -> Result<f64, DynamicsError> {
        let idx = self.base.independent().to_vec();
        let (r, n) = (idx.len(), self.model.nq());
        let mut gram = DMatrix::<f64>::zeros(r, r);
        let mut row = vec![0.0; r];
        for k in 0..q.len() / n {
            let s = k * n..(k + 1) * n;
            let y = joint_torque_regressor(
                self.model,
                &mut self.data,
                &q[s.clone()],
                &qdot[s.clone()],
                &qddot[s],
            )?;
            for i in 0..y.nrows() {
                row.iter_mut().zip(&idx).for_each(|(x, &c)| *x = y[(i, c)]);
                for c in 0..r {
                    for d in c..r {
                        gram[(c, d)] += row[c] * row[d];
                    }
                }
            }
        }
        let g = DMatrix::from_fn(r, r, |i, j| {
            let (c, d) = (i.min(j), i.max(j));
            gram[(c, d)] / (gram[(c, c)] * gram[(d, d)]).sqrt().max(1e-300)
        });
        let e = g.symmetric_eigenvalues();
        Ok(if e.min() > 0.0 {
            (e.max() / e.min()).sqrt()
        } else {
            f64::INFINITY
        })
    }
}

/// Sample times with each harmonic's sine and cosine precomputed.
struct Grid {
    w: f64,
    harmonics: usize,
    /// `(sin, cos)` of `w l t_k`, `k * L + (l - 1)`.
    trig: Vec<(f64, f64)>,
}

impl Grid {
    /// `count` samples evenly over one period.
    fn new(w: f64, harmonics: usize, period: f64, count: usize) -> Self {
        Self::at(
            w,
            harmonics,
            (0..count)
                .map(|k| k as f64 * period / count as f64)
                .collect(),
        )
    }

    fn at(w: f64, harmonics: usize, t: Vec<f64>) -> Self {
        let trig = t
            .iter()
            .flat_map(|t| (1..=harmonics).map(move |l| (w * l as f64 * t).sin_cos()))
            .collect();
        Grid { w, harmonics, trig }
    }

    fn len(&self) -> usize {
        self.trig.len() / self.harmonics
    }

    /// Position, velocity, acceleration of `f` at sample `k`.
    fn evaluate(&self, f: &FourierSeries, k: usize) -> [f64; 3] {
        let mut out = [f.offset, 0.0, 0.0];
        for (l, (&(s, c), (a, b))) in self.trig[k * self.harmonics..(k + 1) * self.harmonics]
            .iter()
            .zip(f.a.iter().zip(&f.b))
            .enumerate()
        {
            let wl = self.w * (l + 1) as f64;
            out[0] += (a * s - b * c) / wl;
            out[1] += a * c + b * s;
            out[2] += wl * (b * c - a * s);
        }
        out
    }

    /// Every sample of every joint: positions, velocities, accelerations, row-major.
    fn sample(&self, series: &[FourierSeries]) -> [Vec<f64>; 3] {
        let size = self.len() * series.len();
        let mut out = [
            Vec::with_capacity(size),
            Vec::with_capacity(size),
            Vec::with_capacity(size),
        ];
        for k in 0..self.len() {
            for f in series {
                let s = self.evaluate(f, k);
                (0..3).for_each(|j| out[j].push(s[j]));
            }
        }
        out
    }

    /// `f` scaled (never up when `cap` is 1) so that on this grid every limit holds, and
    /// its offset set to centre the motion in the range.
    fn fit(&self, f: FourierSeries, bounds: &Bounds, cap: f64) -> FourierSeries {
        let (mut lo, mut hi, mut v, mut a) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0.0f64);
        let centred = FourierSeries { offset: 0.0, ..f };
        for k in 0..self.len() {
            let [p, pv, pa] = self.evaluate(&centred, k);
            (lo, hi, v, a) = (lo.min(p), hi.max(p), v.max(pv.abs()), a.max(pa.abs()));
        }
        let span = 0.5 * (hi - lo);
        let scale = [
            bounds.allowed / span,
            bounds.velocity / v,
            bounds.acceleration / a,
            cap,
        ]
        .into_iter()
        .filter(|s| !s.is_nan())
        .fold(f64::INFINITY, f64::min);
        let scale = if scale.is_finite() { scale } else { 0.0 };
        FourierSeries {
            offset: bounds.middle - scale * 0.5 * (hi + lo),
            a: centred.a.iter().map(|x| x * scale).collect(),
            b: centred.b.iter().map(|x| x * scale).collect(),
        }
    }
}
