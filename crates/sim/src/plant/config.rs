//! Serde configuration of the plant (docs/method.md section 1): what a scenario file says
//! about the simulated arm. Every struct rejects unknown keys and has defaults, so a
//! scenario only writes what differs from an ideal, frictionless, unperturbed arm.
//!
//! ```toml
//! rate_hz = 5000.0
//! control_rate_hz = 1000.0
//! integrator = "rk4_split"          # or "semi_implicit_euler"
//! inertia_scale = 1.2               # the true arm is 20 % heavier than the nominal one
//! effort_limit_scale = 1.0
//! friction_solve = "newton"        # approximations for speed, off by default
//! hold_mass_matrix = false          # (accuracy: docs/benchmarks.md, "Closed loop")
//! newton_tolerance = 1e-12
//! initial_q = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5]
//!
//! [[friction]]
//! joint = "*"                       # every joint; later entries override
//! viscous = 0.7
//! coulomb = 0.5
//! v_s = 0.01
//!
//! [[deadzones]]
//! joint = "left_s0"
//! d_left = -0.49
//! d_right = 0.49
//!
//! [spring]
//! enabled = true                    # Baxter's s1 counterbalance
//!
//! [[environment.joint_springs]]
//! joints = ["left_s0"]
//! mass = [0.01]
//! damping = [0.15]
//! stiffness = [1.1]
//! t_start = 12.0
//! t_end = 30.0
//!
//! [sensors]
//! resolution_rad = 1e-5
//! noise_std = 1e-4
//! seed = 7
//! filter_cutoff_hz = 20.0
//! ```

use std::collections::BTreeMap;

use admittance_dynamics::Model;
use serde::{Deserialize, Serialize};

use crate::checks::{finite, joint_index, joint_selection, non_negative, positive};
use crate::environment::EnvironmentConfig;
use crate::integrator::Integrator;
use crate::plant::error::SimError;
use crate::sensors::SensorConfig;

/// The complete description of the simulated plant and its sensors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantConfig {
    /// Plant integration rate (Hz); the plant step is `1 / rate_hz`. Default 5000.
    pub rate_hz: f64,
    /// Control rate (Hz): the command is held (zero-order hold) for
    /// `rate_hz / control_rate_hz` plant steps, which must be a whole number. Default 1000.
    pub control_rate_hz: f64,
    /// Integration scheme. Default [`Integrator::Rk4Split`].
    pub integrator: Integrator,
    /// How accelerations are obtained when no term couples through the mass matrix.
    /// Default [`Solver::Auto`].
    pub solver: Solver,
    /// Every body's mass and inertia multiplied by this (the true arm against the
    /// nominal model). Default 1.
    pub inertia_scale: f64,
    /// Further per-body multipliers by joint name, on top of `inertia_scale`.
    pub body_scales: BTreeMap<String, f64>,
    /// A rigid payload at the tip frame of the true arm (the nominal model does not know it).
    pub payload: Option<PayloadConfig>,
    /// Gravity in the base frame, overriding the model's (e.g. `[0, 0, 0]` for tests).
    pub gravity: Option<[f64; 3]>,
    /// The URDF effort limits are multiplied by this before clamping the actuator
    /// output. Default 1.
    pub effort_limit_scale: f64,
    /// Joint friction, per joint; `joint = "*"` applies to all joints; later entries
    /// override earlier ones. Default: none.
    pub friction: Vec<FrictionConfig>,
    /// Actuator deadzones, per joint (same rules as `friction`). Default: none.
    pub deadzones: Vec<DeadzoneConfig>,
    /// The counterbalance spring. Default: off.
    pub spring: SpringConfig,
    /// Environments acting on the arm in time windows. Default: none.
    pub environment: EnvironmentConfig,
    /// Encoders and filtered differentiation.
    pub sensors: SensorConfig,
    /// Initial joint positions in chain order; empty means all zero.
    pub initial_q: Vec<f64>,
    /// Initial joint velocities in chain order; empty means all zero.
    pub initial_qdot: Vec<f64>,
    /// An approximation for speed, off by default: the mass matrix `M(q)` is computed at
    /// the first plant step of each control period and held over the period's other steps
    /// (the bias `C qdot + G` is still computed at every step). Its accuracy against the
    /// exact plant and its speed are in docs/benchmarks.md ("Closed loop").
    pub hold_mass_matrix: bool,
    /// The implicit friction solve's Newton iteration stops once a step is at most this
    /// times the velocity scale `max(1, |qdot|)` (rad/s). Default 1e-12 (the exact plant);
    /// larger values, up to 1e-3, save iterations (near the solution the remaining error is
    /// about the square of the last step): an approximation for speed, measured in
    /// docs/benchmarks.md ("Closed loop").
    pub newton_tolerance: f64,
    /// How the implicit friction update is solved. Default [`FrictionSolve::Newton`] (the
    /// exact plant); [`FrictionSolve::Linearized`] is an approximation for speed.
    pub friction_solve: FrictionSolve,
}

impl Default for PlantConfig {
    fn default() -> Self {
        Self {
            rate_hz: 5000.0,
            control_rate_hz: admittance_loop::DEFAULT_CONTROL_RATE_HZ,
            integrator: Integrator::default(),
            solver: Solver::default(),
            inertia_scale: 1.0,
            body_scales: BTreeMap::new(),
            payload: None,
            gravity: None,
            effort_limit_scale: 1.0,
            friction: Vec::new(),
            deadzones: Vec::new(),
            spring: SpringConfig::default(),
            environment: EnvironmentConfig::default(),
            sensors: SensorConfig::default(),
            initial_q: Vec::new(),
            initial_qdot: Vec::new(),
            hold_mass_matrix: false,
            newton_tolerance: crate::plant::implicit::DEFAULT_STEP_TOLERANCE,
            friction_solve: FrictionSolve::default(),
        }
    }
}

/// How the plant solves its implicit friction update `A dv + h phi(v + dv) = h r`
/// (crates/sim/src/plant/implicit.rs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionSolve {
    /// Newton's method until a step is below `newton_tolerance` (about 2.5 iterations per
    /// step in experiment A): the exact plant.
    #[default]
    Newton,
    /// One Newton step from the step's starting velocity, with its line search: the
    /// friction linearised at the start of each plant step (a linearly implicit update, as
    /// MuJoCo's implicit integrators treat velocity-dependent forces). One matrix
    /// factorisation per solve instead of two or three; its accuracy against the exact
    /// plant and its speed are in docs/benchmarks.md ("Closed loop").
    Linearized,
}

impl FrictionSolve {
    /// The Newton iterations the solve may take.
    pub(crate) fn max_iterations(self) -> u32 {
        match self {
            FrictionSolve::Newton => crate::plant::implicit::MAX_ITERATIONS,
            FrictionSolve::Linearized => 1,
        }
    }
}

/// How the step obtains joint accelerations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// The articulated-body algorithm for every acceleration that needs no matrix (no
    /// environment mass acting, and for semi-implicit Euler no friction or environment
    /// damping, which it solves implicitly with the matrix); CRBA + RNEA + an in-place
    /// Cholesky solve otherwise. (On Baxter at 5 kHz ABA was the faster of the two: 1.35
    /// against 1.41 us per semi-implicit Euler step, 4.9 against 5.1 us per RK4 step.)
    #[default]
    Auto,
    /// Always CRBA + RNEA + Cholesky.
    Cholesky,
}

/// Joint friction `F(qdot) = viscous qdot + coulomb tanh(qdot / v_s)` (N m, per joint),
/// unknown to the controller. The plant treats it implicitly (see [`crate::integrator`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionConfig {
    /// Joint name, or `"*"` for every joint.
    pub joint: String,
    /// Viscous coefficient Fv (N m s/rad), >= 0.
    pub viscous: f64,
    /// Coulomb level Fc (N m), >= 0.
    pub coulomb: f64,
    /// Velocity scale of the tanh (rad/s), > 0. Default 0.01.
    pub v_s: f64,
}

impl Default for FrictionConfig {
    fn default() -> Self {
        Self {
            joint: "*".into(),
            viscous: 0.0,
            coulomb: 0.0,
            v_s: 0.01,
        }
    }
}

/// Actuator deadzone of one joint (docs/method.md eq. 17, typo fixed):
/// `D(tau) = slope_right (tau - d_right)` for `tau >= d_right`, `0` inside, and
/// `slope_left (tau - d_left)` for `tau <= d_left`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeadzoneConfig {
    /// Joint name, or `"*"` for every joint.
    pub joint: String,
    /// Left breakpoint d_l (N m), <= 0.
    pub d_left: f64,
    /// Right breakpoint d_r (N m), >= 0.
    pub d_right: f64,
    /// Slope m_l beyond the left breakpoint, > 0. Default 1.
    pub slope_left: f64,
    /// Slope m_r beyond the right breakpoint, > 0. Default 1.
    pub slope_right: f64,
}

impl Default for DeadzoneConfig {
    fn default() -> Self {
        Self {
            joint: "*".into(),
            d_left: 0.0,
            d_right: 0.0,
            slope_left: 1.0,
            slope_right: 1.0,
        }
    }
}

/// The law of the counterbalance spring.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpringModel {
    /// `tau_spring = fraction * G_j(q)` with `G_j` the gravity torque on the spring's
    /// joint of the *nominal* model (before inertia scaling and payload): a spring tuned
    /// to cancel that fraction of the arm's own weight at every pose. It needs one
    /// gravity pass of the nominal model per force evaluation.
    #[default]
    GravityFraction,
    /// `tau_spring = k0 + k1 cos(q_j + phase)`: a spring that depends on its own joint
    /// only, like a physical one.
    Cosine,
}

/// Baxter's shoulder (s1) counterbalance spring: a passive joint torque, not subject to
/// the deadzone or the effort limits. The URDF does not model it; without it the gravity
/// torque on s1 at q = 0 (-52.9 N m) exceeds s1's 50 N m effort limit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpringConfig {
    /// Off by default; scenarios of the Baxter arm turn it on.
    pub enabled: bool,
    /// The joint it acts on. Default `"left_s1"`.
    pub joint: String,
    /// The spring law. Default [`SpringModel::GravityFraction`].
    pub model: SpringModel,
    /// For `gravity_fraction`: the fraction of the nominal gravity torque cancelled, in
    /// [0, 1]. Default 0.5 (leaves about 27 N m of s1's 50 N m for gravity at worst).
    pub fraction: f64,
    /// For `cosine`: constant term (N m).
    pub k0: f64,
    /// For `cosine`: amplitude (N m).
    pub k1: f64,
    /// For `cosine`: phase (rad).
    pub phase: f64,
}

impl Default for SpringConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            joint: "left_s1".into(),
            model: SpringModel::GravityFraction,
            fraction: 0.5,
            k0: 0.0,
            k1: 0.0,
            phase: 0.0,
        }
    }
}

/// A rigid payload carried at the tip frame of the true arm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PayloadConfig {
    /// Mass (kg), >= 0.
    pub mass: f64,
    /// Centre of mass in the tip frame (m).
    pub com: [f64; 3],
    /// Principal moments about the centre of mass, tip-frame axes: `[ixx, iyy, izz]` (kg m^2).
    pub inertia: [f64; 3],
    /// Products of inertia `[ixy, ixz, iyz]` (kg m^2). Default zero.
    pub products: [f64; 3],
}

impl Default for PayloadConfig {
    fn default() -> Self {
        Self {
            mass: 0.0,
            com: [0.0; 3],
            inertia: [0.0; 3],
            products: [0.0; 3],
        }
    }
}

/// The highest plant rate (Hz): a 1 us step, 200 times finer than the scenarios' 5 kHz.
/// Beyond it a run's work grows without improving anything the controller can see.
pub const MAX_RATE_HZ: f64 = 1e6;

impl PlantConfig {
    /// Number of plant steps per control period (`rate_hz / control_rate_hz`), after
    /// checking that both rates are positive and the ratio is a whole number.
    pub fn substeps(&self) -> Result<usize, SimError> {
        positive(|| "rate_hz".into(), self.rate_hz)?;
        positive(|| "control_rate_hz".into(), self.control_rate_hz)?;
        if self.rate_hz > MAX_RATE_HZ {
            return Err(SimError::config(
                "rate_hz",
                format!(
                    "{} Hz is beyond the {MAX_RATE_HZ} Hz this simulator supports (a 1 us step; the scenarios use 5 kHz)",
                    self.rate_hz
                ),
            ));
        }
        let ratio = self.rate_hz / self.control_rate_hz;
        let rounded = ratio.round();
        if rounded < 1.0 || (ratio - rounded).abs() > 1e-9 * ratio {
            return Err(SimError::config(
                "rate_hz",
                format!(
                    "the plant rate ({} Hz) must be a whole multiple (>= 1) of control_rate_hz ({} Hz)",
                    self.rate_hz, self.control_rate_hz
                ),
            ));
        }
        Ok(rounded as usize)
    }

    /// Checks every value against its domain and every name against `model` (the
    /// nominal model the plant is built from). [`crate::Plant::new`] calls it.
    pub fn validate(&self, model: &Model) -> Result<(), SimError> {
        let n = model.nq();
        self.substeps()?;
        positive(|| "inertia_scale".into(), self.inertia_scale)?;
        for (name, s) in &self.body_scales {
            joint_index(model, || format!("body_scales.{name}"), name)?;
            positive(|| format!("body_scales.{name}"), *s)?;
        }
        if let Some(p) = &self.payload {
            non_negative(|| "payload.mass".into(), p.mass)?;
            for (k, v) in p.com.iter().enumerate() {
                finite(|| format!("payload.com[{k}]"), *v)?;
            }
            for (k, v) in p.inertia.iter().enumerate() {
                non_negative(|| format!("payload.inertia[{k}]"), *v)?;
            }
            for (k, v) in p.products.iter().enumerate() {
                finite(|| format!("payload.products[{k}]"), *v)?;
            }
        }
        if let Some(g) = &self.gravity {
            for (k, v) in g.iter().enumerate() {
                finite(|| format!("gravity[{k}]"), *v)?;
            }
        }
        positive(|| "effort_limit_scale".into(), self.effort_limit_scale)?;
        if !(self.newton_tolerance > 0.0 && self.newton_tolerance <= 1e-3) {
            return Err(SimError::config(
                "newton_tolerance",
                format!(
                    "must be in (0, 1e-3], got {} (default 1e-12: the exact plant)",
                    self.newton_tolerance
                ),
            ));
        }
        for (k, f) in self.friction.iter().enumerate() {
            joint_selection(model, || format!("friction[{k}].joint"), &f.joint)?;
            non_negative(|| format!("friction[{k}].viscous"), f.viscous)?;
            non_negative(|| format!("friction[{k}].coulomb"), f.coulomb)?;
            positive(|| format!("friction[{k}].v_s"), f.v_s)?;
        }
        for (k, d) in self.deadzones.iter().enumerate() {
            joint_selection(model, || format!("deadzones[{k}].joint"), &d.joint)?;
            finite(|| format!("deadzones[{k}].d_left"), d.d_left)?;
            if d.d_left > 0.0 {
                return Err(SimError::config(
                    format!("deadzones[{k}].d_left"),
                    format!("must be <= 0, got {}", d.d_left),
                ));
            }
            non_negative(|| format!("deadzones[{k}].d_right"), d.d_right)?;
            positive(|| format!("deadzones[{k}].slope_left"), d.slope_left)?;
            positive(|| format!("deadzones[{k}].slope_right"), d.slope_right)?;
        }
        if self.spring.enabled {
            let s = &self.spring;
            joint_index(model, || "spring.joint".into(), &s.joint)?;
            match s.model {
                SpringModel::GravityFraction => {
                    if !(s.fraction.is_finite() && (0.0..=1.0).contains(&s.fraction)) {
                        return Err(SimError::config(
                            "spring.fraction",
                            format!("must be in [0, 1], got {}", s.fraction),
                        ));
                    }
                }
                SpringModel::Cosine => {
                    finite(|| "spring.k0".into(), s.k0)?;
                    finite(|| "spring.k1".into(), s.k1)?;
                    finite(|| "spring.phase".into(), s.phase)?;
                }
            }
        }
        self.environment.validate(model, "environment")?;
        self.sensors
            .validate(model, self.control_rate_hz, "sensors")?;
        for (key, values) in [
            ("initial_q", &self.initial_q),
            ("initial_qdot", &self.initial_qdot),
        ] {
            if !values.is_empty() && values.len() != n {
                return Err(SimError::config(
                    key,
                    format!(
                        "has {} values but the model has {n} joints (leave it empty for zeros)",
                        values.len()
                    ),
                ));
            }
            for (k, v) in values.iter().enumerate() {
                finite(|| format!("{key}[{k}]"), *v)?;
            }
        }
        Ok(())
    }
}
