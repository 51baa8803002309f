//! The neural controller: construction, the state it exposes, the law of docs/method.md
//! section 3 and the [`Controller`] step with its safe hold.

use std::sync::Arc;

use admittance_dynamics::Model;
use admittance_learning::rbf::GaussianRbfLayer;

use super::config::{FNetworkConfig, NeuralControllerConfig};
use super::deadzone_inverse::DeadzoneInverse;
use super::networks::{
    build_layer, fill_zf, mat_vec_add, outer, run_layer, FNet, F_RANGES, T_RANGES,
};
use super::nodes::GrowthState;
use crate::config::Bound;
use crate::controller::{ControlInput, Controller};
use crate::error::{ConfigError, Fault, StepStatus};
use crate::safe_hold::SafeHold;

/// The paper's adaptive neural controller (the exact law and update laws are in the
/// documentation of `src/neural/mod.rs`).
///
/// Faults (see [`SafeHold`]): the hold is written, the weights, relevance and growth are
/// not touched (adaptation frozen), and `tau_prev` (the deadzone network's input) becomes
/// the hold torque that was commanded. A law output that is not finite is also a fault;
/// a network whose weights are then no longer finite is zeroed.
///
/// Sizing note: `Gamma ||S(Z)||^2` acts as an integral gain on `e2`; with wide nodes (the
/// default width) `||S||^2` is tens along a trajectory. With the joint inertia `M_i` the
/// adaptive loop rings near `sqrt(Gamma ||S||^2 / M_i)` rad/s with damping ratio
/// `K2 / (2 sqrt(Gamma ||S||^2 M_i))`; and the `K2 e2` term alone needs `K2 dt / M_i < 2`
/// in a loop of period `dt` (Baxter's w2, `M ~ 6e-4 kg m^2`, is unstable with the paper's
/// `K2 = 6` at 1 kHz unless the plant adds reflected rotor inertia or `K2` is lowered on
/// that joint).
#[derive(Clone, Debug)]
pub struct NeuralController {
    pub(super) name: &'static str,
    pub(super) n: usize,
    pub(super) k1: Vec<f64>,
    pub(super) k2: Vec<f64>,
    pub(super) f: FNet,
    pub(super) t: Option<GaussianRbfLayer>,
    pub(super) inverse: Option<DeadzoneInverse>,
    pub(super) initial_f: FNet,
    pub(super) initial_t: Option<GaussianRbfLayer>,
    pub(super) hold: SafeHold,
    pub(super) adaptation: bool,
    pub(super) initial_adaptation: bool,
    pub(super) track_relevance: bool,
    pub(super) growth: [GrowthState; 5],
    // Per-step buffers.
    pub(super) e1: Vec<f64>,
    pub(super) e2: Vec<f64>,
    pub(super) alpha: Vec<f64>,
    pub(super) alpha_dot: Vec<f64>,
    pub(super) f_hat: Vec<f64>,
    pub(super) dtau_hat: Vec<f64>,
    pub(super) dz_inverse: Vec<f64>,
    pub(super) dz_demand: Vec<f64>,
    pub(super) tau_prev: Vec<f64>,
    pub(super) z_f: Vec<f64>,
    pub(super) z_t: Vec<f64>,
    pub(super) z_c: Vec<f64>,
    pub(super) z_pred: Vec<f64>,
    pub(super) mat: Vec<f64>,
    pub(super) err_mat: Vec<f64>,
    pub(super) steps: u64,
}

impl NeuralController {
    /// Builds the controller for `model` (used only by the [`SafeHold`]: the law is
    /// model-free) with `config`. Errors name the offending key (`"k1[2]"`,
    /// `"f.network.width"`, `"deadzone_network.theta"`, `"safe_hold.damping"`, ...).
    pub fn new(model: Arc<Model>, config: &NeuralControllerConfig) -> Result<Self, ConfigError> {
        let n = model.nq();
        if n == 0 {
            return Err(ConfigError::new("model", "has no moving joint"));
        }
        let k1 = config.k1.resolve("k1", n, Bound::Positive)?;
        let k2 = config.k2.resolve("k2", n, Bound::Positive)?;
        let f = match &config.f {
            FNetworkConfig::Lumped {
                include_e2,
                network,
            } => {
                let groups = if *include_e2 { 5 } else { 4 };
                let net = build_layer(network, n, &F_RANGES[..groups], n, 0.3)
                    .map_err(|e| e.within("f.network"))?;
                FNet::Lumped {
                    net,
                    include_e2: *include_e2,
                }
            }
            FNetworkConfig::Split { m, c, g } => FNet::Split {
                m: build_layer(m, n, &F_RANGES[..1], n * n, 0.3).map_err(|e| e.within("f.m"))?,
                c: build_layer(c, n, &F_RANGES[..2], n * n, 0.3).map_err(|e| e.within("f.c"))?,
                g: build_layer(g, n, &F_RANGES[..1], n, 0.3).map_err(|e| e.within("f.g"))?,
            },
        };
        let t = if config.deadzone_compensation {
            Some(
                build_layer(&config.deadzone_network, n, &T_RANGES, n, 0.125)
                    .map_err(|e| e.within("deadzone_network"))?,
            )
        } else {
            None
        };
        let inverse = match (&config.deadzone_inverse, config.deadzone_compensation) {
            (Some(cfg), true) => {
                Some(DeadzoneInverse::new(cfg, n).map_err(|e| e.within("deadzone_inverse"))?)
            }
            _ => None,
        };
        let hold = SafeHold::new(model, &config.safe_hold).map_err(|e| e.within("safe_hold"))?;
        let zf_len = match &f {
            FNet::Lumped { net, .. } => net.input_dim(),
            FNet::Split { .. } => 0,
        };
        Ok(NeuralController {
            name: if config.deadzone_compensation {
                "nn"
            } else {
                "nn_uncompensated"
            },
            n,
            k1,
            k2,
            initial_f: f.clone(),
            initial_t: t.clone(),
            f,
            t,
            inverse,
            hold,
            adaptation: config.adaptation,
            initial_adaptation: config.adaptation,
            track_relevance: config.track_relevance,
            growth: [GrowthState::default(); 5],
            e1: vec![0.0; n],
            e2: vec![0.0; n],
            alpha: vec![0.0; n],
            alpha_dot: vec![0.0; n],
            f_hat: vec![0.0; n],
            dtau_hat: vec![0.0; n],
            dz_inverse: vec![0.0; n],
            dz_demand: vec![0.0; n],
            tau_prev: vec![0.0; n],
            z_f: vec![0.0; zf_len],
            z_t: vec![0.0; 4 * n],
            z_c: vec![0.0; 2 * n],
            z_pred: vec![0.0; zf_len.max(2 * n)],
            mat: vec![0.0; n * n],
            err_mat: vec![0.0; n * n],
            steps: 0,
        })
    }

    // ---- state exposed for experiments A and C ---------------------------------------

    /// `f_hat` of the last step (N m).
    pub fn f_hat(&self) -> &[f64] {
        &self.f_hat
    }
    /// `Dtau_hat` of the last step (zeros when compensation is disabled).
    pub fn deadzone_estimate(&self) -> &[f64] {
        &self.dtau_hat
    }
    /// The structured deadzone inverse's term of the last step (included in
    /// [`deadzone_estimate`](Self::deadzone_estimate); zeros without it).
    pub fn deadzone_inverse_term(&self) -> &[f64] {
        &self.dz_inverse
    }
    /// The structured inverse's edge estimates `[d_r_hat_0, d_l_hat_0, d_r_hat_1, ...]`
    /// (`None` without it).
    pub fn deadzone_edges(&self) -> Option<&[f64]> {
        self.inverse.as_ref().map(|d| d.edges.as_slice())
    }
    /// `e1 = q_r - q` of the last step.
    pub fn e1(&self) -> &[f64] {
        &self.e1
    }
    /// `e2 = alpha - q'` of the last step.
    pub fn e2(&self) -> &[f64] {
        &self.e2
    }
    /// `alpha` of the last step.
    pub fn alpha(&self) -> &[f64] {
        &self.alpha
    }
    /// `alpha'` of the last step.
    pub fn alpha_dot(&self) -> &[f64] {
        &self.alpha_dot
    }
    /// The torque commanded at the last step (input of the deadzone network).
    pub fn last_torque(&self) -> &[f64] {
        &self.tau_prev
    }
    /// Gains `K1`.
    pub fn k1(&self) -> &[f64] {
        &self.k1
    }
    /// Gains `K2`.
    pub fn k2(&self) -> &[f64] {
        &self.k2
    }
    /// The safe hold (effort limits, fault counters).
    pub fn safe_hold(&self) -> &SafeHold {
        &self.hold
    }
    /// Whether the split M/C/G form is used.
    pub fn is_split(&self) -> bool {
        matches!(self.f, FNet::Split { .. })
    }
    /// Number of steps that ran the normal law since construction or reset.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Whether the weights adapt.
    pub fn adaptation_enabled(&self) -> bool {
        self.adaptation
    }
    /// Switches adaptation on or off (off: the weights are frozen, the law still runs).
    pub fn set_adaptation(&mut self, on: bool) {
        self.adaptation = on;
    }

    /// `f_hat` at an arbitrary point without changing any state (for measuring the
    /// approximation error along a recorded trajectory, docs/method.md section 6 C). `e2` is used
    /// only by a lumped network with `include_e2`. Does not allocate.
    pub fn predict_f(
        &mut self,
        q: &[f64],
        qdot: &[f64],
        alpha: &[f64],
        alpha_dot: &[f64],
        e2: &[f64],
        out: &mut [f64],
    ) -> Result<(), Fault> {
        let n = self.n;
        for (argument, v) in [
            ("q", q),
            ("qdot", qdot),
            ("alpha", alpha),
            ("alpha_dot", alpha_dot),
            ("e2", e2),
            ("out", &*out),
        ] {
            if v.len() != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        match &self.f {
            FNet::Lumped { net, include_e2 } => {
                fill_zf(&mut self.z_pred, q, qdot, alpha, alpha_dot, e2, *include_e2);
                net.predict(&self.z_pred, out)
                    .map_err(|_| Fault::Internal("f network prediction"))
            }
            FNet::Split { m, c, g } => {
                g.predict(q, out)
                    .map_err(|_| Fault::Internal("G network prediction"))?;
                m.predict(q, &mut self.mat)
                    .map_err(|_| Fault::Internal("M network prediction"))?;
                mat_vec_add(&self.mat, alpha_dot, out);
                self.z_pred[..n].copy_from_slice(q);
                self.z_pred[n..].copy_from_slice(qdot);
                c.predict(&self.z_pred, &mut self.mat)
                    .map_err(|_| Fault::Internal("C network prediction"))?;
                mat_vec_add(&self.mat, alpha, out);
                Ok(())
            }
        }
    }

    /// The current input `Z_f` of the lumped network (empty for the split form).
    pub fn f_input(&self) -> &[f64] {
        &self.z_f
    }

    /// The current input `Z_t` of the deadzone network.
    pub fn deadzone_input(&self) -> &[f64] {
        &self.z_t
    }

    fn law(&mut self, input: &ControlInput, dt: f64, torque: &mut [f64]) -> Result<(), Fault> {
        let n = self.n;
        for i in 0..n {
            self.e1[i] = input.q_ref[i] - input.q[i];
            self.alpha[i] = input.qdot_ref[i] + self.k1[i] * self.e1[i];
            self.e2[i] = self.alpha[i] - input.qdot[i];
            self.alpha_dot[i] =
                input.qddot_ref[i] + self.k1[i] * (input.qdot_ref[i] - input.qdot[i]);
        }
        let adapt = self.adaptation;
        match &mut self.f {
            FNet::Lumped { net, include_e2 } => {
                fill_zf(
                    &mut self.z_f,
                    input.q,
                    input.qdot,
                    &self.alpha,
                    &self.alpha_dot,
                    &self.e2,
                    *include_e2,
                );
                run_layer(
                    net,
                    &self.z_f,
                    &self.e2,
                    adapt,
                    dt,
                    &mut self.f_hat,
                    "f network",
                )?;
            }
            FNet::Split { m, c, g } => {
                // G: f_hat = G_hat(q)
                run_layer(
                    g,
                    input.q,
                    &self.e2,
                    adapt,
                    dt,
                    &mut self.f_hat,
                    "G network",
                )?;
                // M: f_hat += M_hat(q) alpha', error vec(e2 alpha'^T)
                outer(&self.e2, &self.alpha_dot, &mut self.err_mat);
                run_layer(
                    m,
                    input.q,
                    &self.err_mat,
                    adapt,
                    dt,
                    &mut self.mat,
                    "M network",
                )?;
                mat_vec_add(&self.mat, &self.alpha_dot, &mut self.f_hat);
                // C: f_hat += C_hat(q, q') alpha, error vec(e2 alpha^T)
                self.z_c[..n].copy_from_slice(input.q);
                self.z_c[n..].copy_from_slice(input.qdot);
                outer(&self.e2, &self.alpha, &mut self.err_mat);
                run_layer(
                    c,
                    &self.z_c,
                    &self.err_mat,
                    adapt,
                    dt,
                    &mut self.mat,
                    "C network",
                )?;
                mat_vec_add(&self.mat, &self.alpha, &mut self.f_hat);
            }
        }
        match &mut self.t {
            Some(t) => {
                self.z_t[..n].copy_from_slice(&self.tau_prev);
                self.z_t[n..2 * n].copy_from_slice(input.q);
                self.z_t[2 * n..3 * n].copy_from_slice(input.qdot);
                self.z_t[3 * n..].copy_from_slice(&self.e2);
                run_layer(
                    t,
                    &self.z_t,
                    &self.e2,
                    adapt,
                    dt,
                    &mut self.dtau_hat,
                    "deadzone network",
                )?;
            }
            None => self.dtau_hat.fill(0.0),
        }
        match &mut self.inverse {
            Some(inv) => {
                for i in 0..n {
                    self.dz_demand[i] =
                        self.f_hat[i] + self.k2[i] * self.e2[i] - input.external_torque_estimate[i];
                }
                inv.step(&self.dz_demand, &self.e2, adapt, dt, &mut self.dz_inverse);
                for (d, x) in self.dtau_hat.iter_mut().zip(&self.dz_inverse) {
                    *d += x;
                }
            }
            None => self.dz_inverse.fill(0.0),
        }
        for (i, t) in torque.iter_mut().enumerate() {
            *t = self.f_hat[i] + self.k2[i] * self.e2[i] + self.dtau_hat[i]
                - input.external_torque_estimate[i];
        }
        Ok(())
    }
}

impl Controller for NeuralController {
    fn name(&self) -> &str {
        self.name
    }

    fn dof(&self) -> usize {
        self.n
    }

    fn step(&mut self, input: &ControlInput, dt: f64, torque: &mut [f64]) -> StepStatus {
        if let Err(status) = self.hold.guard(input, dt, torque) {
            let k = self.n.min(torque.len());
            self.tau_prev[..k].copy_from_slice(&torque[..k]);
            return status;
        }
        let status = match self.law(input, dt, torque) {
            Ok(()) => self.hold.finish(input.qdot, torque),
            Err(fault) => self.hold.hold(fault, input.qdot, torque),
        };
        if status.is_ok() {
            self.steps += 1;
            self.after_step();
        } else {
            self.zero_non_finite_networks();
        }
        self.tau_prev.copy_from_slice(torque);
        status
    }

    fn reset(&mut self) {
        self.f.clone_from(&self.initial_f);
        self.t.clone_from(&self.initial_t);
        if let Some(inv) = &mut self.inverse {
            inv.edges.fill(0.0);
        }
        self.adaptation = self.initial_adaptation;
        self.growth = [GrowthState::default(); 5];
        self.hold.reset();
        for v in [
            &mut self.e1,
            &mut self.e2,
            &mut self.alpha,
            &mut self.alpha_dot,
            &mut self.f_hat,
            &mut self.dtau_hat,
            &mut self.dz_inverse,
            &mut self.dz_demand,
            &mut self.tau_prev,
            &mut self.z_f,
            &mut self.z_t,
        ] {
            v.fill(0.0);
        }
        self.steps = 0;
    }
}
