//! Building the controller's Gaussian RBF layers from their configuration, and the small
//! helpers that run them inside the law (docs/method.md section 3).

use admittance_learning::rbf::{GaussianRbfLayer, Placement, RbfConfigError, RbfLayerConfig};

use super::config::NetworkConfig;
use crate::config::Bound;
use crate::error::{ConfigError, Fault};

pub(super) const F_RANGES: [[f64; 2]; 5] = [
    [-1.5, 1.5],
    [-1.3, 1.3],
    [-1.3, 1.3],
    [-1.3, 1.3],
    [-1.0, 1.0],
];
pub(super) const T_RANGES: [[f64; 2]; 4] = [[-10.0, 10.0], [-1.3, 1.3], [-1.5, 1.5], [-1.0, 1.0]];

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
pub(super) fn build_layer(
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
pub(super) enum FNet {
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

/// `Z_f = [q, q', alpha, alpha' (, e2)]`.
pub(super) fn fill_zf(
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
pub(super) fn run_layer(
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
pub(super) fn outer(a: &[f64], b: &[f64], out: &mut [f64]) {
    let n = b.len();
    for (i, ai) in a.iter().enumerate() {
        for (j, bj) in b.iter().enumerate() {
            out[i * n + j] = ai * bj;
        }
    }
}

/// `out += A x` with `A` row-major `n x n`.
pub(super) fn mat_vec_add(a: &[f64], x: &[f64], out: &mut [f64]) {
    let n = x.len();
    for (i, o) in out.iter_mut().enumerate() {
        let row = &a[i * n..(i + 1) * n];
        *o += row.iter().zip(x).map(|(r, v)| r * v).sum::<f64>();
    }
}
