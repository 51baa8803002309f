//! The structured deadzone inverse of the neural controller (optional, beyond the paper).
//!
//! With [`NeuralControllerConfig::deadzone_inverse`](crate::NeuralControllerConfig::deadzone_inverse)
//! set (and compensation on), a second, structured term is added to `Dtau_hat`, the adaptive
//! deadzone inverse of the control literature (Tao and Kokotovic, IEEE TAC 1994, with a smooth switch as in Zhou, Wen and
//! Zhang, IEEE TAC 2006):
//!
//! ```text
//!     v        = f_hat + K2 e2 - tau_ext_hat          (the torque asked for before compensation)
//!     phi+_i   = (1 + tanh(v_i / eps)) / 2,  phi-_i = 1 - phi+_i
//!     Dtau_hat = W_t^T S_t(Z_t) + [d_r_hat_i phi+_i + d_l_hat_i phi-_i]_i
//!     d_r_hat' = Gamma_e (phi+ e2 - sigma_e d_r_hat),  d_l_hat' = Gamma_e (phi- e2 - sigma_e d_l_hat)
//! ```
//!
//! projected onto `0 <= d_r_hat_i <= b_i`, `-b_i <= d_l_hat_i <= 0` (`b_i` the configured
//! bound; 0 disables joint i). Why: with unit slopes the torque lost in docs/method.md's deadzone
//! is `Delta_tau(u) = sat(u; d_l, d_r)`, a function of the command alone with corners at the
//! edges; to make `D(u) = v` the command must *jump* the gap when `v` changes sign,
//! `u = v + d_r` for `v > 0` and `u = v + d_l` for `v < 0`. That is a step in `v` of height
//! `d_r - d_l`, linear in the unknown edges with the known regressors `phi+-`, so the same
//! Lyapunov argument as for `W_t` applies (docs/method.md section 3: the term enters `M e2'` as
//! `Dtau - Dtau_hat`, and the update is `Gamma (regressor e2 - sigma estimate)`), and
//! projection onto a convex set that holds the true edges keeps it. The paper's network cannot
//! draw that step: its Gaussian nodes are as wide as its 28-dimensional box (width about 22,
//! against the 0.98 N m gap) and it sees `tau_prev`, which already holds its own output. In
//! experiment A the lumped f network absorbs the mean offset `+-d` (as a function of the sign
//! of `alpha'`) in both variants, so what is left to win is the time spent crossing the gap;
//! this term removes most of it (figures in `scenarios/deadzone.toml`). `v` leaves out the
//! network's output, so there is no algebraic loop.

use serde::{Deserialize, Serialize};

use crate::config::{Bound, JointValues};
use crate::error::ConfigError;

fn default_inverse_smoothing() -> f64 {
    0.5
}
fn default_inverse_theta() -> f64 {
    1.0 / 30.0
}
fn default_inverse_sigma() -> f64 {
    0.001
}

/// The structured deadzone inverse added to `Dtau_hat` (see the documentation of
/// `src/neural/deadzone_inverse.rs`). Ignored when `deadzone_compensation` is false.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeadzoneInverseConfig {
    /// Prior bound `b_i >= 0` (N m) on the size of joint i's deadzone edges: the estimates
    /// stay in `0 <= d_r_hat <= b`, `-b <= d_l_hat <= 0`. 0 switches the inverse off on that
    /// joint (a joint known to have no deadzone: there the term would only add gain near
    /// `v = 0`). One value for all joints or one per joint.
    pub bound: JointValues,
    /// Width `eps > 0` (N m) of the smooth switch `tanh(v / eps)` (default 0.5: above the
    /// noise of `K2 e2`, below the gaps; it also bounds the extra gain
    /// `(d_r_hat - d_l_hat) / (2 eps)` that an overestimated edge adds around `v = 0`: in
    /// experiment A eps = 0.2 let the start-up transient push the edges past the paper's
    /// +-0.49 N m gap into a chattering limit cycle once `Gamma_e >= 100`, eps = 0.5 stayed
    /// clean up to `Gamma_e = 400`).
    #[serde(default = "default_inverse_smoothing")]
    pub smoothing: f64,
    /// `Theta_e = Gamma_e^-1 > 0` (default 1/30). The two regressors sum to 1, unlike the
    /// tens of `||S||^2` of a wide Gaussian network, so `Gamma_e` is larger than `Gamma_t`.
    #[serde(default = "default_inverse_theta")]
    pub theta: f64,
    /// Sigma-modification `sigma_e >= 0` (default 0.001, scaled like `Gamma_e` for
    /// regressors of unit size; 0.035 lets the f network take the whole offset back).
    #[serde(default = "default_inverse_sigma")]
    pub sigma: f64,
}

/// Run-time state of the structured deadzone inverse.
#[derive(Clone, Debug)]
pub(super) struct DeadzoneInverse {
    bound: Vec<f64>,
    eps: f64,
    gamma: f64,
    sigma: f64,
    /// `[d_r_hat_0, d_l_hat_0, d_r_hat_1, ...]`.
    pub(super) edges: Vec<f64>,
}

impl DeadzoneInverse {
    pub(super) fn new(cfg: &DeadzoneInverseConfig, n: usize) -> Result<Self, ConfigError> {
        Ok(DeadzoneInverse {
            bound: cfg.bound.resolve("bound", n, Bound::NonNegative)?,
            eps: Bound::Positive.check("smoothing", cfg.smoothing)?,
            gamma: 1.0 / Bound::Positive.check("theta", cfg.theta)?,
            sigma: Bound::NonNegative.check("sigma", cfg.sigma)?,
            edges: vec![0.0; 2 * n],
        })
    }

    /// Writes joint i's term (with the estimates before this step's update) to `out[i]`
    /// and, when `adapt`, updates the estimates over `dt` (Euler, then projection). A
    /// non-finite `v` or `e2` gives 0 and leaves the estimates alone.
    pub(super) fn step(&mut self, v: &[f64], e2: &[f64], adapt: bool, dt: f64, out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            let b = self.bound[i];
            if b == 0.0 || !(v[i].is_finite() && e2[i].is_finite()) {
                *o = 0.0;
                continue;
            }
            let pos = 0.5 * (1.0 + (v[i] / self.eps).tanh());
            let neg = 1.0 - pos;
            let (r, l) = (self.edges[2 * i], self.edges[2 * i + 1]);
            *o = r * pos + l * neg;
            if adapt {
                let g = self.gamma * dt;
                self.edges[2 * i] = (r + g * (pos * e2[i] - self.sigma * r)).clamp(0.0, b);
                self.edges[2 * i + 1] = (l + g * (neg * e2[i] - self.sigma * l)).clamp(-b, 0.0);
            }
        }
    }
}
