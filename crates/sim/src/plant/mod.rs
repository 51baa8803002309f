//! The plant: the true arm that stands in for the robot (docs/method.md section 1),
//!
//! ```text
//! M(q) qddot + C(q, qdot) qdot + G(q) + F(qdot) = D(tau) + tau_ext + tau_spring
//! ```
//!
//! integrated at a plant rate finer than the control rate; the command is held over a
//! control period (zero-order hold, [`Plant::step_control`]).
//! * The true model is the nominal one with `inertia_scale`, `body_scales`, a `payload`
//!   and a `gravity` override applied (the controller keeps the nominal one).
//! * The command goes through the per-joint deadzone `D` and is then clamped to the
//!   effort limits (times `effort_limit_scale`); a non-finite command is taken as zero
//!   and reported ([`StepRecord::command_nonfinite`]).
//! * Friction `F`, the environment's `M_E` and `C_E` implicitly ([`crate::integrator`]),
//!   the rest of `tau_ext` and the spring explicitly.
//! * After construction a step allocates nothing and never panics; if the state ever
//!   became non-finite (it should not), the step is undone, the velocity zeroed and
//!   [`StepRecord::diverged`] set.

#![allow(clippy::needless_range_loop)] // parallel per-joint arrays read clearest indexed

pub mod actuator;
pub mod config;
mod dynamics;
pub mod error;
pub mod friction;
pub(crate) mod implicit;
mod integrate;
pub(crate) mod linalg;
pub(crate) mod spring;

pub(crate) use dynamics::Dynamics;

use admittance_dynamics::{kinetic_energy, potential_energy, Data, Model, Payload};
use nalgebra::{Matrix3, Vector3};

use crate::checks::joint_selection;
use crate::environment::Environment;
use crate::integrator::Integrator;
use actuator::{clamp_effort, Deadzone};
use config::PlantConfig;
use error::{check_len, SimError};
use friction::Friction;
use implicit::ImplicitSolver;
use linalg::SpdSystem;
use spring::Spring;

/// What happened in the last plant step. Per-joint vectors in chain order; torques that
/// vary within the step are their means over it (impulse / step), as the integrator
/// applied them.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord {
    /// Time at the end of the step (s).
    pub time: f64,
    /// The command as used (a non-finite value replaced by 0).
    pub command: Vec<f64>,
    /// Whether the command was non-finite (and taken as 0).
    pub command_nonfinite: Vec<bool>,
    /// Whether the command was strictly inside the dead band.
    pub in_deadzone: Vec<bool>,
    /// The deadzone output `D(tau)`.
    pub deadzone_output: Vec<f64>,
    /// The torque the actuator applied: `D(tau)` clamped to the effort limits.
    pub applied: Vec<f64>,
    /// Whether the effort limit clamped `D(tau)`.
    pub clamped: Vec<bool>,
    /// The true external torque on the arm (environment), never seen by controllers.
    pub tau_ext: Vec<f64>,
    /// The friction torque acting on the arm (`-F(qdot)`).
    pub tau_friction: Vec<f64>,
    /// The spring torque.
    pub tau_spring: Vec<f64>,
    /// The mean joint acceleration over the step `(qdot_end - qdot_start) / h`.
    pub qddot: Vec<f64>,
    /// Newton iterations of the implicit velocity updates in this step.
    pub newton_iterations: u32,
    /// The state went non-finite and the step was undone (velocity zeroed).
    pub diverged: bool,
}

impl StepRecord {
    /// A record of `n` joints, every value zero (a plant outside this crate fills the
    /// fields it has: the co-simulation of the Python package).
    pub fn new(n: usize) -> Self {
        Self {
            time: 0.0,
            command: vec![0.0; n],
            command_nonfinite: vec![false; n],
            in_deadzone: vec![false; n],
            deadzone_output: vec![0.0; n],
            applied: vec![0.0; n],
            clamped: vec![false; n],
            tau_ext: vec![0.0; n],
            tau_friction: vec![0.0; n],
            tau_spring: vec![0.0; n],
            qddot: vec![0.0; n],
            newton_iterations: 0,
            diverged: false,
        }
    }

    /// Whether any joint's command was non-finite.
    pub fn any_nonfinite_command(&self) -> bool {
        self.command_nonfinite.iter().any(|b| *b)
    }
}

/// Counters over the plant's life since construction or the last reset.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlantCounters {
    /// Plant steps taken.
    pub steps: u64,
    /// Steps whose command had a non-finite value.
    pub nonfinite_commands: u64,
    /// Steps undone because the state went non-finite.
    pub diverged: u64,
    /// Total Newton iterations of the implicit velocity updates.
    pub newton_iterations: u64,
}

/// The simulated arm.
#[derive(Clone, Debug)]
pub struct Plant {
    pub(crate) dynx: Dynamics,
    pub(crate) integrator: Integrator,
    pub(crate) h: f64,
    pub(crate) substeps: usize,
    deadzones: Vec<Deadzone>,
    effort: Vec<f64>,
    pub(crate) q: Vec<f64>,
    pub(crate) v: Vec<f64>,
    pub(crate) q_prev: Vec<f64>,
    pub(crate) v_prev: Vec<f64>,
    pub(crate) steps: u64,
    /// Integrator stage buffers: positions, velocities, accelerations, scratch.
    pub(crate) stage_q: Vec<f64>,
    pub(crate) stage_v: [Vec<f64>; 4],
    pub(crate) stage_a: [Vec<f64>; 4],
    pub(crate) dv: Vec<f64>,
    /// The balanced split's frozen forcing acceleration.
    pub(crate) balance_c: Vec<f64>,
    /// The dissipative sub-step's first stage velocity and second stage base.
    pub(crate) diss_v1: Vec<f64>,
    pub(crate) diss_w: Vec<f64>,
    /// Step accumulators (weighted sums of the torques applied in the step).
    pub(crate) acc_ext: Vec<f64>,
    pub(crate) acc_friction: Vec<f64>,
    pub(crate) acc_spring: Vec<f64>,
    pub(crate) record: StepRecord,
    pub(crate) counters: PlantCounters,
    initial_q: Vec<f64>,
    initial_v: Vec<f64>,
}

impl Plant {
    /// Builds the plant from the nominal model and a configuration (validated here).
    pub fn new(nominal: &Model, config: &PlantConfig) -> Result<Self, SimError> {
        config.validate(nominal)?;
        let n = nominal.nq();
        let substeps = config.substeps()?;

        // The true model.
        let mut scales = vec![config.inertia_scale; n];
        for (name, s) in &config.body_scales {
            if let Some(i) = nominal.joint_index(name) {
                scales[i] *= s;
            }
        }
        let mut model = if scales.iter().all(|s| *s == 1.0) {
            nominal.clone()
        } else {
            nominal.with_body_scales(&scales)?
        };
        if let Some(p) = &config.payload {
            let [ixx, iyy, izz] = p.inertia;
            let [ixy, ixz, iyz] = p.products;
            let inertia = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
            model = model.with_payload(&Payload {
                mass: p.mass,
                com: Vector3::from(p.com),
                inertia,
            })?;
        }
        let mut nominal_for_spring = nominal.clone();
        if let Some(g) = config.gravity {
            model.gravity = Vector3::from(g);
            nominal_for_spring.gravity = Vector3::from(g);
        }

        let mut friction = vec![Friction::NONE; n];
        for (k, f) in config.friction.iter().enumerate() {
            for i in joint_selection(nominal, || format!("friction[{k}].joint"), &f.joint)? {
                friction[i] = Friction {
                    viscous: f.viscous,
                    coulomb: f.coulomb,
                    v_s: f.v_s,
                };
            }
        }
        let mut deadzones = vec![Deadzone::identity(); n];
        for (k, d) in config.deadzones.iter().enumerate() {
            for i in joint_selection(nominal, || format!("deadzones[{k}].joint"), &d.joint)? {
                deadzones[i] = Deadzone {
                    d_left: d.d_left,
                    d_right: d.d_right,
                    slope_left: d.slope_left,
                    slope_right: d.slope_right,
                };
            }
        }
        let effort = model
            .effort_limits()
            .map(|e| e * config.effort_limit_scale)
            .collect();
        let spring = Spring::new(nominal, &config.spring);
        let spring_shares_gravity = spring
            .as_ref()
            .is_some_and(|s| s.is_gravity_fraction() && same_dynamics(&model, &nominal_for_spring));
        let env = Environment::new(nominal, &config.environment)?;
        let data = Data::new(&model);
        let nominal_data = Data::new(&nominal_for_spring);
        let initial_q = if config.initial_q.is_empty() {
            vec![0.0; n]
        } else {
            config.initial_q.clone()
        };
        let initial_v = if config.initial_qdot.is_empty() {
            vec![0.0; n]
        } else {
            config.initial_qdot.clone()
        };
        let mut dynx = Dynamics {
            n,
            model,
            nominal: nominal_for_spring,
            data,
            nominal_data,
            env,
            spring,
            spring_shares_gravity,
            solver: config.solver,
            phi: friction.clone(),
            friction,
            u: vec![0.0; n],
            spring_buf: vec![0.0; n],
            ext_buf: vec![0.0; n],
            tau_buf: vec![0.0; n],
            r: vec![0.0; n],
            mat: vec![0.0; n * n],
            m_state: vec![0.0; n * n],
            mass_valid: false,
            hold_mass: config.hold_mass_matrix,
            mass_held: false,
            sys: SpdSystem::new(n),
            implicit: ImplicitSolver::new(n),
        };
        dynx.implicit.set_step_tolerance(config.newton_tolerance);
        dynx.implicit
            .set_max_iterations(config.friction_solve.max_iterations());
        let vec4 = || [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        Ok(Self {
            dynx,
            integrator: config.integrator,
            h: 1.0 / config.rate_hz,
            substeps,
            deadzones,
            effort,
            q: initial_q.clone(),
            v: initial_v.clone(),
            q_prev: vec![0.0; n],
            v_prev: vec![0.0; n],
            steps: 0,
            stage_q: vec![0.0; n],
            stage_v: vec4(),
            stage_a: vec4(),
            dv: vec![0.0; n],
            balance_c: vec![0.0; n],
            diss_v1: vec![0.0; n],
            diss_w: vec![0.0; n],
            acc_ext: vec![0.0; n],
            acc_friction: vec![0.0; n],
            acc_spring: vec![0.0; n],
            record: StepRecord::new(n),
            counters: PlantCounters::default(),
            initial_q,
            initial_v,
        })
    }

    /// Number of joints.
    pub fn nq(&self) -> usize {
        self.dynx.n
    }

    /// The true model (perturbed copy of the nominal one).
    pub fn model(&self) -> &Model {
        &self.dynx.model
    }

    /// The nominal model the plant was built from (with the gravity override, if any).
    pub fn nominal_model(&self) -> &Model {
        &self.dynx.nominal
    }

    /// The integrator in use.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// The plant step (s).
    pub fn dt(&self) -> f64 {
        self.h
    }

    /// Plant steps per control period.
    pub fn substeps(&self) -> usize {
        self.substeps
    }

    /// The control period (s).
    pub fn control_dt(&self) -> f64 {
        self.h * self.substeps as f64
    }

    /// Simulated time (s): `steps * dt`, so it does not drift.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.h
    }

    /// Joint positions.
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// Joint velocities.
    pub fn qdot(&self) -> &[f64] {
        &self.v
    }

    /// Mean joint accelerations over the last step (true, not measured).
    pub fn qddot(&self) -> &[f64] {
        &self.record.qddot
    }

    /// The true external torque of the last step (for oracle observers and metrics only).
    pub fn tau_ext(&self) -> &[f64] {
        &self.record.tau_ext
    }

    /// The last step's record.
    pub fn record(&self) -> &StepRecord {
        &self.record
    }

    /// Counters since construction or the last reset.
    pub fn counters(&self) -> PlantCounters {
        self.counters
    }

    /// The effort limits applied to the actuator output (URDF effort times the scale).
    pub fn effort_limits(&self) -> &[f64] {
        &self.effort
    }

    /// The deadzone of each joint.
    pub fn deadzones(&self) -> &[Deadzone] {
        &self.deadzones
    }

    /// The friction law of each joint.
    pub fn friction(&self) -> &[Friction] {
        &self.dynx.friction
    }

    /// The environments (activity, wall forces).
    pub fn environment(&self) -> &Environment {
        &self.dynx.env
    }

    /// Back to time 0 at the configured initial state, environments and counters reset.
    pub fn reset(&mut self) {
        self.q.copy_from_slice(&self.initial_q);
        self.v.copy_from_slice(&self.initial_v);
        self.steps = 0;
        self.dynx.env.reset();
        self.dynx.mass_valid = false;
        self.dynx.mass_held = false;
        self.record = StepRecord::new(self.dynx.n);
        self.counters = PlantCounters::default();
    }

    /// Sets the joint state, keeping the time.
    pub fn set_state(&mut self, q: &[f64], qdot: &[f64]) -> Result<(), SimError> {
        let n = self.dynx.n;
        check_len("q", q, n)?;
        check_len("qdot", qdot, n)?;
        if q.iter().chain(qdot).any(|x| !x.is_finite()) {
            return Err(SimError::config(
                "state",
                "positions and velocities must be finite",
            ));
        }
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(qdot);
        self.dynx.mass_valid = false;
        self.dynx.mass_held = false;
        Ok(())
    }

    /// Kinetic and potential energy of the true arm at the current state (J); the
    /// spring's and the environments' energy are not included.
    pub fn energy(&mut self) -> (f64, f64) {
        let d = &mut self.dynx;
        let ke = kinetic_energy(&d.model, &mut d.data, &self.q, &self.v).unwrap_or(f64::NAN);
        let pe = potential_energy(&d.model, &mut d.data, &self.q).unwrap_or(f64::NAN);
        (ke, pe)
    }

    /// The actuator: deadzone then effort clamp, into `dynx.u` and the record.
    fn actuate(&mut self, tau: &[f64]) -> bool {
        let mut nonfinite = false;
        let rec = &mut self.record;
        for i in 0..self.dynx.n {
            let (cmd, bad) = if tau[i].is_finite() {
                (tau[i], false)
            } else {
                (0.0, true)
            };
            nonfinite |= bad;
            let dz = &self.deadzones[i];
            let out = dz.apply(cmd);
            let (applied, clamped) = clamp_effort(out, self.effort[i]);
            rec.command[i] = cmd;
            rec.command_nonfinite[i] = bad;
            rec.in_deadzone[i] = dz.contains(cmd);
            rec.deadzone_output[i] = out;
            rec.applied[i] = applied;
            rec.clamped[i] = clamped;
            self.dynx.u[i] = applied;
        }
        nonfinite
    }

    /// One plant step of `dt` with the joint command `tau` (before deadzone and limits).
    /// Does not allocate; a non-finite command value is taken as zero and reported.
    pub fn step(&mut self, tau: &[f64]) -> Result<&StepRecord, SimError> {
        check_len("tau", tau, self.dynx.n)?;
        self.dynx.mass_held = false;
        self.step_inner(tau);
        Ok(&self.record)
    }

    /// One control period: `substeps` plant steps with `tau` held (zero-order hold).
    /// Returns the record of the last plant step.
    pub fn step_control(&mut self, tau: &[f64]) -> Result<&StepRecord, SimError> {
        check_len("tau", tau, self.dynx.n)?;
        // A held mass matrix is computed at the period's first step.
        self.dynx.mass_held = false;
        for _ in 0..self.substeps {
            self.step_inner(tau);
        }
        Ok(&self.record)
    }

    fn step_inner(&mut self, tau: &[f64]) {
        let nonfinite = self.actuate(tau);
        let t = self.time();
        self.q_prev.copy_from_slice(&self.q);
        self.v_prev.copy_from_slice(&self.v);
        self.acc_ext.fill(0.0);
        self.acc_friction.fill(0.0);
        self.acc_spring.fill(0.0);
        self.record.newton_iterations = 0;
        {
            let d = &mut self.dynx;
            d.env.begin_step(t, &self.q);
            let damping = d.env.damping_diag();
            for i in 0..d.n {
                d.phi[i] = Friction {
                    viscous: d.friction[i].viscous + damping[i],
                    ..d.friction[i]
                };
            }
        }
        let ok = match self.integrator {
            Integrator::SemiImplicitEuler => self.step_semi_implicit_euler(t),
            Integrator::Rk4Split => self.step_rk4_split(t),
        };
        self.steps += 1;
        self.counters.steps += 1;
        self.counters.newton_iterations += self.record.newton_iterations as u64;
        if nonfinite {
            self.counters.nonfinite_commands += 1;
        }
        let finite = ok && self.q.iter().chain(&self.v).all(|x| x.is_finite());
        let rec = &mut self.record;
        rec.time = self.steps as f64 * self.h;
        rec.diverged = !finite;
        if finite {
            let inv_h = 1.0 / self.h;
            let me = self.dynx.env.mass_diag();
            for i in 0..self.dynx.n {
                let a = (self.v[i] - self.v_prev[i]) * inv_h;
                rec.qddot[i] = a;
                rec.tau_ext[i] = self.acc_ext[i] - me[i] * a;
                rec.tau_friction[i] = self.acc_friction[i];
                rec.tau_spring[i] = self.acc_spring[i];
            }
        } else {
            self.counters.diverged += 1;
            self.q.copy_from_slice(&self.q_prev);
            self.v.fill(0.0);
            rec.qddot.fill(0.0);
            rec.tau_ext.fill(0.0);
            rec.tau_friction.fill(0.0);
            rec.tau_spring.fill(0.0);
            self.dynx.mass_valid = false;
            self.dynx.mass_held = false;
        }
    }
}

/// Whether two models give the same `G(q)` by the same operations: the same joints
/// (kind, axis, placement), bodies and gravity.
fn same_dynamics(a: &Model, b: &Model) -> bool {
    a.gravity == b.gravity
        && a.bodies == b.bodies
        && a.joints.len() == b.joints.len()
        && a.joints
            .iter()
            .zip(&b.joints)
            .all(|(x, y)| x.kind == y.kind && x.axis == y.axis && x.placement == y.placement)
}
