//! The paper's adaptive RBF neural controller with deadzone compensation (METHOD.md
//! section 3, the paper's eq. 24-27, with METHOD's sign set) and the dynamic-node hooks of
//! METHOD.md section 4.
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
//! With [`NeuralControllerConfig::deadzone_inverse`] set (and compensation on), a second,
//! structured term is added to `Dtau_hat`, the adaptive deadzone inverse of the control
//! literature (Tao and Kokotovic, IEEE TAC 1994, with a smooth switch as in Zhou, Wen and
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
//! bound; 0 disables joint i). Why: with unit slopes the torque lost in METHOD.md's deadzone
//! is `Delta_tau(u) = sat(u; d_l, d_r)`, a function of the command alone with corners at the
//! edges; to make `D(u) = v` the command must *jump* the gap when `v` changes sign,
//! `u = v + d_r` for `v > 0` and `u = v + d_l` for `v < 0`. That is a step in `v` of height
//! `d_r - d_l`, linear in the unknown edges with the known regressors `phi+-`, so the same
//! Lyapunov argument as for `W_t` applies (METHOD.md section 3: the term enters `M e2'` as
//! `Dtau - Dtau_hat`, and the update is `Gamma (regressor e2 - sigma estimate)`), and
//! projection onto a convex set that holds the true edges keeps it. The paper's network cannot
//! draw that step: its Gaussian nodes are as wide as its 28-dimensional box (width about 22,
//! against the 0.98 N m gap) and it sees `tau_prev`, which already holds its own output. In
//! experiment A the lumped f network absorbs the mean offset `+-d` (as a function of the sign
//! of `alpha'`) in both variants, so what is left to win is the time spent crossing the gap;
//! this term removes most of it (figures in `scenarios/deadzone.toml`). `v` leaves out the
//! network's output, so there is no algebraic loop.
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
//! (METHOD.md section 3, "Derivation"; the paper's printed eq. 27 mixes signs and is not
//! used). The weights are integrated over each step with `S` and `e2` held (the RBF
//! layer's integrator, exact decay by default), using the weights before the update for the
//! output of the step.
//!
//! The controller is model-free except for [`SafeHold`]: no nominal-model feedforward.

use std::sync::Arc;

use admittance_dynamics::{coriolis_matrix, crba, gravity_torque, Data, DimensionError, Model};
use admittance_learning::rbf::{
    GaussianRbfLayer, GrowOutcome, GrowthParams, Integrator, Placement, RbfConfigError,
    RbfLayerConfig,
};
use serde::{Deserialize, Serialize};

use crate::config::{Bound, JointValues};
use crate::controller::{ControlInput, Controller};
use crate::error::{ConfigError, Fault, StepStatus};
use crate::safe_hold::{SafeHold, SafeHoldConfig};

// ----------------------------------------------------------------------------------------
// Configuration
// ----------------------------------------------------------------------------------------

fn default_placement() -> Placement {
    Placement::Random {
        count: 512,
        seed: 1,
    }
}
fn default_sigma() -> f64 {
    0.035
}
fn default_window() -> usize {
    1000
}
fn default_min_activation() -> f64 {
    1e-16
}
fn default_max_neighbours() -> usize {
    16
}

/// One Gaussian RBF network of the controller (METHOD.md section 3: eq. 9 nodes; section 4:
/// dynamic nodes). Every field has a default, so a scenario sets only what it changes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetworkConfig {
    /// Initial centres: `{ kind = "random", count, seed }` (default: 512 nodes, seed 1),
    /// `{ kind = "lattice", points = [...] }` (one count per input *dimension*), or
    /// `{ kind = "explicit", centres = [[...], ...] }`. Random and lattice centres fill the
    /// box given by `ranges` (or `lower`/`upper`).
    pub placement: Placement,
    /// Width `eta` of every initial node (eq. 9). Default (`None`): the root-mean-square
    /// distance between two points drawn uniformly in the box,
    /// `sqrt(sum_k (hi_k - lo_k)^2 / 6)`, so that a typical input activates a typical node
    /// at about `exp(-1)` (in the `4n`- and `5n`-dimensional inputs of the paper the nodes
    /// are far apart and must be wide).
    pub width: Option<f64>,
    /// Capacity `L_max` (storage allocated once). Default: initial nodes + 128.
    pub capacity: Option<usize>,
    /// `Theta = Gamma^-1 > 0`. Default: 0.3 for the f networks (M, C, G, lumped), 0.125 for
    /// the deadzone network (the paper's experiment A); experiment C uses 0.03.
    pub theta: Option<f64>,
    /// Sigma-modification `sigma >= 0` (default 0.035, experiment C's value).
    pub sigma: f64,
    /// One `[lo, hi]` range per input *group* (applied to every joint of the group), in the
    /// network's input order. Defaults (the paper's Section IV-A): lumped f
    /// `[q, q', alpha, alpha', e2]`: `[-1.5,1.5], [-1.3,1.3], [-1.3,1.3], [-1.3,1.3], [-1,1]`
    /// (the last only with `include_e2`); deadzone `[tau_prev, q, q', e2]`: `[-10,10],
    /// [-1.3,1.3], [-1.5,1.5], [-1,1]`; split M and G `[q]`: `[-1.5,1.5]`; split C `[q, q']`:
    /// `[-1.5,1.5], [-1.3,1.3]`.
    pub ranges: Option<Vec<[f64; 2]>>,
    /// Per-dimension lower corner of the box (overrides `ranges`; needs `upper`).
    pub lower: Option<Vec<f64>>,
    /// Per-dimension upper corner of the box (overrides `ranges`; needs `lower`).
    pub upper: Option<Vec<f64>>,
    /// Weight integrator (`"exact_decay"`, default, or `"euler"`).
    pub integrator: Integrator,
    /// Relevance window (tracked steps) used by discard (METHOD.md section 4).
    pub relevance_window: usize,
    /// Activations below this are computed as zero (default 1e-16).
    pub min_activation: f64,
    /// Largest `m` accepted by growth.
    pub max_neighbours: usize,
    /// Growth parameters carried with the network (used by
    /// [`NeuralController::request_growth`] when the request gives none).
    pub growth: Option<GrowthParams>,
}

impl Default for NetworkConfig {
    fn default() -> Self {
        NetworkConfig {
            placement: default_placement(),
            width: None,
            capacity: None,
            theta: None,
            sigma: default_sigma(),
            ranges: None,
            lower: None,
            upper: None,
            integrator: Integrator::default(),
            relevance_window: default_window(),
            min_activation: default_min_activation(),
            max_neighbours: default_max_neighbours(),
            growth: None,
        }
    }
}

fn default_inverse_smoothing() -> f64 {
    0.5
}
fn default_inverse_theta() -> f64 {
    1.0 / 30.0
}
fn default_inverse_sigma() -> f64 {
    0.001
}

/// The structured deadzone inverse added to `Dtau_hat` (see the module documentation,
/// "Structured deadzone inverse"). Ignored when `deadzone_compensation` is false.
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
struct DeadzoneInverse {
    bound: Vec<f64>,
    eps: f64,
    gamma: f64,
    sigma: f64,
    /// `[d_r_hat_0, d_l_hat_0, d_r_hat_1, ...]`.
    edges: Vec<f64>,
}

impl DeadzoneInverse {
    fn new(cfg: &DeadzoneInverseConfig, n: usize) -> Result<Self, ConfigError> {
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
    fn step(&mut self, v: &[f64], e2: &[f64], adapt: bool, dt: f64, out: &mut [f64]) {
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

/// How `f = M alpha' + C alpha + G` is approximated (METHOD.md section 3).
#[allow(clippy::large_enum_variant)] // a configuration value, built once
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum FNetworkConfig {
    /// One network `f_hat = W_f^T S_f(Z_f)` (the default).
    Lumped {
        /// Append `e2` to `Z_f` (the paper's input list `[q, q', alpha, alpha', e2]`).
        #[serde(default)]
        include_e2: bool,
        /// The network.
        #[serde(default)]
        network: NetworkConfig,
    },
    /// Three networks `f_hat = M_hat(q) alpha' + C_hat(q, q') alpha + G_hat(q)`.
    Split {
        /// The inertia network (input `q`, `n^2` outputs).
        #[serde(default)]
        m: NetworkConfig,
        /// The Coriolis network (input `[q, q']`, `n^2` outputs).
        #[serde(default)]
        c: NetworkConfig,
        /// The gravity network (input `q`, `n` outputs).
        #[serde(default)]
        g: NetworkConfig,
    },
}

impl Default for FNetworkConfig {
    fn default() -> Self {
        FNetworkConfig::Lumped {
            include_e2: false,
            network: NetworkConfig::default(),
        }
    }
}

fn k1_default() -> JointValues {
    JointValues::Uniform(12.0)
}
fn k2_default() -> JointValues {
    JointValues::Uniform(6.0)
}
fn yes() -> bool {
    true
}

/// Configuration of [`NeuralController`] (METHOD.md section 3). Defaults are the paper's
/// experiment A: `K1 = 12`, `K2 = 6`, lumped f network with `Theta_f = 0.3`, deadzone
/// network with `Theta_t = 0.125`, 512 random nodes each, `sigma = 0.035`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NeuralControllerConfig {
    /// `K1 > 0` (1/s), per joint or one value.
    #[serde(default = "k1_default")]
    pub k1: JointValues,
    /// `K2 > 0` (N m s/rad), per joint or one value.
    #[serde(default = "k2_default")]
    pub k2: JointValues,
    /// The f network(s).
    #[serde(default)]
    pub f: FNetworkConfig,
    /// Whether the deadzone network `Dtau_hat` is used (false: `nn_uncompensated`).
    #[serde(default = "yes")]
    pub deadzone_compensation: bool,
    /// The deadzone network (ignored when `deadzone_compensation` is false).
    #[serde(default)]
    pub deadzone_network: NetworkConfig,
    /// The structured deadzone inverse added to the network (none by default, the paper's
    /// law; ignored when `deadzone_compensation` is false).
    #[serde(default)]
    pub deadzone_inverse: Option<DeadzoneInverseConfig>,
    /// Whether the weights adapt (can also be switched at run time).
    #[serde(default = "yes")]
    pub adaptation: bool,
    /// Whether node relevance is tracked every step (needed by discard).
    #[serde(default = "yes")]
    pub track_relevance: bool,
    /// The safe hold used on faults.
    #[serde(default)]
    pub safe_hold: SafeHoldConfig,
}

impl Default for NeuralControllerConfig {
    fn default() -> Self {
        NeuralControllerConfig {
            k1: k1_default(),
            k2: k2_default(),
            f: FNetworkConfig::default(),
            deadzone_compensation: true,
            deadzone_network: NetworkConfig::default(),
            deadzone_inverse: None,
            adaptation: true,
            track_relevance: true,
            safe_hold: SafeHoldConfig::default(),
        }
    }
}

/// The networks of a [`NeuralController`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NetworkId {
    /// The lumped f network.
    F,
    /// Split form: inertia network.
    M,
    /// Split form: Coriolis network.
    C,
    /// Split form: gravity network.
    G,
    /// The deadzone compensation network.
    Deadzone,
}

impl NetworkId {
    /// All identifiers, in a fixed order.
    pub const ALL: [NetworkId; 5] = [
        NetworkId::F,
        NetworkId::M,
        NetworkId::C,
        NetworkId::G,
        NetworkId::Deadzone,
    ];

    /// `"f"`, `"m"`, `"c"`, `"g"`, `"deadzone"`.
    pub fn as_str(&self) -> &'static str {
        match self {
            NetworkId::F => "f",
            NetworkId::M => "m",
            NetworkId::C => "c",
            NetworkId::G => "g",
            NetworkId::Deadzone => "deadzone",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// A request to grow nodes near the trajectory (METHOD.md section 4, "Grow").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrowthRequest {
    /// How many nodes to add in total.
    pub nodes: usize,
    /// Minimum number of control steps between two additions (spreads the new nodes along
    /// the trajectory); 1 = try every step.
    pub interval_steps: usize,
    /// Growth test (`m`, `Xi`, minimum spacing, placement on the segment). At each attempt a
    /// node is added at the network's current input iff the mean distance of its `m`
    /// nearest centres exceeds `Xi` and the spacing allows it (the RBF layer's
    /// `maybe_grow_at_last_input`).
    pub params: GrowthParams,
}

/// Progress of a growth request.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GrowthProgress {
    /// Nodes still to add.
    pub pending: usize,
    /// Nodes added since construction or reset.
    pub added: usize,
    /// Attempts that found the input already covered or too close to a centre.
    pub declined: usize,
}

#[derive(Clone, Copy, Debug, Default)]
struct GrowthState {
    request: Option<GrowthRequest>,
    since: usize,
    progress: GrowthProgress,
}

// ----------------------------------------------------------------------------------------
// Building networks
// ----------------------------------------------------------------------------------------

const F_RANGES: [[f64; 2]; 5] = [
    [-1.5, 1.5],
    [-1.3, 1.3],
    [-1.3, 1.3],
    [-1.3, 1.3],
    [-1.0, 1.0],
];
const T_RANGES: [[f64; 2]; 4] = [[-10.0, 10.0], [-1.3, 1.3], [-1.5, 1.5], [-1.0, 1.0]];

fn rbf_error_key(e: &RbfConfigError) -> &'static str {
    match e {
        RbfConfigError::BoxDimension { .. } | RbfConfigError::InvalidBox { .. } => "ranges",
        RbfConfigError::LatticeShape { .. } => "placement.points",
        RbfConfigError::TooManyNodes { .. } | RbfConfigError::EmptyShape { .. } => "capacity",
        RbfConfigError::InvalidCentre { .. } => "placement.centres",
        RbfConfigError::InvalidWidth(_) => "width",
        RbfConfigError::InvalidGain { name, .. } => {
            if *name == "sigma" {
                "sigma"
            } else {
                "theta"
            }
        }
        RbfConfigError::InvalidOption { name } => name,
        RbfConfigError::InvalidGrowth(_) => "growth",
    }
}

/// Builds one layer: `groups` input groups of `n` dimensions each, `outputs` outputs.
fn build_layer(
    cfg: &NetworkConfig,
    n: usize,
    default_ranges: &[[f64; 2]],
    outputs: usize,
    default_theta: f64,
) -> Result<GaussianRbfLayer, ConfigError> {
    let groups = default_ranges.len();
    let dim = groups * n;
    let (lower, upper) = match (&cfg.lower, &cfg.upper) {
        (Some(lo), Some(hi)) => {
            for (key, v) in [("lower", lo), ("upper", hi)] {
                if v.len() != dim {
                    return Err(ConfigError::new(
                        key,
                        format!("has {} values, the network has {dim} inputs ({groups} groups of {n} joints)", v.len()),
                    ));
                }
            }
            (lo.clone(), hi.clone())
        }
        (Some(_), None) => {
            return Err(ConfigError::new(
                "upper",
                "is missing: `lower` needs `upper`",
            ))
        }
        (None, Some(_)) => {
            return Err(ConfigError::new(
                "lower",
                "is missing: `upper` needs `lower`",
            ))
        }
        (None, None) => {
            let ranges: &[[f64; 2]] = cfg.ranges.as_deref().unwrap_or(default_ranges);
            if ranges.len() != groups {
                return Err(ConfigError::new(
                    "ranges",
                    format!("has {} ranges, the network has {groups} input groups (one [lo, hi] per group)", ranges.len()),
                ));
            }
            let mut lower = Vec::with_capacity(dim);
            let mut upper = Vec::with_capacity(dim);
            for (k, r) in ranges.iter().enumerate() {
                if !(r[0].is_finite() && r[1].is_finite() && r[0] <= r[1]) {
                    return Err(ConfigError::new(
                        format!("ranges[{k}]"),
                        format!("is [{}, {}], must be finite with lo <= hi", r[0], r[1]),
                    ));
                }
                lower.extend(std::iter::repeat_n(r[0], n));
                upper.extend(std::iter::repeat_n(r[1], n));
            }
            (lower, upper)
        }
    };
    for i in 0..dim {
        if !(lower[i].is_finite() && upper[i].is_finite() && lower[i] <= upper[i]) {
            return Err(ConfigError::new(
                format!("lower[{i}]"),
                format!(
                    "box [{}, {}] must be finite with lower <= upper",
                    lower[i], upper[i]
                ),
            ));
        }
    }
    let width = match cfg.width {
        Some(w) => Bound::Positive.check("width", w)?,
        None => {
            let s: f64 = lower
                .iter()
                .zip(&upper)
                .map(|(l, u)| (u - l) * (u - l))
                .sum::<f64>()
                / 6.0;
            if s > 0.0 {
                s.sqrt()
            } else {
                1.0
            }
        }
    };
    let theta = Bound::Positive.check("theta", cfg.theta.unwrap_or(default_theta))?;
    let sigma = Bound::NonNegative.check("sigma", cfg.sigma)?;
    let initial = match &cfg.placement {
        Placement::Random { count, .. } => *count,
        Placement::Lattice { points } => points
            .iter()
            .try_fold(1usize, |a, &p| a.checked_mul(p))
            .unwrap_or(usize::MAX),
        Placement::Explicit { centres } => centres.len(),
    };
    let capacity = match cfg.capacity {
        Some(c) => c,
        None => initial.saturating_add(128),
    };
    let layer_config = RbfLayerConfig {
        lower,
        upper,
        placement: cfg.placement.clone(),
        width,
        capacity,
        outputs,
        gamma: 1.0 / theta,
        sigma,
        integrator: cfg.integrator,
        relevance_window: cfg.relevance_window,
        min_activation: cfg.min_activation,
        max_neighbours: cfg.max_neighbours,
        growth: cfg.growth,
    };
    GaussianRbfLayer::from_config(&layer_config)
        .map_err(|e| ConfigError::new(rbf_error_key(&e), format!("{e}")))
}

#[allow(clippy::large_enum_variant)] // one per controller, never moved in the step
#[derive(Clone, Debug)]
enum FNet {
    Lumped {
        net: GaussianRbfLayer,
        include_e2: bool,
    },
    Split {
        m: GaussianRbfLayer,
        c: GaussianRbfLayer,
        g: GaussianRbfLayer,
    },
}

// ----------------------------------------------------------------------------------------
// The controller
// ----------------------------------------------------------------------------------------

/// The paper's adaptive neural controller (see the module documentation for the exact law
/// and update laws).
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
    name: &'static str,
    n: usize,
    k1: Vec<f64>,
    k2: Vec<f64>,
    f: FNet,
    t: Option<GaussianRbfLayer>,
    inverse: Option<DeadzoneInverse>,
    initial_f: FNet,
    initial_t: Option<GaussianRbfLayer>,
    hold: SafeHold,
    adaptation: bool,
    initial_adaptation: bool,
    track_relevance: bool,
    growth: [GrowthState; 5],
    // Per-step buffers.
    e1: Vec<f64>,
    e2: Vec<f64>,
    alpha: Vec<f64>,
    alpha_dot: Vec<f64>,
    f_hat: Vec<f64>,
    dtau_hat: Vec<f64>,
    dz_inverse: Vec<f64>,
    dz_demand: Vec<f64>,
    tau_prev: Vec<f64>,
    z_f: Vec<f64>,
    z_t: Vec<f64>,
    z_c: Vec<f64>,
    z_pred: Vec<f64>,
    mat: Vec<f64>,
    err_mat: Vec<f64>,
    steps: u64,
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

    /// The network `id`, if this controller has it.
    pub fn network(&self, id: NetworkId) -> Option<&GaussianRbfLayer> {
        match (&self.f, id) {
            (FNet::Lumped { net, .. }, NetworkId::F) => Some(net),
            (FNet::Split { m, .. }, NetworkId::M) => Some(m),
            (FNet::Split { c, .. }, NetworkId::C) => Some(c),
            (FNet::Split { g, .. }, NetworkId::G) => Some(g),
            (_, NetworkId::Deadzone) => self.t.as_ref(),
            _ => None,
        }
    }

    /// Mutable access to network `id` (e.g. to load weights). Changing its input dimension
    /// or output count is impossible through the layer's API; everything else is allowed.
    pub fn network_mut(&mut self, id: NetworkId) -> Option<&mut GaussianRbfLayer> {
        match (&mut self.f, id) {
            (FNet::Lumped { net, .. }, NetworkId::F) => Some(net),
            (FNet::Split { m, .. }, NetworkId::M) => Some(m),
            (FNet::Split { c, .. }, NetworkId::C) => Some(c),
            (FNet::Split { g, .. }, NetworkId::G) => Some(g),
            (_, NetworkId::Deadzone) => self.t.as_mut(),
            _ => None,
        }
    }

    /// The networks this controller has, in [`NetworkId::ALL`] order.
    pub fn network_ids(&self) -> impl Iterator<Item = NetworkId> + '_ {
        NetworkId::ALL
            .into_iter()
            .filter(|id| self.network(*id).is_some())
    }

    /// Active node count of network `id` (0 when absent).
    pub fn node_count(&self, id: NetworkId) -> usize {
        self.network(id).map_or(0, |l| l.len())
    }

    /// Frobenius norm of the weights of network `id` (0 when absent).
    pub fn weight_norm(&self, id: NetworkId) -> f64 {
        self.network(id).map_or(0.0, |l| l.weight_norm())
    }

    /// **Discard** (METHOD.md section 4, eq. 29-31): removes from network `id` every node
    /// whose tracked activation stayed below `upsilon` over the trailing relevance window
    /// (paper: 0.05); returns how many were removed. Needs relevance tracking
    /// ([`NeuralControllerConfig::track_relevance`]); nodes tracked for less than a full
    /// window are kept. Does not allocate.
    pub fn discard(&mut self, id: NetworkId, upsilon: f64) -> usize {
        self.network_mut(id).map_or(0, |l| l.discard(upsilon))
    }

    /// [`discard`](Self::discard) on every f network (lumped, or M, C and G); the deadzone
    /// network is left alone. Returns the total removed.
    pub fn discard_f(&mut self, upsilon: f64) -> usize {
        [NetworkId::F, NetworkId::M, NetworkId::C, NetworkId::G]
            .into_iter()
            .map(|id| self.discard(id, upsilon))
            .sum()
    }

    /// **Grow** (METHOD.md section 4): arms a request to add `request.nodes` nodes to
    /// network `id` near the trajectory. From the next step on, every `interval_steps`
    /// steps the controller tries one addition at the network's current input (see
    /// [`GrowthRequest::params`]) until the count is reached or the network is full. A new
    /// request replaces a pending one. Does not allocate.
    pub fn request_growth(
        &mut self,
        id: NetworkId,
        request: GrowthRequest,
    ) -> Result<(), ConfigError> {
        if self.network(id).is_none() {
            return Err(ConfigError::new(
                "network",
                format!("this controller has no `{}` network", id.as_str()),
            ));
        }
        request
            .params
            .validate()
            .map_err(|e| ConfigError::new("growth.params", format!("{e}")))?;
        if request.interval_steps == 0 {
            return Err(ConfigError::new(
                "growth.interval_steps",
                "must be at least 1",
            ));
        }
        let state = &mut self.growth[id.index()];
        state.request = Some(request);
        state.since = request.interval_steps; // first attempt at the next step
        state.progress.pending = request.nodes;
        Ok(())
    }

    /// Progress of growth on network `id`.
    pub fn growth_progress(&self, id: NetworkId) -> GrowthProgress {
        self.growth[id.index()].progress
    }

    /// Cancels a pending growth request on network `id`.
    pub fn cancel_growth(&mut self, id: NetworkId) {
        let s = &mut self.growth[id.index()];
        s.request = None;
        s.progress.pending = 0;
    }

    /// `f_hat` at an arbitrary point without changing any state (for measuring the
    /// approximation error along a recorded trajectory, METHOD.md section 6 C). `e2` is used
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

    fn after_step(&mut self) {
        let track = self.track_relevance;
        for id in NetworkId::ALL {
            let state = self.growth[id.index()];
            let grow = state.progress.pending > 0 && state.request.is_some();
            if !track && !grow {
                continue;
            }
            let Some(layer) = self.network_mut(id) else {
                continue;
            };
            if track {
                let _ = layer.track_relevance();
            }
            if !grow {
                continue;
            }
            let request = state.request.expect("checked above");
            let mut state = state;
            state.since = state.since.saturating_add(1);
            if state.since >= request.interval_steps {
                match layer.maybe_grow_at_last_input(&request.params) {
                    Ok(GrowOutcome::Added { .. }) => {
                        state.progress.pending -= 1;
                        state.progress.added += 1;
                        state.since = 0;
                    }
                    Ok(GrowOutcome::AtCapacity { .. }) => {
                        state.progress.pending = 0;
                    }
                    Ok(_) => state.progress.declined += 1,
                    Err(_) => {}
                }
                if state.progress.pending == 0 {
                    state.request = None;
                }
            }
            self.growth[id.index()] = state;
        }
    }
}

impl NeuralController {
    /// After a faulted law step: a network whose weights are no longer all finite (they
    /// cannot recover by themselves) is zeroed, so that learning restarts at the next step.
    fn zero_non_finite_networks(&mut self) {
        for id in NetworkId::ALL {
            if let Some(layer) = self.network_mut(id) {
                if !layer.weights().iter().all(|w| w.is_finite()) {
                    layer.reset_weights();
                }
            }
        }
    }
}

/// `Z_f = [q, q', alpha, alpha' (, e2)]`.
fn fill_zf(
    z: &mut [f64],
    q: &[f64],
    qdot: &[f64],
    alpha: &[f64],
    alpha_dot: &[f64],
    e2: &[f64],
    include_e2: bool,
) {
    let n = q.len();
    z[..n].copy_from_slice(q);
    z[n..2 * n].copy_from_slice(qdot);
    z[2 * n..3 * n].copy_from_slice(alpha);
    z[3 * n..4 * n].copy_from_slice(alpha_dot);
    if include_e2 {
        z[4 * n..5 * n].copy_from_slice(e2);
    }
}

/// Evaluates `layer` at `z` into `out`, adapting with error `e` over `dt` when `adapt`.
fn run_layer(
    layer: &mut GaussianRbfLayer,
    z: &[f64],
    e: &[f64],
    adapt: bool,
    dt: f64,
    out: &mut [f64],
    what: &'static str,
) -> Result<(), Fault> {
    let r = if adapt {
        layer.evaluate_adapt(z, e, dt, out)
    } else {
        layer.evaluate(z, out)
    };
    r.map_err(|_| Fault::Internal(what))
}

/// `out[i n + j] = a_i b_j`.
fn outer(a: &[f64], b: &[f64], out: &mut [f64]) {
    let n = b.len();
    for (i, ai) in a.iter().enumerate() {
        for (j, bj) in b.iter().enumerate() {
            out[i * n + j] = ai * bj;
        }
    }
}

/// `out += A x` with `A` row-major `n x n`.
fn mat_vec_add(a: &[f64], x: &[f64], out: &mut [f64]) {
    let n = x.len();
    for (i, o) in out.iter_mut().enumerate() {
        let row = &a[i * n..(i + 1) * n];
        *o += row.iter().zip(x).map(|(r, v)| r * v).sum::<f64>();
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

/// The "true" lumped function of METHOD.md section 3 / experiment C for a model:
/// `out = M(q) alpha' + C(q, q') alpha + G(q)` (Christoffel-form `C`; no friction).
/// Uses `data` as workspace; does not allocate.
pub fn true_lumped_f(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qdot: &[f64],
    alpha: &[f64],
    alpha_dot: &[f64],
    out: &mut [f64],
) -> Result<(), DimensionError> {
    let n = model.nq();
    for (argument, v) in [("alpha", alpha), ("alpha_dot", alpha_dot), ("out", &*out)] {
        if v.len() != n {
            return Err(DimensionError {
                argument,
                expected: n,
                found: v.len(),
            });
        }
    }
    let m = crba(model, data, q)?;
    for (i, o) in out.iter_mut().enumerate() {
        *o = (0..n).map(|j| m[(i, j)] * alpha_dot[j]).sum();
    }
    let c = coriolis_matrix(model, data, q, qdot)?;
    for (i, o) in out.iter_mut().enumerate() {
        *o += (0..n).map(|j| c[(i, j)] * alpha[j]).sum::<f64>();
    }
    let g = gravity_torque(model, data, q)?;
    for (o, gi) in out.iter_mut().zip(g.iter()) {
        *o += gi;
    }
    Ok(())
}
