//! Fixed-step integration schemes of the plant.
//!
//! Both treat the dissipative, velocity-dependent diagonal torques `phi(v)` (joint
//! friction `Fv v + Fc tanh(v / v_s)` plus the active environments' `C_E v`) implicitly
//! with L-stable methods, each implicit stage solved exactly by a line-searched Newton
//! iteration (see the `implicit` solver in `plant`): the stiff Coulomb term with a small
//! `v_s` neither oscillates nor blows up at the plant step.
//! The environment mass `M_E` is added to the mass matrix in every solve (coupled, not
//! lagged).
//!
//! * [`Integrator::SemiImplicitEuler`]: `v+ = v + h a(q, v, v+)`, `q+ = q + h v+` with
//!   `(M + M_E + h dphi/dv) a = tau - C v - G - phi(v)` iterated to the backward-Euler
//!   solution. Without friction it is exactly MuJoCo's "Euler" integrator (semi-implicit
//!   in velocity), the scheme of the side-by-side timing. First order; symplectic for a
//!   constant mass matrix, but not exactly with `M(q)` in this velocity form: the energy
//!   error of the free, frictionless Baxter arm is O(h) and grows slowly (1.5e-2 of the
//!   kinetic energy over 2 s at 5 kHz, `tests/plant_energy.rs`).
//! * [`Integrator::Rk4Split`] (default): without dissipative terms, the classical
//!   fourth-order Runge-Kutta step of
//!   `(M + M_E) qddot = D(tau) + tau_spring + tau_ext,explicit - C qdot - G` (the free
//!   frictionless arm at fourth order: energy error O(h^4), 4e-11 of the kinetic energy
//!   over 2 s at 5 kHz). With friction or environment damping, a *balanced* Strang split
//!   `D(h/2) R(h) D(h/2)`: with `c = (M + M_E)^-1 (tau - C qdot - G)` the forcing
//!   acceleration at the step's start, `D` integrates
//!   `qddot = -(M + M_E)^-1 phi(qdot) + c` at fixed `q` by a two-stage L-stable, stiffly
//!   accurate SDIRK method (second order), and `R` is the RK4 step of the rest minus `c`.
//!   Adding and subtracting `c` makes an equilibrium of friction against the forcing
//!   (sticking under a torque below the Coulomb level) an equilibrium of both sub-steps;
//!   a plain split would let the RK4 step push a stuck light joint by `h tau / m` every
//!   step and the friction pull it back, a creep several times too fast. Second order
//!   with friction, unconditionally stable (L-stable in the dissipative part). Without
//!   friction it costs about four semi-implicit Euler steps; with it, four implicit
//!   solves more.
//!
//! In both, activity of the environments is fixed at the step's start; the command is
//! held over the step.

use serde::{Deserialize, Serialize};

use crate::plant::Plant;

/// The integration scheme of a [`Plant`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Semi-implicit (symplectic) Euler with implicit dissipation; MuJoCo's "Euler".
    SemiImplicitEuler,
    /// RK4 for the conservative and forcing terms, split with backward-Euler dissipation.
    #[default]
    Rk4Split,
}

impl Integrator {
    /// The name used in configuration files and timing output.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::SemiImplicitEuler => "semi_implicit_euler",
            Integrator::Rk4Split => "rk4_split",
        }
    }
}

impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Plant {
    /// Adds `w` times the last force evaluation's spring and explicit environment torques
    /// to the step accumulators.
    #[inline(always)]
    fn accumulate_explicit(&mut self, w: f64) {
        for i in 0..self.dynx.n {
            self.acc_ext[i] += w * self.dynx.ext_buf[i];
            self.acc_spring[i] += w * self.dynx.spring_buf[i];
        }
    }

    /// Adds `w` times the dissipative torques at velocity `v` (friction and environment
    /// damping, as applied by an implicit update) to the accumulators.
    #[inline(always)]
    fn accumulate_dissipation(&mut self, w: f64, at_stage: bool) {
        let damping = self.dynx.env.damping_diag();
        let v = if at_stage { &self.diss_v1 } else { &self.v };
        for i in 0..self.dynx.n {
            let vi = v[i];
            self.acc_friction[i] -= w * self.dynx.friction[i].torque(vi);
            self.acc_ext[i] -= w * damping[i] * vi;
        }
    }

    pub(crate) fn step_semi_implicit_euler(&mut self, t: f64) -> bool {
        let h = self.h;
        let n = self.dynx.n;
        let d = &mut self.dynx;
        let matrix_path = d.needs_matrix() || d.dissipative();
        if !matrix_path {
            d.applied_forces(t, &self.q, &self.v);
            let Ok(a) =
                admittance_dynamics::aba(&d.model, &mut d.data, &self.q, &self.v, &d.tau_buf)
            else {
                return false;
            };
            for i in 0..n {
                self.dv[i] = h * a[i];
            }
        } else {
            if !d.forces_and_matrix(t, &self.q, &self.v, true) {
                return false;
            }
            let rep = d
                .implicit
                .solve(&d.mat, &self.v, h, &d.r, &d.phi, &mut self.dv);
            self.record.newton_iterations += rep.iterations;
            if !rep.ok {
                return false;
            }
        }
        for i in 0..n {
            self.v[i] += self.dv[i];
            self.q[i] += h * self.v[i];
        }
        self.dynx.mass_valid = false;
        self.accumulate_explicit(1.0);
        // Without environment damping phi is the friction law itself, and the solver
        // already evaluated it at the new velocity.
        let no_damping = self.dynx.env.damping_diag().iter().all(|c| *c == 0.0);
        match self.dynx.implicit.last_torque() {
            Some(f) if no_damping && matrix_path => {
                for (acc, fi) in self.acc_friction.iter_mut().zip(f).take(n) {
                    *acc -= fi;
                }
            }
            _ => self.accumulate_dissipation(1.0, false),
        }
        true
    }

    /// The dissipative half step of the balanced split at the current state:
    /// `v' = -A^-1 phi(v) + c` over `h/2` at fixed `q`, with `c` the step's frozen forcing
    /// acceleration, by the two-stage L-stable SDIRK method (Alexander's, `gamma = 1 -
    /// 1/sqrt 2`, stiffly accurate, second order). Each stage is an implicit solve of
    /// `A dv + gamma (h/2) phi(w + dv) = gamma (h/2) A c`. `d.r` holds `A c` when
    /// `have_r`, else it is computed here.
    fn dissipative_half_step(&mut self, have_r: bool) -> bool {
        const GAMMA: f64 = 1.0 - std::f64::consts::FRAC_1_SQRT_2;
        let n = self.dynx.n;
        let hs = GAMMA * 0.5 * self.h;
        let d = &mut self.dynx;
        if !have_r {
            if !d.mass_matrix(&self.q, true) {
                return false;
            }
            for i in 0..n {
                let row = &d.mat[i * n..i * n + n];
                d.r[i] = row.iter().zip(&self.balance_c).map(|(a, c)| a * c).sum();
            }
        }
        // Stage 1 from v.
        let rep = d
            .implicit
            .solve(&d.mat, &self.v, hs, &d.r, &d.phi, &mut self.dv);
        self.record.newton_iterations += rep.iterations;
        if !rep.ok {
            return false;
        }
        // Stage 2 from w = v + (1 - gamma) / gamma (V1 - v).
        let k = (1.0 - GAMMA) / GAMMA;
        for i in 0..n {
            self.diss_v1[i] = self.v[i] + self.dv[i];
            self.diss_w[i] = self.v[i] + k * self.dv[i];
        }
        let rep = d
            .implicit
            .solve(&d.mat, &self.diss_w, hs, &d.r, &d.phi, &mut self.dv);
        self.record.newton_iterations += rep.iterations;
        if !rep.ok {
            return false;
        }
        for i in 0..n {
            self.v[i] = self.diss_w[i] + self.dv[i];
        }
        // The dissipative impulse over h/2: (1 - gamma) phi(V1) + gamma phi(V2).
        self.accumulate_dissipation(0.5 * (1.0 - GAMMA), true);
        self.accumulate_dissipation(0.5 * GAMMA, false);
        true
    }

    pub(crate) fn step_rk4_split(&mut self, t: f64) -> bool {
        let h = self.h;
        let n = self.dynx.n;
        let dissipative = self.dynx.dissipative();
        if dissipative {
            // Balanced splitting: the forcing acceleration c = A^-1 (tau - C v - G) at the
            // step's start is added to the dissipative sub-steps and subtracted from the
            // RK4 step, so that a stick (or any) equilibrium of friction against the
            // forcing is an equilibrium of both sub-steps.
            let d = &mut self.dynx;
            if !d.forces_and_matrix(t, &self.q, &self.v, true) {
                return false;
            }
            d.sys.matrix_mut().copy_from_slice(&d.mat);
            if !d.sys.factor() {
                return false;
            }
            self.balance_c.copy_from_slice(&d.r);
            d.sys.solve_in_place(&mut self.balance_c);
            if !self.dissipative_half_step(true) {
                return false;
            }
        } else {
            self.balance_c.fill(0.0);
        }
        let weights = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];
        let offsets = [0.0, 0.5, 0.5, 1.0];
        for s in 0..4 {
            if s == 0 {
                self.stage_v[0].copy_from_slice(&self.v);
                let (v0, a0) = (&self.stage_v[0], &mut self.stage_a[0]);
                if !self.dynx.accel(t, &self.q, v0, true, a0) {
                    return false;
                }
            } else {
                let c = offsets[s] * h;
                let (prev_v, rest_v) = self.stage_v.split_at_mut(s);
                let (prev_a, rest_a) = self.stage_a.split_at_mut(s);
                let (vp, ap, vs, as_) = (
                    &prev_v[s - 1],
                    &prev_a[s - 1],
                    &mut rest_v[0],
                    &mut rest_a[0],
                );
                for i in 0..n {
                    self.stage_q[i] = self.q[i] + c * vp[i];
                    vs[i] = self.v[i] + c * ap[i];
                }
                if !self.dynx.accel(t + c, &self.stage_q, vs, false, as_) {
                    return false;
                }
            }
            if dissipative {
                for (a, c) in self.stage_a[s].iter_mut().zip(&self.balance_c) {
                    *a -= c;
                }
            }
            self.accumulate_explicit(weights[s]);
        }
        let [v1, v2, v3, v4] = &self.stage_v;
        let [a1, a2, a3, a4] = &self.stage_a;
        let k = h / 6.0;
        for i in 0..n {
            self.q[i] += k * (v1[i] + 2.0 * (v2[i] + v3[i]) + v4[i]);
            self.v[i] += k * (a1[i] + 2.0 * (a2[i] + a3[i]) + a4[i]);
        }
        self.dynx.mass_valid = false;
        if dissipative && !self.dissipative_half_step(false) {
            return false;
        }
        true
    }
}
