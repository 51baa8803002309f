//! The hybrid observer (beyond the paper; docs/method.md sections 5 and 7): the generalised
//! momentum observer on a nominal model, with a flat RBF network that supplies what the
//! nominal model misses.
//!
//! With the true arm `M q'' + C q' + G + F = tau + tau_ext` and a nominal model
//! `M_n, C_n, G_n`, the torque the nominal model cannot explain in free motion is
//!
//! ```text
//!     delta(q, q', q'') = tau - (M_n q'' + C_n q' + G_n)     (free motion: tau_ext = 0)
//!                       = (M - M_n) q'' + (C - C_n) q' + (G - G_n) + F
//! ```
//!
//! A network trained on free-motion data learns `delta_hat` (friction-shaped inputs help:
//! most of `delta` is joint friction). The momentum observer is then run on the nominal
//! model with the corrected torque `tau - delta_hat`, so that its residual converges to
//! `tau_ext` instead of `tau_ext - delta`:
//!
//! ```text
//!     r = K_O (M_n q' - integral(tau - delta_hat + C_n^T q' - G_n + r) dt - p0)
//! ```
//!
//! The network sees the same signals as in training (docs/outputs.md, "Free-motion
//! data"): the filtered angles, their derivatives and the filtered command, one sample late.

use admittance_learning::broad::{BroadModel, Workspace};

use crate::error::{ConfigError, Fault, StepStatus};
use crate::momentum::MomentumObserver;
use crate::observer::{Observer, ObserverInput};
use crate::safe_hold::first_non_finite;

/// Momentum observer plus a learned model-error correction. Allocation-free per update.
#[derive(Clone, Debug)]
pub struct HybridObserver {
    momentum: MomentumObserver,
    residual: BroadModel,
    ws: Workspace,
    n: usize,
    x: Vec<f64>,
    delta_hat: Vec<f64>,
    corrected_tau: Vec<f64>,
    coverage: f64,
}

impl HybridObserver {
    /// `residual` maps `[q, q', q'']` (3n inputs) to `delta` (n outputs) of the momentum
    /// observer's nominal model.
    pub fn new(momentum: MomentumObserver, residual: BroadModel) -> Result<Self, ConfigError> {
        let n = momentum.dof();
        if residual.d_out() != n || residual.d_in() != 3 * n {
            return Err(ConfigError::new(
                "model",
                format!(
                    "has {} inputs and {} outputs; the hybrid observer of a {n}-joint arm needs [q, qdot, qddot] -> delta ({} inputs, {n} outputs)",
                    residual.d_in(),
                    residual.d_out(),
                    3 * n
                ),
            ));
        }
        let ws = residual.workspace();
        Ok(HybridObserver {
            momentum,
            residual,
            ws,
            n,
            x: vec![0.0; 3 * n],
            delta_hat: vec![0.0; n],
            corrected_tau: vec![0.0; n],
            coverage: 1.0,
        })
    }

    /// How well the last input lies inside the residual network's training data, in
    /// [0, 1] (`BroadModel::coverage`): 1 inside, falling to 0 away from every centre. The
    /// correction is faded by it, so outside its data the hybrid is the momentum observer.
    pub fn coverage(&self) -> f64 {
        self.coverage
    }

    /// The residual network.
    pub fn residual_model(&self) -> &BroadModel {
        &self.residual
    }

    /// The last correction `delta_hat`.
    pub fn delta_hat(&self) -> &[f64] {
        &self.delta_hat
    }

    fn correct(&mut self, input: &ObserverInput) -> Result<(), Fault> {
        let n = self.n;
        for (argument, v) in [
            ("q", input.q),
            ("qdot", input.qdot),
            ("qddot", input.qddot),
            ("tau_commanded", input.tau_commanded),
        ] {
            if v.len() != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found: v.len(),
                });
            }
            if let Some(joint) = first_non_finite(v) {
                return Err(Fault::NonFiniteMeasurement { argument, joint });
            }
        }
        self.x[..n].copy_from_slice(input.q);
        self.x[n..2 * n].copy_from_slice(input.qdot);
        self.x[2 * n..].copy_from_slice(input.qddot);
        // Faded to zero outside the training data (a network without a recorded coverage
        // threshold predicts as it always did).
        self.coverage = self
            .residual
            .predict_faded_into(&self.x, &mut self.delta_hat, &mut self.ws)
            .map_err(|_| Fault::Internal("hybrid observer: prediction"))?;
        for i in 0..n {
            let c = input.tau_commanded[i] - self.delta_hat[i];
            if !c.is_finite() {
                return Err(Fault::NonFiniteEstimate { joint: i });
            }
            self.corrected_tau[i] = c;
        }
        Ok(())
    }
}

impl Observer for HybridObserver {
    fn name(&self) -> &str {
        "hybrid"
    }
    fn dof(&self) -> usize {
        self.n
    }
    /// On a fault the estimate is zero and the momentum part restarts at the next valid
    /// sample (as [`MomentumObserver`] does).
    fn update(&mut self, input: &ObserverInput, dt: f64, estimate: &mut [f64]) -> StepStatus {
        if let Err(f) = self.correct(input) {
            estimate.fill(0.0);
            self.momentum.reset();
            return StepStatus::Fault(f);
        }
        let corrected = ObserverInput {
            tau_commanded: &self.corrected_tau,
            ..*input
        };
        self.momentum.update(&corrected, dt, estimate)
    }
    fn coverage(&self) -> Option<f64> {
        Some(self.coverage)
    }
    fn reset(&mut self) {
        self.momentum.reset();
        self.delta_hat.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MomentumObserverConfig;
    use admittance_dynamics::{rnea, Data, Model};
    use admittance_learning::broad::{fit, BroadConfig, Dataset, FrictionFeatures};
    use std::sync::Arc;

    const URDF: &str = r#"<robot name="two">
      <link name="base"/>
      <link name="l1"><inertial><origin xyz="0.2 0 0"/><mass value="2"/>
        <inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="l2"><inertial><origin xyz="0.15 0 0"/><mass value="1"/>
        <inertia ixx="0.005" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
        <axis xyz="0 1 0"/><limit effort="100" velocity="5" lower="-3" upper="3"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
        <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/><limit effort="100" velocity="5" lower="-3" upper="3"/></joint>
    </robot>"#;

    /// A residual the network's linear part and friction columns represent well: viscous
    /// and Coulomb friction (the usual unknowns of a nominal model).
    fn friction(qdot: &[f64]) -> [f64; 2] {
        [
            0.3 * qdot[0] + 0.5 * (qdot[0] / 0.01).tanh(),
            0.1 * qdot[1] + 0.2 * (qdot[1] / 0.01).tanh(),
        ]
    }

    #[test]
    fn corrected_momentum_observer_removes_learned_friction() {
        let model = Arc::new(Model::from_urdf_str(URDF, "two", None, None).unwrap());
        let mut data = Data::new(&model);
        // Free-motion samples: tau = RNEA(q, qdot, qddot) + friction; the residual of the
        // (exact) nominal model is the friction.
        let mut inputs = Vec::new();
        let mut targets = Vec::new();
        for k in 0..3000 {
            let t = k as f64 * 0.01;
            let x = [
                0.5 * (0.7 * t).sin(),
                0.4 * (1.1 * t).cos(),
                0.35 * (0.7 * t).cos(),
                -0.44 * (1.1 * t).sin(),
                -0.245 * (0.7 * t).sin(),
                -0.484 * (1.1 * t).cos(),
            ];
            inputs.extend_from_slice(&x);
            targets.extend_from_slice(&friction(&x[2..4]));
        }
        let train = Dataset::new(&inputs, &targets, 6, 2).unwrap();
        let config = BroadConfig {
            nodes: 20,
            friction: FrictionFeatures {
                columns: vec![2, 3],
                scales: vec![0.01],
            },
            centre_subsample: 500,
            lambda_grid: vec![1e-9],
            threads: 1,
            ..BroadConfig::default()
        };
        let (net, _) = fit(&train, None, &config).unwrap();
        let momentum = MomentumObserver::new(
            model.clone(),
            &MomentumObserverConfig {
                gain: crate::JointValues::Uniform(50.0),
            },
        )
        .unwrap();
        let mut plain = momentum.clone();
        let mut hybrid = HybridObserver::new(momentum, net).unwrap();
        // Free motion along the same path: the plain observer reads the friction as an
        // external torque, the hybrid one does not.
        let dt = 1e-3;
        let mut est_plain = [0.0; 2];
        let mut est_hybrid = [0.0; 2];
        let (mut err_plain, mut err_hybrid) = (0.0f64, 0.0f64);
        for k in 0..4000 {
            let t = k as f64 * dt;
            let q = [0.5 * (0.7 * t).sin(), 0.4 * (1.1 * t).cos()];
            let qd = [0.35 * (0.7 * t).cos(), -0.44 * (1.1 * t).sin()];
            let qdd = [-0.245 * (0.7 * t).sin(), -0.484 * (1.1 * t).cos()];
            let mut tau: Vec<f64> = rnea(&model, &mut data, &q, &qd, &qdd)
                .unwrap()
                .iter()
                .copied()
                .collect();
            let f = friction(&qd);
            tau[0] += f[0];
            tau[1] += f[1];
            let input = ObserverInput {
                time: t,
                q: &q,
                qdot: &qd,
                qddot: &qdd,
                tau_commanded: &tau,
            };
            assert!(plain.update(&input, dt, &mut est_plain).is_ok());
            assert!(hybrid.update(&input, dt, &mut est_hybrid).is_ok());
            if t > 1.0 {
                err_plain = err_plain.max(est_plain[0].abs());
                err_hybrid = err_hybrid.max(est_hybrid[0].abs());
            }
        }
        assert!(err_plain > 0.3, "plain observer sees friction: {err_plain}");
        assert!(
            err_hybrid < 0.2 * err_plain,
            "hybrid {err_hybrid} vs plain {err_plain}"
        );
    }

    #[test]
    fn non_finite_input_is_a_fault_with_zero_estimate() {
        let model = Arc::new(Model::from_urdf_str(URDF, "two", None, None).unwrap());
        let inputs: Vec<f64> = (0..60).map(|k| (k as f64 * 0.37).sin()).collect();
        let targets: Vec<f64> = (0..20).map(|k| (k as f64 * 0.11).cos()).collect();
        let train = Dataset::new(&inputs, &targets, 6, 2).unwrap();
        let config = BroadConfig {
            nodes: 3,
            friction: FrictionFeatures::none(),
            centre_subsample: 10,
            lambda_grid: vec![1e-6],
            threads: 1,
            ..BroadConfig::default()
        };
        let (net, _) = fit(&train, None, &config).unwrap();
        let momentum = MomentumObserver::new(model, &MomentumObserverConfig::default()).unwrap();
        let mut hybrid = HybridObserver::new(momentum, net).unwrap();
        let mut est = [1.0; 2];
        let input = ObserverInput {
            time: 0.0,
            q: &[0.0, f64::NAN],
            qdot: &[0.0; 2],
            qddot: &[0.0; 2],
            tau_commanded: &[0.0; 2],
        };
        assert!(!hybrid.update(&input, 1e-3, &mut est).is_ok());
        assert_eq!(est, [0.0; 2]);
    }
}
