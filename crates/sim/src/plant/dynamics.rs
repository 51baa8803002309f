//! The plant's model, forces and solvers ([`Dynamics`]): what a force evaluation needs,
//! apart from the state vectors so that the integrators can borrow both.

use admittance_dynamics::{
    aba, bias_and_gravity, crba, mass_matrix_and_bias, nonlinear_effects, Data, Model,
};

use super::config::Solver;
use super::friction::Friction;
use super::implicit::ImplicitSolver;
use super::linalg::SpdSystem;
use super::spring::Spring;
use crate::environment::Environment;

/// Model, forces and solvers: everything a force evaluation needs, kept apart from the
/// state vectors so that the integrators can borrow both.
#[derive(Clone, Debug)]
pub(crate) struct Dynamics {
    pub n: usize,
    pub model: Model,
    pub nominal: Model,
    pub data: Data,
    pub nominal_data: Data,
    pub env: Environment,
    pub spring: Option<Spring>,
    /// The spring is a gravity fraction and the nominal model has the true model's
    /// kinematics, inertias and gravity: its `G(q)` is the true one, computed in the same
    /// pass as `M` and `C qdot + G` ([`Dynamics::forces_and_matrix`]).
    pub spring_shares_gravity: bool,
    pub solver: Solver,
    /// Friction per joint.
    pub friction: Vec<Friction>,
    /// Friction plus the active environment damping, for the current step.
    pub phi: Vec<Friction>,
    /// Actuator torque held for the step.
    pub u: Vec<f64>,
    /// Spring torque of the last force evaluation.
    pub spring_buf: Vec<f64>,
    /// Explicit environment torque of the last force evaluation.
    pub ext_buf: Vec<f64>,
    /// u + spring + explicit environment.
    pub tau_buf: Vec<f64>,
    /// Right-hand side `tau_buf - C qdot - G`.
    pub r: Vec<f64>,
    /// `M(q) + diag(M_E)`, row-major.
    pub mat: Vec<f64>,
    /// `M` at the state's `q`, row-major, valid while `mass_valid` (or, held, while
    /// `mass_held`).
    pub m_state: Vec<f64>,
    pub mass_valid: bool,
    /// [`super::config::PlantConfig::hold_mass_matrix`]: `m_state` is kept for the whole
    /// control period.
    pub hold_mass: bool,
    /// `m_state` holds this control period's `M` (only with `hold_mass`).
    pub mass_held: bool,
    pub sys: SpdSystem,
    pub implicit: ImplicitSolver,
}

impl Dynamics {
    /// Whether any dissipative term (friction, environment damping) acts this step.
    #[inline]
    pub(crate) fn dissipative(&self) -> bool {
        self.phi.iter().any(|f| !f.is_zero())
    }

    /// Whether the accelerations need the mass matrix (rather than ABA) this step.
    #[inline]
    pub(crate) fn needs_matrix(&self) -> bool {
        self.solver == Solver::Cholesky || self.env.has_mass()
    }

    /// Spring, explicit environment and their sum with `u`, into the buffers.
    #[inline]
    pub(crate) fn applied_forces(&mut self, t: f64, q: &[f64], v: &[f64]) {
        self.spring_buf.fill(0.0);
        if let Some(s) = &self.spring {
            self.spring_buf[s.joint] = s.torque(&self.nominal, &mut self.nominal_data, q);
        }
        self.env
            .explicit_torque(&self.model, &mut self.data, t, q, v, &mut self.ext_buf);
        for i in 0..self.n {
            self.tau_buf[i] = self.u[i] + self.spring_buf[i] + self.ext_buf[i];
        }
    }

    /// `mat = M(q) + diag(M_E)`; `state` says `q` is the plant's current position (the
    /// result is cached for it).
    #[inline]
    pub(crate) fn mass_matrix(&mut self, q: &[f64], state: bool) -> bool {
        let n = self.n;
        if !((state && self.mass_valid) || self.mass_held) {
            let Ok(m) = crba(&self.model, &mut self.data, q) else {
                return false;
            };
            // Symmetric: row-major and column-major agree.
            self.mat.copy_from_slice(m.as_slice());
            if state {
                self.m_state.copy_from_slice(&self.mat);
                self.mass_valid = true;
                self.mass_held = self.hold_mass;
            }
        } else {
            self.mat.copy_from_slice(&self.m_state);
        }
        for (i, me) in self.env.mass_diag().iter().enumerate() {
            self.mat[i * n + i] += me;
        }
        true
    }

    /// What [`Self::applied_forces`], [`Self::mass_matrix`] and [`Self::rhs`] compute, in
    /// that order, at `(t, q, v)`: the applied forces into the buffers, `mat = M(q) +
    /// diag(M_E)` and `r = tau_buf - (C qdot + G)`. Unless `M` is cached, the joint
    /// placements are computed once for `M`, `C qdot + G` and the spring's gravity (same
    /// values, a third of the kinematics).
    #[inline]
    pub(crate) fn forces_and_matrix(&mut self, t: f64, q: &[f64], v: &[f64], state: bool) -> bool {
        if state && self.mass_valid {
            self.applied_forces(t, q, v);
            return self.mass_matrix(q, state) && self.rhs(q, v);
        }
        let n = self.n;
        let shared = self.spring_shares_gravity;
        if self.mass_held {
            // The period's M, the bias (and the spring's gravity) at this q.
            if bias_and_gravity(&self.model, &mut self.data, q, v, shared).is_err() {
                return false;
            }
            self.mat.copy_from_slice(&self.m_state);
        } else {
            if mass_matrix_and_bias(&self.model, &mut self.data, q, v, shared).is_err() {
                return false;
            }
            // Symmetric: row-major and column-major agree.
            self.mat.copy_from_slice(self.data.mass_matrix.as_slice());
            if state {
                self.m_state.copy_from_slice(&self.mat);
                self.mass_valid = true;
                self.mass_held = self.hold_mass;
            }
        }
        for (i, me) in self.env.mass_diag().iter().enumerate() {
            self.mat[i * n + i] += me;
        }
        // r holds C qdot + G until the applied forces are known.
        self.r
            .copy_from_slice(self.data.nonlinear_effects.as_slice());
        self.spring_buf.fill(0.0);
        if let Some(s) = &self.spring {
            self.spring_buf[s.joint] = if shared {
                s.torque_from_gravity(self.data.gravity_torque.as_slice())
            } else {
                s.torque(&self.nominal, &mut self.nominal_data, q)
            };
        }
        self.env
            .explicit_torque(&self.model, &mut self.data, t, q, v, &mut self.ext_buf);
        for i in 0..n {
            self.tau_buf[i] = self.u[i] + self.spring_buf[i] + self.ext_buf[i];
            self.r[i] = self.tau_buf[i] - self.r[i];
        }
        true
    }

    /// `r = tau_buf - (C qdot + G)`.
    #[inline]
    pub(crate) fn rhs(&mut self, q: &[f64], v: &[f64]) -> bool {
        let Ok(nle) = nonlinear_effects(&self.model, &mut self.data, q, v) else {
            return false;
        };
        for i in 0..self.n {
            self.r[i] = self.tau_buf[i] - nle[i];
        }
        true
    }

    /// Accelerations of the conservative-plus-forcing part at `(t, q, v)` (no friction, no
    /// environment damping: those are in the implicit sub-steps), into `a`.
    pub(crate) fn accel(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        state: bool,
        a: &mut [f64],
    ) -> bool {
        if !self.needs_matrix() {
            self.applied_forces(t, q, v);
            let Ok(qdd) = aba(&self.model, &mut self.data, q, v, &self.tau_buf) else {
                return false;
            };
            a.copy_from_slice(qdd.as_slice());
            return a.iter().all(|x| x.is_finite());
        }
        if !self.forces_and_matrix(t, q, v, state) {
            return false;
        }
        self.sys.matrix_mut().copy_from_slice(&self.mat);
        if !self.sys.factor() {
            return false;
        }
        a.copy_from_slice(&self.r);
        self.sys.solve_in_place(a);
        true
    }
}
