//! The counterbalance spring (Baxter's s1): a passive joint torque that carries part of
//! the arm's weight. See [`SpringConfig`] for the two laws.

use admittance_dynamics::{gravity_torque, Data, Model};

use crate::plant::config::{SpringConfig, SpringModel};

/// The spring at run time.
#[derive(Clone, Debug)]
pub(crate) struct Spring {
    pub joint: usize,
    model: SpringModel,
    fraction: f64,
    k0: f64,
    k1: f64,
    phase: f64,
}

impl Spring {
    /// `None` when the configuration turns it off. The joint name was validated.
    pub(crate) fn new(model: &Model, config: &SpringConfig) -> Option<Self> {
        if !config.enabled {
            return None;
        }
        Some(Self {
            joint: model.joint_index(&config.joint)?,
            model: config.model,
            fraction: config.fraction,
            k0: config.k0,
            k1: config.k1,
            phase: config.phase,
        })
    }

    /// Whether the law is the gravity fraction.
    pub(crate) fn is_gravity_fraction(&self) -> bool {
        self.model == SpringModel::GravityFraction
    }

    /// The gravity-fraction torque from `G(q)` of the nominal model, computed elsewhere
    /// (the same value as [`Self::torque`]).
    #[inline]
    pub(crate) fn torque_from_gravity(&self, g: &[f64]) -> f64 {
        self.fraction * g.get(self.joint).copied().unwrap_or(0.0)
    }

    /// The spring torque at `q` (on its joint only); `nominal` and `data` serve the
    /// gravity-fraction law.
    #[inline]
    pub(crate) fn torque(&self, nominal: &Model, data: &mut Data, q: &[f64]) -> f64 {
        match self.model {
            SpringModel::GravityFraction => match gravity_torque(nominal, data, q) {
                Ok(g) => self.fraction * g[self.joint],
                Err(_) => 0.0,
            },
            SpringModel::Cosine => self.k0 + self.k1 * (q[self.joint] + self.phase).cos(),
        }
    }
}
