//! The admittance on the six task axes (the paper's eq. 5, docs/method.md sign):
//!
//! ```text
//!     M_d dx'' + C_d dx' + G_d dx = f_ext_hat,      dx = x_r - x_d  (per axis)
//! ```
//!
//! integrated over a step with the wrench held, as the joint-space
//! [`Admittance`](crate::Admittance) does per joint: exactly without `M_d` (also for
//! `G_d = 0`, where `dx` grows by `dt f / C_d`), by backward Euler with `M_d`. An axis that is
//! not compliant keeps `dx = dx' = dx'' = 0`.

use nalgebra::Vector6;

use super::config::AxisAdmittanceConfig;
use crate::config::Bound;
use crate::error::ConfigError;

/// Gains and state of the six axes.
#[derive(Clone, Debug)]
pub(crate) struct AxisDeviation {
    compliant: [bool; 6],
    damping: [f64; 6],
    stiffness: [f64; 6],
    /// `None`: first order on that axis.
    inertia: [Option<f64>; 6],
    /// `dx`, `dx'`, `dx''` (linear first; the angular part is the rotation vector of
    /// `R_r R_d^T`).
    pub(crate) position: Vector6<f64>,
    pub(crate) velocity: Vector6<f64>,
    pub(crate) acceleration: Vector6<f64>,
}

impl AxisDeviation {
    pub(crate) fn new(
        compliant: [bool; 6],
        linear: &AxisAdmittanceConfig,
        angular: &AxisAdmittanceConfig,
    ) -> Result<Self, ConfigError> {
        let mut out = AxisDeviation {
            compliant,
            damping: [0.0; 6],
            stiffness: [0.0; 6],
            inertia: [None; 6],
            position: Vector6::zeros(),
            velocity: Vector6::zeros(),
            acceleration: Vector6::zeros(),
        };
        for (offset, group, cfg) in [(0, "linear", linear), (3, "angular", angular)] {
            let within = |e: ConfigError| e.within(group);
            let c = cfg
                .damping
                .resolve("damping", Bound::Positive)
                .map_err(within)?;
            let g = cfg
                .stiffness
                .resolve("stiffness", Bound::NonNegative)
                .map_err(within)?;
            let m = match &cfg.inertia {
                Some(m) => Some(m.resolve("inertia", Bound::Positive).map_err(within)?),
                None => None,
            };
            for k in 0..3 {
                out.damping[offset + k] = c[k];
                out.stiffness[offset + k] = g[k];
                out.inertia[offset + k] = m.map(|m| m[k]);
            }
        }
        Ok(out)
    }

    /// The state after a step of `dt` with the wrench `f` held, written to `position`,
    /// `velocity`, `acceleration` (the state itself is not changed: the caller commits it
    /// with [`commit`](Self::commit) once the whole step succeeded).
    pub(crate) fn advance(
        &self,
        f: &Vector6<f64>,
        dt: f64,
        position: &mut Vector6<f64>,
        velocity: &mut Vector6<f64>,
        acceleration: &mut Vector6<f64>,
    ) {
        for i in 0..6 {
            if !self.compliant[i] {
                position[i] = 0.0;
                velocity[i] = 0.0;
                acceleration[i] = 0.0;
                continue;
            }
            let (c, g, force) = (self.damping[i], self.stiffness[i], f[i]);
            let (x, v) = (self.position[i], self.velocity[i]);
            match self.inertia[i] {
                None if g > 0.0 => {
                    let x_ss = force / g;
                    let x_new = x_ss + (x - x_ss) * (-g * dt / c).exp();
                    position[i] = x_new;
                    velocity[i] = (force - g * x_new) / c;
                    acceleration[i] = -(g / c) * velocity[i];
                }
                None => {
                    position[i] = x + dt * force / c;
                    velocity[i] = force / c;
                    acceleration[i] = 0.0;
                }
                Some(m) => {
                    let v_new = (m * v + dt * (force - g * x)) / (m + dt * c + dt * dt * g);
                    position[i] = x + dt * v_new;
                    velocity[i] = v_new;
                    acceleration[i] = (force - c * v_new - g * position[i]) / m;
                }
            }
        }
    }

    /// Makes the advanced state the current one.
    pub(crate) fn commit(
        &mut self,
        position: &Vector6<f64>,
        velocity: &Vector6<f64>,
        acceleration: &Vector6<f64>,
    ) {
        self.position = *position;
        self.velocity = *velocity;
        self.acceleration = *acceleration;
    }

    pub(crate) fn reset(&mut self) {
        self.position = Vector6::zeros();
        self.velocity = Vector6::zeros();
        self.acceleration = Vector6::zeros();
    }
}
