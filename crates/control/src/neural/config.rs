//! Configuration of the neural controller: its networks, the form of the f approximation
//! and the controller's gains and switches (docs/method.md sections 3 and 4).

use admittance_learning::rbf::{GrowthParams, Integrator, Placement};
use serde::{Deserialize, Serialize};

use super::deadzone_inverse::DeadzoneInverseConfig;
use crate::config::JointValues;
use crate::safe_hold::SafeHoldConfig;

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

/// One Gaussian RBF network of the controller (docs/method.md section 3: eq. 9 nodes; section 4:
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
    /// Relevance window (tracked steps) used by discard (docs/method.md section 4).
    pub relevance_window: usize,
    /// Activations below this are computed as zero (default 1e-16).
    pub min_activation: f64,
    /// Largest `m` accepted by growth.
    pub max_neighbours: usize,
    /// Growth parameters carried with the network (used by
    /// [`NeuralController::request_growth`](crate::NeuralController::request_growth) when the request gives none).
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

/// How `f = M alpha' + C alpha + G` is approximated (docs/method.md section 3).
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

/// Configuration of [`NeuralController`](crate::NeuralController) (docs/method.md section 3).
/// Defaults are the paper's experiment A: `K1 = 12`, `K2 = 6`, lumped f network with `Theta_f = 0.3`, deadzone
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
