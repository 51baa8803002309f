//! Layer description (serde) and centre placement (docs/method.md section 3, last paragraph).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::RbfConfigError;

/// How the weights are integrated over one step `dt` of the update law
/// `W' = Gamma (S(Z) e^T - sigma W)` (docs/method.md section 3), with `S(Z)` and `e` held
/// constant over the step (zero-order hold).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Explicit Euler: `W <- W + dt Gamma (S e^T - sigma W)`.
    /// Stable only while `Gamma sigma dt < 2`.
    Euler,
    /// Exact solution of the linear ODE over the step:
    /// `W <- a W + (1 - a) / sigma * S e^T` with `a = exp(-Gamma sigma dt)`
    /// (and `W <- W + Gamma dt S e^T` when `sigma = 0`). Unconditionally stable; agrees
    /// with [`Integrator::Euler`] to first order in `dt`. The default.
    #[default]
    ExactDecay,
}

/// Where the initial centres go (docs/method.md section 3: on a lattice or sampled, inside a
/// box given per input dimension).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Placement {
    /// A regular lattice with `points[k]` points along dimension `k`, end points included
    /// (one point: the box midpoint). Node count is the product of the counts; see
    /// [`lattice_centres`] for the ordering.
    Lattice {
        /// Points per input dimension.
        points: Vec<usize>,
    },
    /// `count` centres sampled independently and uniformly inside the box with a ChaCha8
    /// generator seeded by `seed` (deterministic across runs and platforms); see
    /// [`random_centres`].
    Random {
        /// Number of centres.
        count: usize,
        /// RNG seed.
        seed: u64,
    },
    /// An explicit list of centres (each of the box dimension; they need not lie inside
    /// the box).
    Explicit {
        /// One centre per node.
        centres: Vec<Vec<f64>>,
    },
}

impl Default for Placement {
    fn default() -> Self {
        Placement::Explicit {
            centres: Vec::new(),
        }
    }
}

/// Parameters of node growth (docs/method.md section 4, "Grow"; eq. 20-22).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrowthParams {
    /// `m`: number of nearest centres whose mean distance to `Z` is compared with `Xi`
    /// (eq. 21). Clamped to `1..=max_neighbours` of the layer, and to the node count.
    pub neighbours: usize,
    /// `Xi`: grow when the mean distance of the `m` nearest centres exceeds it (eq. 22).
    pub distance_threshold: f64,
    /// Minimum distance between the new centre and every existing centre; a candidate
    /// closer than this is not added. Zero disables the check.
    #[serde(default)]
    pub min_spacing: f64,
    /// Where the new centre goes on the segment from the nearest centre `u_near` to `Z`:
    /// `u_new = u_near + step_fraction (Z - u_near)`. Eq. 20 as printed adds a distance to
    /// a point; docs/method.md section 4 fixes it to this segment form. The default `1.0` places
    /// the new centre at `Z`.
    #[serde(default = "one")]
    pub step_fraction: f64,
}

fn one() -> f64 {
    1.0
}

impl GrowthParams {
    /// Growth at `Z` (`step_fraction = 1`) with the given `m`, `Xi` and spacing.
    pub fn new(neighbours: usize, distance_threshold: f64, min_spacing: f64) -> Self {
        GrowthParams {
            neighbours,
            distance_threshold,
            min_spacing,
            step_fraction: 1.0,
        }
    }

    /// Checks `Xi >= 0`, `min_spacing >= 0`, `0 < step_fraction <= 1`, all finite
    /// (`Xi` may be `+inf`: never grow).
    pub fn validate(&self) -> Result<(), RbfConfigError> {
        if self.distance_threshold.is_nan() || self.distance_threshold < 0.0 {
            return Err(RbfConfigError::InvalidGrowth(
                "distance_threshold must be >= 0",
            ));
        }
        if !(self.min_spacing.is_finite() && self.min_spacing >= 0.0) {
            return Err(RbfConfigError::InvalidGrowth(
                "min_spacing must be finite and >= 0",
            ));
        }
        if !(self.step_fraction > 0.0 && self.step_fraction <= 1.0) {
            return Err(RbfConfigError::InvalidGrowth(
                "step_fraction must be in (0, 1]",
            ));
        }
        Ok(())
    }
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

/// Description of one Gaussian RBF layer (docs/method.md section 3: eq. 9 activations, the
/// sigma-modified update law; section 4: dynamic nodes).
///
/// JSON example (unknown fields are rejected):
///
/// ```json
/// { "lower": [-1.5, -1.3], "upper": [1.5, 1.3],
///   "placement": { "kind": "lattice", "points": [5, 4] },
///   "width": 0.6, "capacity": 64, "outputs": 7, "gamma": 33.3, "sigma": 0.035,
///   "integrator": "exact_decay", "relevance_window": 2000,
///   "growth": { "neighbours": 4, "distance_threshold": 0.8, "min_spacing": 0.2 } }
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RbfLayerConfig {
    /// Lower corner of the input box, one entry per input dimension (this fixes `d`).
    pub lower: Vec<f64>,
    /// Upper corner of the input box.
    pub upper: Vec<f64>,
    /// Placement of the initial centres.
    pub placement: Placement,
    /// Width `eta` of every initial node (eq. 9); also the width of a grown node when the
    /// layer is empty.
    pub width: f64,
    /// Capacity `L_max`: storage is allocated for this many nodes once.
    pub capacity: usize,
    /// Number of outputs `n` (joints).
    pub outputs: usize,
    /// Adaptation gain `Gamma = Theta^-1` (docs/method.md section 3; experiment C: Theta = 0.03).
    pub gamma: f64,
    /// Sigma-modification `sigma` (experiment C: 0.035).
    pub sigma: f64,
    /// Weight integrator (default [`Integrator::ExactDecay`]).
    #[serde(default)]
    pub integrator: Integrator,
    /// Relevance window `W` in tracked steps (default 1000); see
    /// [`GaussianRbfLayer::track_relevance`](super::GaussianRbfLayer::track_relevance).
    #[serde(default = "default_window")]
    pub relevance_window: usize,
    /// Activations below this are computed as exactly zero (the node is skipped, no `exp`
    /// is evaluated); default `1e-16`, `0` disables the cut-off (activations below about
    /// `3e-308`, i.e. `exp(-708)`, are still flushed to zero).
    #[serde(default = "default_min_activation")]
    pub min_activation: f64,
    /// Largest `m` accepted by growth (size of the fixed nearest-neighbour scratch buffer);
    /// default 16.
    #[serde(default = "default_max_neighbours")]
    pub max_neighbours: usize,
    /// Optional growth parameters carried with the layer (see
    /// [`GaussianRbfLayer::growth_params`](super::GaussianRbfLayer::growth_params)).
    #[serde(default)]
    pub growth: Option<GrowthParams>,
}

impl Default for RbfLayerConfig {
    /// An empty description with the paper's experiment-C gains (Gamma = 1/0.03,
    /// sigma = 0.035); `lower`, `upper`, `placement`, `width`, `capacity` and `outputs`
    /// must be filled in.
    fn default() -> Self {
        RbfLayerConfig {
            lower: Vec::new(),
            upper: Vec::new(),
            placement: Placement::default(),
            width: 1.0,
            capacity: 0,
            outputs: 0,
            gamma: 1.0 / 0.03,
            sigma: 0.035,
            integrator: Integrator::default(),
            relevance_window: default_window(),
            min_activation: default_min_activation(),
            max_neighbours: default_max_neighbours(),
            growth: None,
        }
    }
}

impl RbfLayerConfig {
    /// Input dimension `d` (the box dimension).
    pub fn input_dim(&self) -> usize {
        self.lower.len()
    }

    /// Parses a JSON description.
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The initial centres, flat and node-major (`count * d` values).
    pub fn centres(&self) -> Result<Vec<f64>, RbfConfigError> {
        check_box(&self.lower, &self.upper)?;
        let d = self.lower.len();
        let centres = match &self.placement {
            Placement::Lattice { points } => lattice_centres(&self.lower, &self.upper, points)?,
            Placement::Random { count, seed } => {
                random_centres(&self.lower, &self.upper, *count, *seed)?
            }
            Placement::Explicit { centres } => {
                let mut flat = Vec::with_capacity(centres.len() * d);
                for (index, c) in centres.iter().enumerate() {
                    if c.len() != d || c.iter().any(|x| !x.is_finite()) {
                        return Err(RbfConfigError::InvalidCentre {
                            index,
                            got: c.len(),
                            expected: d,
                        });
                    }
                    flat.extend_from_slice(c);
                }
                flat
            }
        };
        let nodes = centres.len() / d;
        if nodes > self.capacity {
            return Err(RbfConfigError::TooManyNodes {
                nodes,
                capacity: self.capacity,
            });
        }
        Ok(centres)
    }
}

pub(crate) fn check_box(lower: &[f64], upper: &[f64]) -> Result<(), RbfConfigError> {
    if lower.is_empty() || lower.len() != upper.len() {
        return Err(RbfConfigError::BoxDimension {
            lower: lower.len(),
            upper: upper.len(),
        });
    }
    for (dim, (&lo, &hi)) in lower.iter().zip(upper).enumerate() {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(RbfConfigError::InvalidBox {
                dim,
                lower: lo,
                upper: hi,
            });
        }
    }
    Ok(())
}

/// Lattice centres over the box `[lower, upper]` (docs/method.md section 3): `points[k]` evenly
/// spaced values per dimension, end points included (`lower[k] + (upper[k] - lower[k]) j /
/// (points[k] - 1)`, or the midpoint when `points[k] == 1`). Returned flat and node-major,
/// in lexicographic order with the **last** dimension varying fastest.
pub fn lattice_centres(
    lower: &[f64],
    upper: &[f64],
    points: &[usize],
) -> Result<Vec<f64>, RbfConfigError> {
    check_box(lower, upper)?;
    let d = lower.len();
    if points.len() != d || points.contains(&0) {
        return Err(RbfConfigError::LatticeShape {
            dim: d,
            got: points.to_vec(),
        });
    }
    let nodes = points.iter().try_fold(1usize, |acc, &k| acc.checked_mul(k));
    // Guard against absurd lattices before allocating (the caller checks capacity too).
    let nodes = match nodes {
        Some(n) if n.checked_mul(d).is_some_and(|t| t <= (1usize << 32)) => n,
        other => {
            return Err(RbfConfigError::TooManyNodes {
                nodes: other.unwrap_or(usize::MAX),
                capacity: (1usize << 32) / d,
            })
        }
    };
    let coord = |k: usize, j: usize| -> f64 {
        if points[k] == 1 {
            0.5 * (lower[k] + upper[k])
        } else {
            let t = j as f64 / (points[k] - 1) as f64;
            lower[k] + (upper[k] - lower[k]) * t
        }
    };
    let mut out = Vec::with_capacity(nodes * d);
    let mut index = vec![0usize; d];
    for _ in 0..nodes {
        for (k, &j) in index.iter().enumerate() {
            out.push(coord(k, j));
        }
        // Odometer increment, last dimension fastest.
        for k in (0..d).rev() {
            index[k] += 1;
            if index[k] < points[k] {
                break;
            }
            index[k] = 0;
        }
    }
    Ok(out)
}

/// `count` centres sampled uniformly in the box (docs/method.md section 3), flat and node-major.
/// Coordinate `k` of each centre is `lower[k] + (upper[k] - lower[k]) u` with `u` a uniform
/// `[0, 1)` draw from `ChaCha8Rng::seed_from_u64(seed)`, drawn node by node, dimension by
/// dimension: the same seed always gives the same centres.
pub fn random_centres(
    lower: &[f64],
    upper: &[f64],
    count: usize,
    seed: u64,
) -> Result<Vec<f64>, RbfConfigError> {
    check_box(lower, upper)?;
    let d = lower.len();
    if count.checked_mul(d).is_none_or(|t| t > (1usize << 32)) {
        return Err(RbfConfigError::TooManyNodes {
            nodes: count,
            capacity: (1usize << 32) / d,
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(count * d);
    for _ in 0..count {
        for k in 0..d {
            let u: f64 = rng.random();
            out.push(lower[k] + (upper[k] - lower[k]) * u);
        }
    }
    Ok(out)
}
