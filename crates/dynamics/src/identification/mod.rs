//! Identification of a real arm (docs/method.md section 1): the inertial parameters of
//! every body and what each joint adds (rotor inertia, friction, offset, springs), fitted
//! by least squares to free motion, regularised toward the URDF, physically consistent,
//! with every choice made and every error measured on motion the fit did not see.
//! [`excitation`] designs the motion to record for it: a finite Fourier series per joint
//! inside the arm's limits, optimised for the base regressor's condition number.
//!
//! ```no_run
//! use admittance_dynamics::{identify, IdentificationSettings, Model, Samples};
//! # let (q, qd, qdd, tau) = (vec![0.0; 70], vec![0.0; 70], vec![0.0; 70], vec![0.0; 70]);
//! let model = Model::from_urdf_file("models/baxter_left_arm.urdf".as_ref(), None, None).unwrap();
//! let train = Samples { q: &q, qdot: &qd, qddot: &qdd, tau: &tau, dof: 7 };
//! let ident = identify(&model, &train, None, &IdentificationSettings::default()).unwrap();
//! println!("expected false torque per joint (N m): {:?}", ident.summary.expected_false_torque_rms);
//! ```

mod acceleration_gain;
mod base;
mod cholesky;
mod consistency;
mod constrained;
mod excitation;
mod excitation_settings;
mod file;
mod fit;
mod fit_acceleration;
mod held_out;
mod joint_terms;
mod normal;
mod payload;
mod prior_scale;
mod recording_checks;
mod samples;
mod settings;
mod springs;
mod training_range;
mod training_speed;
mod urdf_torques;

pub use acceleration_gain::AccelerationGains;
pub use base::BaseParameters;
pub use consistency::is_physically_consistent;
pub use excitation::{
    excitation, Excitation, ExcitationSettings, FourierSeries, LimitUse, DEFAULT_EXCITATION_RANGE,
    DEFAULT_LIMIT_FRACTION, DEFAULT_VELOCITY_LIMIT,
};
pub use file::{IdentificationFile, IDENTIFICATION_FORMAT, IDENTIFICATION_FORMAT_VERSION};
pub use fit::identify;
pub use fit_acceleration::FIT_ACCELERATION_HZ;
pub use joint_terms::JointTerms;
pub use payload::identify_payload;
pub use samples::Samples;
pub use settings::{IdentificationSettings, COULOMB_WIDTH_CANDIDATES};
pub use training_range::{
    beyond_training_range, beyond_training_range_of, outside_training_range, RangeExcursion,
    TRAINING_RANGE_MARGIN,
};
pub use training_speed::{
    beyond_training_speed, faster_than_training, SpeedExcursion, TRAINING_SPEED_MARGIN,
};

use serde::{Deserialize, Serialize};

use crate::algorithms::regressor::{with_inertial_parameters, PARAMETERS_PER_BODY};
use crate::algorithms::rnea::{rnea, rnea_pass_at_placements};
use crate::data::Data;
use crate::error::{check_len, DimensionError, DynamicsError};
use crate::model::Model;
use settings::is_zero;

/// An identified arm: its rigid-body model (the URDF's kinematics with identified
/// inertias) and each joint's terms. `tau = RNEA(q, q', q'') + tau_joint(q, q', q'')`.
#[derive(Clone, Debug)]
pub struct Identification {
    /// The identified rigid-body model.
    pub model: Model,
    /// Per-joint rotor inertia, friction, offset and springs.
    pub joint_terms: Vec<JointTerms>,
    /// How it was chosen and what it is expected to get wrong.
    pub summary: IdentificationSummary,
}

/// What identification chose and measured on held-out motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentificationSummary {
    /// Where settings were chosen and errors measured.
    pub held_out: String,
    /// The ridge weight toward the URDF (relative to each column's scale).
    pub ridge: f64,
    /// Per joint: whether it kept spring terms.
    pub springs: Vec<bool>,
    /// Bodies that an unconstrained fit would have made physically impossible (the fit
    /// kept them possible): where the data and rigid-body physics disagree.
    pub projected_bodies: Vec<usize>,
    /// Bodies that ended at their mass bound or sphere (`IdentificationSettings::
    /// max_mass_ratio`): the data wanted them heavier or farther out than the arm's size, a
    /// torque the model lacks (a spring, a cable) or a URDF whose masses are off. Absent in
    /// older files: none listed.
    #[serde(default)]
    pub bodies_at_extent: Vec<usize>,
    /// Expected false torque on motion not trained on, rms per joint (N m).
    pub expected_false_torque_rms: Vec<f64>,
    /// The URDF's own rms per joint on the same held-out motion (N m).
    pub prior_false_torque_rms: Vec<f64>,
    /// Number of base parameters (identifiable combinations of the inertial ones).
    pub base_parameters: usize,
    /// Condition number of the training motion's base regressor (columns at unit norm);
    /// infinite when the motion leaves a base parameter unexcited, and for an
    /// identification that was not fitted (`from_model`). Written as `null` in files (JSON
    /// has no infinity), read back as infinite.
    #[serde(deserialize_with = "null_as_infinite")]
    pub condition_number: f64,
    /// Training samples.
    pub training_samples: usize,
    /// Validation samples (0: blocked cross-validation).
    pub validation_samples: usize,
    /// The settings used.
    pub settings: IdentificationSettings,
    /// Cut-off of the input conditioning (`InputConditioner`, docs/method.md section 7) the
    /// samples went through before the fit (Hz; 0: the signals as recorded). Every consumer
    /// conditions its inputs the same way.
    #[serde(default)]
    pub input_filter_hz: f64,
    /// Per joint: how much later its torque signal is than the motion signals (s;
    /// negative: earlier; empty: none). `identify` chooses one delay for all joints on
    /// held-out motion (kept when it removes a fifth of the error). Consumers pair each joint's
    /// torque with the motion this much older.
    #[serde(default)]
    pub delay_s: Vec<f64>,
    /// 90 % step-response time of the conditioned estimate (s): the conditioning filter's
    /// plus the delay; what the cut-off costs in reaction time.
    #[serde(default)]
    pub step_response_s: f64,
    /// How much of the measured (conditioned) acceleration the prediction trusts, chosen
    /// on held-out motion: a Wiener gain, 1 for clean accelerations, toward 0 where
    /// differentiation noise swamps the inertial torque (a physical model cannot shrink its
    /// inertia to absorb that noise, as a free least squares does with negative rotor
    /// inertias). [`Identification::predict`] multiplies `q''` by it; the rigid-body model
    /// itself is untouched (the momentum observer never uses `q''`).
    #[serde(default = "unit_gain")]
    pub acceleration_gain: f64,
    /// The factor on the URDF's inertial parameters that the ridge pulls toward: the
    /// least-squares scale of the URDF's gravity and Coriolis torque to the recorded torque
    /// (its inertial torque, friction, offsets and springs beside it), or 1 when that is
    /// within 1 % of 1 or the URDF's torque explains too little of the recorded one to tell
    /// (`identify` refuses a scale outside 0.25 to 4 that it explains). Away from 1 it says that the
    /// torque and the URDF disagree in size (a torque constant or gear ratio, the torque's
    /// units, masses uniformly off); the fitted bodies carry it.
    #[serde(default = "unit_gain")]
    pub prior_scale: f64,
    /// Per joint, the lowest and highest position of the training samples (rad or m; empty:
    /// not recorded). Outside it the fitted springs, offsets and gravity extrapolate, which
    /// held-out stretches of the same recording cannot judge: `admittance evaluate` reports
    /// the samples that leave it ([`Identification::range_excursions`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub training_range: Vec<[f64; 2]>,
    /// Per joint, the highest speed `|q'|` of the training samples, conditioned as they
    /// were fitted (rad/s or m/s; empty: not recorded). Faster the fitted friction
    /// extrapolates: `admittance evaluate` reports the samples that exceed it
    /// ([`Identification::speed_excursions`]) and the run-time loop flags each such step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub training_speed: Vec<f64>,
    /// The cut-off (Hz) of the zero-phase low-pass on the acceleration the fit regressed the
    /// inertial torque on (`IdentificationSettings::fit_acceleration_hz`); 0: as measured
    /// (and in files written before it existed).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub fit_acceleration_hz: f64,
    /// Per joint, the mean square of the measured (conditioned) `q''` on the motion the
    /// gain was chosen on: the validation samples when given, else the training samples
    /// ((rad/s^2)^2; empty: not recorded, as in older files). With
    /// `acceleration_gain` it gives the noise power `(1 - gain) P` against which predictions
    /// over a motion raise the gain where that motion accelerates well beyond the noise
    /// ([`AccelerationGains`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub acceleration_power: Vec<f64>,
}

fn unit_gain() -> f64 {
    1.0
}

/// Per-joint rms errors of a model on samples.
pub(crate) struct JointErrors {
    pub rms: Vec<f64>,
}

impl Identification {
    /// A plain rigid-body model as a nominal model: no joint terms (what a URDF alone
    /// says), so that every consumer of a nominal model takes either.
    pub fn from_model(model: Model) -> Self {
        let n = model.nq();
        let none = JointTerms {
            coulomb_width: COULOMB_WIDTH_CANDIDATES[0],
            ..Default::default()
        };
        Identification {
            model,
            joint_terms: vec![none; n],
            summary: IdentificationSummary::empty(n),
        }
    }

    /// Whether any joint term is non-zero (an identification, not a bare URDF model).
    pub fn has_joint_terms(&self) -> bool {
        self.joint_terms.iter().any(|t| !t.is_zero())
    }

    /// Replaces each row's torque by what this model does not explain: `tau -
    /// predict(q, q', q'')`, with rows `[q, q', q'']` (3 n per row) in `inputs` and `n` per
    /// row in `torques`: the target of a residual network.
    pub fn subtract_from(&self, inputs: &[f64], torques: &mut [f64]) -> Result<(), DimensionError> {
        let n = self.model.nq();
        let mut data = Data::new(&self.model);
        let mut out = vec![0.0; n];
        // The rows are one motion in time order: the gain on `q''` follows it.
        let mut gains = AccelerationGains::new(&self.summary, None);
        let mut g = vec![0.0; n];
        for (row, target) in inputs.chunks_exact(3 * n).zip(torques.chunks_exact_mut(n)) {
            let (q, qd, qdd) = (&row[..n], &row[n..2 * n], &row[2 * n..]);
            gains.update(qdd, &mut g);
            self.predict_with_gains(&mut data, q, qd, qdd, &g, &mut out)?;
            target.iter_mut().zip(&out).for_each(|(t, m)| *t -= m);
        }
        Ok(())
    }

    /// From a solution vector `[10 n inertial | 7 per joint]`.
    pub(crate) fn from_solution(
        model: &Model,
        x: &nalgebra::DVector<f64>,
        width: f64,
    ) -> Result<Self, DynamicsError> {
        let n = model.nq();
        let split = PARAMETERS_PER_BODY * n;
        let identified = with_inertial_parameters(model, &x.as_slice()[..split])?;
        let joint_terms = x.as_slice()[split..]
            .chunks_exact(joint_terms::JOINT_FEATURES)
            .map(|c| JointTerms::from_coefficients(c, width))
            .collect();
        Ok(Identification {
            model: identified,
            joint_terms,
            summary: IdentificationSummary::empty(n),
        })
    }

    /// The torque the identified arm needs for measured `(q, q', q'')` (N m), into `out`:
    /// RNEA on the identified model plus each joint's terms, the measured acceleration
    /// weighted by [`IdentificationSummary::acceleration_gain`]. Allocation-free.
    pub fn predict(
        &self,
        data: &mut Data,
        q: &[f64],
        qdot: &[f64],
        qddot: &[f64],
        out: &mut [f64],
    ) -> Result<(), DimensionError> {
        let gain = self.summary.acceleration_gain;
        self.predict_at(data, q, qdot, qddot, |_| gain, out)
    }

    /// [`predict`](Self::predict) with each joint's own share of the measured acceleration,
    /// `gains` (from [`AccelerationGains`] over a motion). Allocation-free.
    pub fn predict_with_gains(
        &self,
        data: &mut Data,
        q: &[f64],
        qdot: &[f64],
        qddot: &[f64],
        gains: &[f64],
        out: &mut [f64],
    ) -> Result<(), DimensionError> {
        check_len("gains", gains, self.model.nq())?;
        self.predict_at(data, q, qdot, qddot, |i| gains[i], out)
    }

    fn predict_at(
        &self,
        data: &mut Data,
        q: &[f64],
        qdot: &[f64],
        qddot: &[f64],
        gain: impl Fn(usize) -> f64,
        out: &mut [f64],
    ) -> Result<(), DimensionError> {
        let n = self.model.nq();
        check_len("out", out, n)?;
        check_len("qddot", qddot, n)?;
        // The gain goes through `out` as the acceleration buffer: no allocation.
        for (i, (o, a)) in out.iter_mut().zip(qddot).enumerate() {
            *o = gain(i) * a;
        }
        let tau = rnea(&self.model, data, q, qdot, out)?;
        for (i, o) in out.iter_mut().enumerate() {
            let qdd = gain(i) * qddot[i];
            *o = tau[i] + self.joint_terms[i].torque(q[i], qdot[i], qdd);
        }
        Ok(())
    }

    /// The predictions of consecutive samples of one motion (rows of `n`, in time order, at
    /// the identification's sample rate): [`predict`](Self::predict) with the gain on `q''`
    /// raised where the motion accelerates well beyond the training's noise
    /// ([`AccelerationGains`]), into `out`.
    pub fn predict_motion(
        &self,
        q: &[f64],
        qdot: &[f64],
        qddot: &[f64],
        out: &mut [f64],
    ) -> Result<(), DimensionError> {
        let n = self.model.nq();
        for (name, v) in [("q", q), ("qdot", qdot), ("qddot", qddot)] {
            check_len(name, v, out.len())?;
        }
        let mut data = Data::new(&self.model);
        let mut gains = AccelerationGains::new(&self.summary, None);
        let mut g = vec![0.0; n];
        for k in 0..out.len() / n.max(1) {
            let r = k * n..(k + 1) * n;
            gains.update(&qddot[r.clone()], &mut g);
            let (q, qd, qdd) = (&q[r.clone()], &qdot[r.clone()], &qddot[r.clone()]);
            self.predict_with_gains(&mut data, q, qd, qdd, &g, &mut out[r])?;
        }
        Ok(())
    }

    /// Each joint's friction, offset and springs at `(q, q')` (no rotor inertia), into
    /// `out`: what a momentum observer subtracts besides gravity. Allocation-free.
    pub fn joint_friction_torque(
        &self,
        q: &[f64],
        qdot: &[f64],
        out: &mut [f64],
    ) -> Result<(), DimensionError> {
        let n = self.model.nq();
        check_len("q", q, n)?;
        check_len("qdot", qdot, n)?;
        check_len("out", out, n)?;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.joint_terms[i].velocity_and_position_torque(q[i], qdot[i]);
        }
        Ok(())
    }

    /// The rotor inertia of each joint (kg m^2).
    pub fn armature(&self) -> impl Iterator<Item = f64> + '_ {
        self.joint_terms.iter().map(|t| t.armature)
    }

    /// Per candidate acceleration gain and joint, the sum of squared errors on `samples`:
    /// the prediction is affine in the gain (`tau(g) = tau(0) + g (tau(1) - tau(0))`), so two
    /// predictions per sample serve every gain.
    pub(crate) fn squared_errors_by_gain(
        &self,
        samples: &Samples,
        gains: &[f64],
    ) -> Result<Vec<Vec<f64>>, DynamicsError> {
        let n = self.model.nq();
        let mut data = Data::new(&self.model);
        let (mut p0, mut p1) = (vec![0.0; n], vec![0.0; n]);
        // Per joint: sum e0^2, sum e0 d, sum d^2 (e0 the error at gain 0, d the change per gain).
        let mut sums = vec![[0.0; 3]; n];
        for k in 0..samples.len() {
            let (q, qd, qdd, tau) = samples.row(k);
            // `predict` at gains 1 and 0, the joint placements and joint terms computed once.
            p1.copy_from_slice(rnea(&self.model, &mut data, q, qd, qdd)?.as_slice());
            rnea_pass_at_placements(&self.model, &mut data, Some(qd), None, None);
            for i in 0..n {
                let terms = &self.joint_terms[i];
                let other = terms.velocity_and_position_torque(q[i], qd[i]);
                p0[i] = data.tau[i] + other;
                p1[i] += terms.armature * qdd[i] + other;
            }
            for i in 0..n {
                let (e0, d) = (tau[i] - p0[i], p1[i] - p0[i]);
                sums[i][0] += e0 * e0;
                sums[i][1] += e0 * d;
                sums[i][2] += d * d;
            }
        }
        Ok(gains
            .iter()
            .map(|g| {
                sums.iter()
                    .map(|s| (s[0] - 2.0 * g * s[1] + g * g * s[2]).max(0.0))
                    .collect()
            })
            .collect())
    }

    pub(crate) fn joint_errors(&self, samples: &Samples) -> Result<JointErrors, DynamicsError> {
        let n = self.model.nq();
        let mut data = Data::new(&self.model);
        let mut out = vec![0.0; n];
        let mut sq = vec![0.0; n];
        let mut gains = AccelerationGains::new(&self.summary, None);
        let mut g = vec![0.0; n];
        for k in 0..samples.len() {
            let (q, qd, qdd, tau) = samples.row(k);
            gains.update(qdd, &mut g);
            self.predict_with_gains(&mut data, q, qd, qdd, &g, &mut out)?;
            for i in 0..n {
                sq[i] += (out[i] - tau[i]).powi(2);
            }
        }
        let len = samples.len().max(1) as f64;
        Ok(JointErrors {
            rms: sq.iter().map(|s| (s / len).sqrt()).collect(),
        })
    }
}

/// A number that `null` stands for infinity in (serde_json writes infinities as `null`).
fn null_as_infinite<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

impl IdentificationSummary {
    fn empty(n: usize) -> Self {
        IdentificationSummary {
            held_out: String::new(),
            ridge: 0.0,
            springs: vec![false; n],
            projected_bodies: Vec::new(),
            bodies_at_extent: Vec::new(),
            expected_false_torque_rms: Vec::new(),
            prior_false_torque_rms: Vec::new(),
            base_parameters: 0,
            condition_number: f64::INFINITY,
            training_samples: 0,
            validation_samples: 0,
            settings: IdentificationSettings::default(),
            input_filter_hz: 0.0,
            delay_s: Vec::new(),
            step_response_s: 0.0,
            acceleration_gain: 1.0,
            prior_scale: 1.0,
            training_range: Vec::new(),
            training_speed: Vec::new(),
            fit_acceleration_hz: 0.0,
            acceleration_power: Vec::new(),
        }
    }
}

impl<'a> Samples<'a> {
    /// Samples `start..end`.
    pub fn slice(&self, start: usize, end: usize) -> Samples<'a> {
        let r = start * self.dof..end * self.dof;
        Samples {
            q: &self.q[r.clone()],
            qdot: &self.qdot[r.clone()],
            qddot: &self.qddot[r.clone()],
            tau: &self.tau[r],
            dof: self.dof,
        }
    }
}

#[allow(dead_code)]
fn _assert_send(i: Identification) -> impl Send + Sync {
    i
}
