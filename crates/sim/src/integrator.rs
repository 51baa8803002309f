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
//!   kinetic energy over 2 s at 5 kHz, `tests/it/plant_energy.rs`).
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

/// The integration scheme of a [`crate::Plant`] (its steps: `plant/integrate.rs`).
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
