//! The learned sensorless observer (docs/method.md section 5, the paper's eq. 19): a flat
//! ("broad") RBF network trained on free-motion data predicts the free-motion torque
//! `f_hat(q, q', q'')`; in contact the difference to the applied torque is the external
//! torque,
//!
//! ```text
//!     tau_ext_hat = LP( f_hat(q, q', q'') - tau )
//! ```
//!
//! (docs/method.md section 0 sign: with `M q'' + C q' + G + F = tau + tau_ext`, the free-motion
//! torque is `f = M q'' + C q' + G + F`, so `f - tau = tau_ext`). `LP` is a first-order
//! low-pass (docs/method.md section 7: the acceleration is noisy). The network's input is the raw
//! `[q, q', q'']` (it standardises internally); `tau` must be the torque signal the training
//! data used (docs/outputs.md, "Free-motion data": the filtered command, one sample late).

use admittance_learning::broad::{BroadModel, Workspace};

use crate::error::{ConfigError, Fault, StepStatus};
use crate::observer::{Observer, ObserverInput};
use crate::safe_hold::first_non_finite;

/// The learned observer of eq. 19. Allocation-free per update.
#[derive(Clone, Debug)]
pub struct LearnedObserver {
    model: BroadModel,
    ws: Workspace,
    n: usize,
    cutoff_hz: f64,
    x: Vec<f64>,
    f_hat: Vec<f64>,
    estimate: Vec<f64>,
    started: bool,
}

impl LearnedObserver {
    /// An observer on a trained network with inputs `[q, q', q'']` (3n) and outputs the n
    /// joint torques; `cutoff_hz` is the low-pass cut-off of the estimate (0: none).
    pub fn new(model: BroadModel, cutoff_hz: f64) -> Result<Self, ConfigError> {
        let n = model.d_out();
        if n == 0 || model.d_in() != 3 * n {
            return Err(ConfigError::new(
                "model",
                format!("has {} inputs and {} outputs; the observer needs [q, qdot, qddot] -> tau (3n inputs, n outputs)", model.d_in(), n),
            ));
        }
        if !(cutoff_hz.is_finite() && cutoff_hz >= 0.0) {
            return Err(ConfigError::new(
                "cutoff_hz",
                format!("is {cutoff_hz}, must be >= 0 (0: no filter)"),
            ));
        }
        let ws = model.workspace();
        Ok(LearnedObserver {
            model,
            ws,
            n,
            cutoff_hz,
            x: vec![0.0; 3 * n],
            f_hat: vec![0.0; n],
            estimate: vec![0.0; n],
            started: false,
        })
    }

    /// The network.
    pub fn model(&self) -> &BroadModel {
        &self.model
    }

    /// The last unfiltered network output `f_hat(q, q', q'')`.
    pub fn f_hat(&self) -> &[f64] {
        &self.f_hat
    }

    fn step(&mut self, input: &ObserverInput, dt: f64, estimate: &mut [f64]) -> Result<(), Fault> {
        let n = self.n;
        for (argument, v) in [
            ("q", input.q),
            ("qdot", input.qdot),
            ("qddot", input.qddot),
            ("tau_commanded", input.tau_commanded),
            ("estimate", &*estimate),
        ] {
            if v.len() != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        for (argument, v) in [
            ("q", input.q),
            ("qdot", input.qdot),
            ("qddot", input.qddot),
            ("tau_commanded", input.tau_commanded),
        ] {
            if let Some(joint) = first_non_finite(v) {
                return Err(Fault::NonFiniteMeasurement { argument, joint });
            }
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Fault::InvalidTimeStep);
        }
        self.x[..n].copy_from_slice(input.q);
        self.x[n..2 * n].copy_from_slice(input.qdot);
        self.x[2 * n..].copy_from_slice(input.qddot);
        self.model
            .predict_into(&self.x, &mut self.f_hat, &mut self.ws)
            .map_err(|_| Fault::Internal("learned observer: prediction"))?;
        let alpha = if self.cutoff_hz > 0.0 {
            dt / (dt + 1.0 / (std::f64::consts::TAU * self.cutoff_hz))
        } else {
            1.0
        };
        for i in 0..n {
            let raw = self.f_hat[i] - input.tau_commanded[i];
            if !raw.is_finite() {
                return Err(Fault::NonFiniteEstimate { joint: i });
            }
            // The filter starts at the first raw value (no transient from zero).
            self.estimate[i] = if self.started {
                self.estimate[i] + alpha * (raw - self.estimate[i])
            } else {
                raw
            };
        }
        self.started = true;
        estimate.copy_from_slice(&self.estimate);
        Ok(())
    }
}

impl Observer for LearnedObserver {
    fn name(&self) -> &str {
        "learned"
    }
    fn dof(&self) -> usize {
        self.n
    }
    fn update(&mut self, input: &ObserverInput, dt: f64, estimate: &mut [f64]) -> StepStatus {
        match self.step(input, dt, estimate) {
            Ok(()) => StepStatus::Ok,
            Err(f) => {
                estimate.fill(0.0);
                StepStatus::Fault(f)
            }
        }
    }
    fn reset(&mut self) {
        self.started = false;
        self.estimate.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admittance_learning::broad::{fit, BroadConfig, Dataset, FrictionFeatures};

    const N: usize = 2;

    /// A free-motion torque the network's linear part represents exactly.
    fn tau_free(x: &[f64]) -> [f64; N] {
        [
            1.0 + 2.0 * x[0] - 0.5 * x[2] + 0.3 * x[4],
            -0.7 + x[1] + 0.2 * x[3] + 0.05 * x[5],
        ]
    }

    fn trained() -> BroadModel {
        let rows = 400;
        let mut inputs = Vec::new();
        let mut targets = Vec::new();
        let mut state: u64 = 12345;
        for _ in 0..rows {
            let mut x = [0.0; 3 * N];
            for v in x.iter_mut() {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *v = (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            }
            inputs.extend_from_slice(&x);
            targets.extend_from_slice(&tau_free(&x));
        }
        let data = Dataset::new(&inputs, &targets, 3 * N, N).unwrap();
        let config = BroadConfig {
            nodes: 10,
            friction: FrictionFeatures::none(),
            centre_subsample: 200,
            lambda_grid: vec![1e-12],
            threads: 1,
            ..BroadConfig::default()
        };
        fit(&data, None, &config).unwrap().0
    }

    #[test]
    fn estimate_is_f_hat_minus_tau_and_is_low_passed() {
        let mut obs = LearnedObserver::new(trained(), 0.0).unwrap();
        let (q, qd, qdd) = ([0.2, 0.5], [0.1, -0.3], [0.4, 0.2]);
        let x = [q[0], q[1], qd[0], qd[1], qdd[0], qdd[1]];
        let f = tau_free(&x);
        // In free motion tau = f: zero estimate; with a contact torque e: tau = f - e.
        let ext = [0.8, -0.25];
        let tau = [f[0] - ext[0], f[1] - ext[1]];
        let mut est = [0.0; N];
        assert!(obs
            .update(
                &ObserverInput {
                    time: 0.0,
                    q: &q,
                    qdot: &qd,
                    qddot: &qdd,
                    tau_commanded: &tau
                },
                1e-3,
                &mut est
            )
            .is_ok());
        for i in 0..N {
            assert!(
                (est[i] - ext[i]).abs() < 1e-4,
                "joint {i}: {} vs {}",
                est[i],
                ext[i]
            );
        }
        // Low-pass: a step of the true torque reaches 1 - exp(-1) after one time constant.
        let fc = 5.0;
        let mut obs = LearnedObserver::new(trained(), fc).unwrap();
        let dt = 1e-4;
        let _ = obs.update(
            &ObserverInput {
                time: 0.0,
                q: &q,
                qdot: &qd,
                qddot: &qdd,
                tau_commanded: &f,
            },
            dt,
            &mut est,
        );
        assert!(est.iter().all(|e| e.abs() < 1e-4));
        let steps = (1.0 / (std::f64::consts::TAU * fc) / dt).round() as usize;
        for _ in 0..steps {
            let _ = obs.update(
                &ObserverInput {
                    time: 0.0,
                    q: &q,
                    qdot: &qd,
                    qddot: &qdd,
                    tau_commanded: &tau,
                },
                dt,
                &mut est,
            );
        }
        for i in 0..N {
            let expected = ext[i] * (1.0 - (-1.0f64).exp());
            assert!(
                (est[i] - expected).abs() < 0.01 * ext[i].abs(),
                "joint {i}: {} vs {expected}",
                est[i]
            );
        }
    }

    #[test]
    fn faults_and_bad_configuration() {
        assert!(LearnedObserver::new(trained(), -1.0).is_err());
        let mut obs = LearnedObserver::new(trained(), 0.0).unwrap();
        let z = [0.0; N];
        let nan = [0.0, f64::NAN];
        let mut est = [1.0; N];
        let s = obs.update(
            &ObserverInput {
                time: 0.0,
                q: &z,
                qdot: &z,
                qddot: &nan,
                tau_commanded: &z,
            },
            1e-3,
            &mut est,
        );
        assert!(matches!(
            s,
            StepStatus::Fault(Fault::NonFiniteMeasurement {
                argument: "qddot",
                joint: 1
            })
        ));
        assert_eq!(est, [0.0; N]);
        let mut short = [0.0; 1];
        assert!(!obs
            .update(
                &ObserverInput {
                    time: 0.0,
                    q: &z,
                    qdot: &z,
                    qddot: &z,
                    tau_commanded: &z
                },
                1e-3,
                &mut short
            )
            .is_ok());
        assert!(!obs
            .update(
                &ObserverInput {
                    time: 0.0,
                    q: &z,
                    qdot: &z,
                    qddot: &z,
                    tau_commanded: &z
                },
                0.0,
                &mut est
            )
            .is_ok());
        assert!(obs
            .update(
                &ObserverInput {
                    time: 0.0,
                    q: &z,
                    qdot: &z,
                    qddot: &z,
                    tau_commanded: &z
                },
                1e-3,
                &mut est
            )
            .is_ok());
    }
}
