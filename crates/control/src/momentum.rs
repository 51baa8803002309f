//! The generalised-momentum observer (docs/method.md section 5, "Baseline"): a model-based
//! external-torque estimate that needs `M`, `C` and `G` of a nominal model but no
//! acceleration.
//!
//! ```text
//!     p = M(q) q'
//!     r = K_O (p - integral_0^t (tau + C(q, q')^T q' - G(q) + r) ds - p0)
//! ```
//!
//! With the plant `M q'' + C q' + G + F = tau + tau_ext` (docs/method.md section 1) and
//! `Mdot = C + C^T`, `p' = tau + tau_ext + C^T q' - G - F`, so `r' = K_O (tau_ext - F - r)`:
//! per joint a first-order low-pass of `tau_ext - F` with time constant `1 / K_O,i`. The
//! estimate has docs/method.md section 0's sign (the torque applied **to** the robot); friction
//! that the nominal model does not know appears in it with the opposite sign.
//!
//! Discretisation (one [`Observer::update`] per control sample, period `dt`): the torque
//! given at a sample is taken as the torque held over the period that just ended
//! (rectangle rule), the model terms `C^T q' - G` are integrated by the trapezoidal rule,
//! and `r` by the rectangle rule with its previous value (explicit: stable for
//! `K_O dt < 2`, and without overshoot for `K_O dt <= 1`). A gain beyond one over the
//! period is taken as `1 / dt` for that step: the estimate cannot follow faster than one
//! sample, and the update stays stable at any sample rate (at 20 Hz the default 50 /s
//! would otherwise diverge). The first
//! update after construction or [`reset`](Observer::reset) sets `p0` and returns zero.

use std::sync::Arc;

use admittance_dynamics::{momentum_observer_terms, Data, Identification, JointTerms, Model};
use serde::{Deserialize, Serialize};

use crate::config::{Bound, JointValues};
use crate::error::{ConfigError, Fault, StepStatus};
use crate::observer::{Observer, ObserverInput};
use crate::safe_hold::first_non_finite;

/// Settings of [`MomentumObserver`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentumObserverConfig {
    /// Observer gain `K_O` per joint (1/s): the estimate follows the true external torque
    /// with time constant `1 / K_O`. Default 50 (20 ms).
    #[serde(default = "default_gain")]
    pub gain: JointValues,
}

fn default_gain() -> JointValues {
    JointValues::Uniform(50.0)
}

impl Default for MomentumObserverConfig {
    fn default() -> Self {
        Self {
            gain: default_gain(),
        }
    }
}

/// The generalised-momentum observer with a nominal model (docs/method.md section 5).
/// Allocation-free after construction.
#[derive(Clone, Debug)]
pub struct MomentumObserver {
    model: Arc<Model>,
    data: Data,
    gain: Vec<f64>,
    /// `integral (tau + C^T q' - G + r) ds`.
    integral: Vec<f64>,
    p0: Vec<f64>,
    r: Vec<f64>,
    /// `C^T q' - G` at the previous sample (trapezoidal rule).
    model_terms_prev: Vec<f64>,
    p: Vec<f64>,
    model_terms: Vec<f64>,
    /// Identified per-joint terms (rotor inertia, friction, offset, springs), or none.
    joint_terms: Vec<JointTerms>,
    started: bool,
}

impl MomentumObserver {
    /// An observer on the nominal `model` (which may differ from the true arm).
    pub fn new(model: Arc<Model>, config: &MomentumObserverConfig) -> Result<Self, ConfigError> {
        let n = model.nq();
        let gain = config.gain.resolve("gain", n, Bound::Positive)?;
        let data = Data::new(&model);
        Ok(MomentumObserver {
            model,
            data,
            gain,
            integral: vec![0.0; n],
            p0: vec![0.0; n],
            r: vec![0.0; n],
            model_terms_prev: vec![0.0; n],
            p: vec![0.0; n],
            model_terms: vec![0.0; n],
            joint_terms: Vec::new(),
            started: false,
        })
    }

    /// An observer on an identified arm: its rigid-body model, and each joint's rotor
    /// inertia (in the momentum, `p = (M + I_a) q'`) and friction, offset and springs
    /// (subtracted like gravity), so that what it reports is the external torque only.
    pub fn from_identification(
        identification: &Identification,
        config: &MomentumObserverConfig,
    ) -> Result<Self, ConfigError> {
        let mut observer = Self::new(Arc::new(identification.model.clone()), config)?;
        observer.joint_terms = identification.joint_terms.clone();
        Ok(observer)
    }

    /// The identified joint terms (empty for a plain rigid-body nominal model).
    pub fn joint_terms(&self) -> &[JointTerms] {
        &self.joint_terms
    }

    /// The gains `K_O`.
    pub fn gain(&self) -> &[f64] {
        &self.gain
    }

    /// The nominal model.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// Computes `p = M q'` and `C^T q' - G` into the buffers, in one O(n) pass over the
    /// chain ([`momentum_observer_terms`]; neither `M` nor `C` is formed).
    fn evaluate(&mut self, q: &[f64], qdot: &[f64]) -> Result<(), Fault> {
        momentum_observer_terms(&self.model, &mut self.data, q, qdot)
            .map_err(|_| Fault::Internal("momentum observer: model terms"))?;
        let d = &self.data;
        for (i, (p, terms)) in self.p.iter_mut().zip(&mut self.model_terms).enumerate() {
            *p = d.momentum[i];
            *terms = d.coriolis_transpose_v[i] - d.gravity_torque[i];
        }
        for (i, joint) in self.joint_terms.iter().enumerate() {
            self.p[i] += joint.armature * qdot[i];
            self.model_terms[i] -= joint.velocity_and_position_torque(q[i], qdot[i]);
        }
        Ok(())
    }

    fn check(&self, input: &ObserverInput, dt: f64, estimate: &[f64]) -> Result<(), Fault> {
        let n = self.gain.len();
        for (argument, v) in [
            ("q", input.q),
            ("qdot", input.qdot),
            ("tau_commanded", input.tau_commanded),
            ("estimate", estimate),
        ] {
            if v.len() != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        if let Some(joint) = first_non_finite(input.q) {
            return Err(Fault::NonFiniteMeasurement {
                argument: "q",
                joint,
            });
        }
        if let Some(joint) = first_non_finite(input.qdot) {
            return Err(Fault::NonFiniteMeasurement {
                argument: "qdot",
                joint,
            });
        }
        if let Some(joint) = first_non_finite(input.tau_commanded) {
            return Err(Fault::NonFiniteMeasurement {
                argument: "tau_commanded",
                joint,
            });
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Fault::InvalidTimeStep);
        }
        Ok(())
    }

    fn step(&mut self, input: &ObserverInput, dt: f64, estimate: &mut [f64]) -> Result<(), Fault> {
        self.check(input, dt, estimate)?;
        self.evaluate(input.q, input.qdot)?;
        let n = self.gain.len();
        if !self.started {
            self.p0.copy_from_slice(&self.p);
            self.integral.fill(0.0);
            self.r.fill(0.0);
            self.model_terms_prev.copy_from_slice(&self.model_terms);
            self.started = true;
            estimate.fill(0.0);
            return Ok(());
        }
        for i in 0..n {
            self.integral[i] += (input.tau_commanded[i] + self.r[i]) * dt
                + 0.5 * (self.model_terms_prev[i] + self.model_terms[i]) * dt;
            let gain = self.gain[i].min(1.0 / dt);
            let r = gain * (self.p[i] - self.integral[i] - self.p0[i]);
            if !r.is_finite() {
                return Err(Fault::NonFiniteEstimate { joint: i });
            }
            self.r[i] = r;
        }
        self.model_terms_prev.copy_from_slice(&self.model_terms);
        estimate.copy_from_slice(&self.r);
        Ok(())
    }
}

impl Observer for MomentumObserver {
    fn name(&self) -> &str {
        "momentum"
    }
    fn dof(&self) -> usize {
        self.gain.len()
    }
    /// On a fault the estimate is zero and the observer restarts at the next valid sample
    /// (a new `p0`), so a bad sample cannot leave a permanent offset in the integral.
    fn update(&mut self, input: &ObserverInput, dt: f64, estimate: &mut [f64]) -> StepStatus {
        match self.step(input, dt, estimate) {
            Ok(()) => StepStatus::Ok,
            Err(f) => {
                estimate.fill(0.0);
                self.started = false;
                StepStatus::Fault(f)
            }
        }
    }
    fn reset(&mut self) {
        self.started = false;
        self.integral.fill(0.0);
        self.r.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admittance_dynamics::{aba, gravity_torque};

    /// Per-joint scales that keep the light wrist joints slow.
    const EXCITATION: [f64; 7] = [1.5, 1.5, 0.5, 0.5, 0.05, 0.05, 0.005];
    const DAMPING: [f64; 7] = [2.0, 2.0, 1.0, 1.0, 0.1, 0.1, 0.01];

    fn baxter() -> Arc<Model> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/baxter_left_arm.urdf"
        );
        Arc::new(Model::from_urdf_file(path.as_ref(), Some("base"), Some("left_hand")).unwrap())
    }

    /// Simulates the true arm (semi-implicit Euler with `sub` substeps per observer sample)
    /// under `tau = G(q) - Kd qdot + 2 sin(...)` (a moving arm) plus `tau_ext`, feeding the
    /// observer the exact state; returns (time, estimate) per sample.
    fn simulate(
        truth: &Model,
        obs: &mut MomentumObserver,
        tau_ext: &[f64],
        ext_start: f64,
        duration: f64,
    ) -> Vec<(f64, Vec<f64>)> {
        simulate_sampled(truth, obs, tau_ext, ext_start, duration, 1e-3)
    }

    /// [`simulate`] with the observer sampled every `dt` (20 substeps of the arm each).
    fn simulate_sampled(
        truth: &Model,
        obs: &mut MomentumObserver,
        tau_ext: &[f64],
        ext_start: f64,
        duration: f64,
        dt: f64,
    ) -> Vec<(f64, Vec<f64>)> {
        let n = truth.nq();
        let mut data = Data::new(truth);
        let mut q = vec![0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
        let mut v = vec![0.0; n];
        let sub = 20;
        let h = dt / sub as f64;
        let mut tau = vec![0.0; n];
        let mut total = vec![0.0; n];
        let mut est = vec![0.0; n];
        let mut out = Vec::new();
        let steps = (duration / dt).round() as usize;
        for k in 0..=steps {
            let t = k as f64 * dt;
            // The torque held over the period that just ended.
            let input = ObserverInput {
                time: t,
                q: &q,
                qdot: &v,
                qddot: &v,
                tau_commanded: &tau,
            };
            let status = obs.update(&input, dt, &mut est);
            assert!(status.is_ok(), "t = {t}: {status:?}");
            out.push((t, est.clone()));
            // Next period's command: gravity compensation, damping and a moving excitation.
            let g = gravity_torque(truth, &mut data, &q).unwrap().clone();
            for i in 0..n {
                tau[i] = g[i] - DAMPING[i] * v[i] + EXCITATION[i] * (2.0 * t + i as f64).sin();
            }
            let on = t >= ext_start;
            for i in 0..n {
                total[i] = tau[i] + if on { tau_ext[i] } else { 0.0 };
            }
            for _ in 0..sub {
                let a = aba(truth, &mut data, &q, &v, &total).unwrap().clone();
                for i in 0..n {
                    v[i] += a[i] * h;
                    q[i] += v[i] * h;
                }
            }
        }
        out
    }

    #[test]
    fn zero_in_free_motion_with_an_exact_model() {
        let model = baxter();
        let mut obs =
            MomentumObserver::new(model.clone(), &MomentumObserverConfig::default()).unwrap();
        let out = simulate(&model, &mut obs, &[0.0; 7], f64::INFINITY, 3.0);
        let worst = out
            .iter()
            .flat_map(|(_, e)| e.iter().map(|x| x.abs()))
            .fold(0.0, f64::max);
        assert!(worst < 0.02, "free-motion estimate up to {worst} N m");
    }

    #[test]
    fn stays_stable_when_the_gain_is_faster_than_the_samples() {
        // 20 Hz samples and the default 50 /s: K_O dt = 2.5, where the explicit update
        // grows by 1.5 times a step; the gain is taken as 1 / dt instead.
        let model = baxter();
        let mut obs =
            MomentumObserver::new(model.clone(), &MomentumObserverConfig::default()).unwrap();
        let tau_ext = [1.0, -2.0, 0.5, 1.5, -0.5, 0.3, 0.2];
        let out = simulate_sampled(&model, &mut obs, &tau_ext, 1.0, 3.0, 0.05);
        for (t, e) in out.iter().filter(|(t, _)| *t >= 1.5) {
            for (i, (x, truth)) in e.iter().zip(&tau_ext).enumerate() {
                assert!(
                    (x - truth).abs() < 0.1 * truth.abs() + 0.05,
                    "t = {t}: joint {i} estimates {x} N m of {truth}"
                );
            }
        }
    }

    #[test]
    fn converges_to_a_constant_external_torque_with_the_gain_time_constant() {
        let model = baxter();
        let gain = 40.0;
        let cfg = MomentumObserverConfig {
            gain: JointValues::Uniform(gain),
        };
        let mut obs = MomentumObserver::new(model.clone(), &cfg).unwrap();
        let ext = [1.0, -2.0, 0.5, 1.0, -0.1, 0.05, 0.01];
        let start = 1.0;
        let out = simulate(&model, &mut obs, &ext, start, 1.5);
        // After one time constant: 1 - exp(-1) of the step; after 10: the step.
        let tau_c = 1.0 / gain;
        let at = |t: f64| &out.iter().find(|(s, _)| *s >= t - 1e-9).unwrap().1;
        let one = at(start + tau_c);
        let settled = at(start + 10.0 * tau_c);
        for i in 0..7 {
            let expected = ext[i] * (1.0 - (-1.0f64).exp());
            assert!(
                (one[i] - expected).abs() < 0.05 * ext[i].abs() + 0.005,
                "joint {i}: {} vs {expected}",
                one[i]
            );
            assert!(
                (settled[i] - ext[i]).abs() < 0.01 * ext[i].abs() + 0.005,
                "joint {i}: {} vs {}",
                settled[i],
                ext[i]
            );
        }
    }

    #[test]
    fn restarts_after_a_fault_and_rejects_bad_gains() {
        let model = baxter();
        assert!(MomentumObserver::new(
            model.clone(),
            &MomentumObserverConfig {
                gain: JointValues::Uniform(-1.0)
            }
        )
        .is_err());
        assert!(MomentumObserver::new(
            model.clone(),
            &MomentumObserverConfig {
                gain: JointValues::PerJoint(vec![1.0; 3])
            }
        )
        .is_err());
        let mut obs = MomentumObserver::new(model, &MomentumObserverConfig::default()).unwrap();
        let q = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];
        let mut bad = q;
        bad[2] = f64::NAN;
        let z = [0.0; 7];
        let mut est = [1.0; 7];
        let status = obs.update(
            &ObserverInput {
                time: 0.0,
                q: &bad,
                qdot: &z,
                qddot: &z,
                tau_commanded: &z,
            },
            1e-3,
            &mut est,
        );
        assert!(matches!(
            status,
            StepStatus::Fault(Fault::NonFiniteMeasurement {
                argument: "q",
                joint: 2
            })
        ));
        assert_eq!(est, [0.0; 7]);
        assert!(obs
            .update(
                &ObserverInput {
                    time: 0.0,
                    q: &q,
                    qdot: &z,
                    qddot: &z,
                    tau_commanded: &z
                },
                1e-3,
                &mut est
            )
            .is_ok());
        assert_eq!(est, [0.0; 7]);
        let mut short = [0.0; 6];
        assert!(!obs
            .update(
                &ObserverInput {
                    time: 0.0,
                    q: &q,
                    qdot: &z,
                    qddot: &z,
                    tau_commanded: &z
                },
                1e-3,
                &mut short
            )
            .is_ok());
    }
}
