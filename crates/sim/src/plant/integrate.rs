//! The plant's steps under each [`crate::Integrator`] (the schemes are described in
//! `integrator.rs`).

use super::Plant;

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
