//! The paper's adaptive RBF neural controller with deadzone compensation (docs/method.md
//! section 3, the paper's eq. 24-27, with METHOD's sign set) and the dynamic-node hooks of
//! docs/method.md section 4.
//!
//! # Control law (implemented exactly)
//!
//! ```text
//!     e1     = q_r - q
//!     alpha  = q_r' + K1 e1
//!     e2     = alpha - q'                                  (= e1' + K1 e1)
//!     alpha' = q_r'' + K1 (q_r' - q')
//!     tau    = f_hat(Z_f) + K2 e2 + Dtau_hat(Z_t) - tau_ext_hat
//! ```
//!
//! then clamped to the effort limits. `f_hat` approximates
//! `f = M(q) alpha' + C(q, q') alpha + G(q)` (+ the friction the plant has):
//!
//! * **lumped** (default): `f_hat = W_f^T S_f(Z_f)`, `Z_f = [q, q', alpha, alpha']` (`4n`
//!   inputs), or `[q, q', alpha, alpha', e2]` (`5n`, the paper's input list) with
//!   `include_e2`;
//! * **split** (the paper's three networks): `f_hat = M_hat alpha' + C_hat alpha + G_hat` with
//!   `M_hat = reshape(W_M^T S_M(q))`, `C_hat = reshape(W_C^T S_C([q, q']))` (each an `n x n`
//!   matrix read row-major from a network with `n^2` outputs: output `i n + j` is entry
//!   `(i, j)`) and `G_hat = W_G^T S_G(q)` (`n` outputs).
//!
//! `Dtau_hat = W_t^T S_t(Z_t)`, `Z_t = [tau_prev, q, q', e2]` with `tau_prev` the torque
//! commanded at the previous step (after clamping); disabled by
//! [`NeuralControllerConfig::deadzone_compensation`] = false (the `nn_uncompensated`
//! variant).
//!
//! # Structured deadzone inverse (optional, beyond the paper)
//!
//! See `deadzone_inverse.rs`: an adaptive inverse of the deadzone added to `Dtau_hat` when
//! [`NeuralControllerConfig::deadzone_inverse`] is set.
//!
//! # Update laws (sigma-modification, the same sign for every network)
//!
//! ```text
//!     W_f' = Gamma_f (S_f(Z_f) e2^T              - sigma_f W_f)
//!     W_t' = Gamma_t (S_t(Z_t) e2^T              - sigma_t W_t)
//!     W_M' = Gamma_M (S_M(q) vec(e2 alpha'^T)^T   - sigma_M W_M)     (split form)
//!     W_C' = Gamma_C (S_C(q,q') vec(e2 alpha^T)^T - sigma_C W_C)
//!     W_G' = Gamma_G (S_G(q) e2^T                 - sigma_G W_G)
//! ```
//!
//! with `Gamma = Theta^-1` and `vec(e2 a^T)` the row-major flattening (entry `i n + j` is
//! `e2_i a_j`), i.e. the gradient of `e2^T f_hat` with respect to the weights. They make the
//! weight-error cross terms of `V = e2^T M e2 / 2 + sum tr(W~^T Theta W~) / 2` cancel
//! (docs/method.md section 3, "Derivation"; the paper's printed eq. 27 mixes signs and is not
//! used). The weights are integrated over each step with `S` and `e2` held (the RBF
//! layer's integrator, exact decay by default), using the weights before the update for the
//! output of the step.
//!
//! The controller is model-free except for [`SafeHold`](crate::SafeHold): no nominal-model
//! feedforward.
//!
//! # Rooms
//!
//! * `config.rs`: the serde configurations (networks, f form, controller);
//! * `networks.rs`: building the RBF layers and running them in the law;
//! * `controller.rs`: [`NeuralController`], its law and the `Controller` step;
//! * `nodes.rs`: the networks by identifier and the dynamic-node events (discard, grow);
//! * `deadzone_inverse.rs`: the structured deadzone inverse;
//! * `true_f.rs`: the true lumped function of a model (experiment C's reference).

mod config;
mod controller;
mod deadzone_inverse;
mod growth;
mod networks;
mod nodes;
mod true_f;

pub use config::{FNetworkConfig, NetworkConfig, NeuralControllerConfig};
pub use controller::NeuralController;
pub use deadzone_inverse::DeadzoneInverseConfig;
pub use nodes::{GrowthProgress, GrowthRequest, NetworkId};
pub use true_f::true_lumped_f;
