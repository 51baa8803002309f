//! The joint-space admittance model and the smooth reference saturation (docs/method.md
//! section 2, the paper's eq. 5-7).
//!
//! ```text
//!     M_d (q_a'' - q_d'') + C_d (q_a' - q_d') + G_d (q_a - q_d) = tau_ext_hat     (eq. 6, METHOD sign)
//!     q_r = c + sat(q_a - c)                                                    (eq. 7)
//! ```
//!
//! Without `M_d` this is `q_a' = q_d' + C_d^-1 (tau_ext_hat - G_d (q_a - q_d))`: the reference
//! yields in the direction of the external torque and settles at
//! `q_a - q_d = G_d^-1 tau_ext_hat`.

use serde::{Deserialize, Serialize};

use crate::config::{Bound, JointValues};
use crate::error::{ConfigError, Fault, StepStatus};
use crate::safe_hold::first_non_finite;

/// Saturation of the admittance state (docs/method.md section 2, eq. 7), per joint.
///
/// Joint `i` keeps `q_r,i` strictly inside `(centre_i - half_range_i, centre_i + half_range_i)`.
/// A joint whose `half_range` is `+inf` is not saturated (`q_r = q_a`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaturationConfig {
    /// `rho` in `(0, 1)`: the linear zone is `|q_a - c| <= rho C` (paper: 0.95).
    pub rho: f64,
    /// Centre `c` of the allowed interval per joint (default 0).
    #[serde(default = "zero")]
    pub centre: JointValues,
    /// Half-range `C > 0` per joint (paper: 1.1); `+inf` disables the saturation of that joint.
    pub half_range: JointValues,
}

fn zero() -> JointValues {
    JointValues::Uniform(0.0)
}

impl SaturationConfig {
    /// The interval `[lower_i, upper_i]` per joint: `c = (lo + hi) / 2`, `C = (hi - lo) / 2`;
    /// a joint without two finite limits is not saturated (`c = 0`, `C = +inf`).
    pub fn from_limits(rho: f64, lower: &[f64], upper: &[f64]) -> Self {
        let (centre, half_range) = lower
            .iter()
            .zip(upper)
            .map(|(&l, &u)| {
                if l.is_finite() && u.is_finite() {
                    (0.5 * (l + u), 0.5 * (u - l))
                } else {
                    (0.0, f64::INFINITY)
                }
            })
            .unzip();
        SaturationConfig {
            rho,
            centre: JointValues::PerJoint(centre),
            half_range: JointValues::PerJoint(half_range),
        }
    }
}

/// Configuration of [`Admittance`] (docs/method.md section 2). Paper: `C_d = 3`, `G_d = 5`,
/// no `M_d`, `rho = 0.95`, `C = 1.1`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdmittanceConfig {
    /// Damping `C_d > 0` (N m s/rad).
    pub damping: JointValues,
    /// Stiffness `G_d > 0` (N m/rad).
    pub stiffness: JointValues,
    /// Optional inertia `M_d > 0` (kg m^2): makes the model second order.
    #[serde(default)]
    pub inertia: Option<JointValues>,
    /// Optional reference saturation (eq. 7).
    #[serde(default)]
    pub saturation: Option<SaturationConfig>,
}

impl AdmittanceConfig {
    /// The paper's values: `C_d = 3`, `G_d = 5`, saturation `rho = 0.95`, `C = 1.1` about 0
    /// on every joint.
    pub fn paper() -> Self {
        AdmittanceConfig {
            damping: JointValues::Uniform(3.0),
            stiffness: JointValues::Uniform(5.0),
            inertia: None,
            saturation: Some(SaturationConfig {
                rho: 0.95,
                centre: zero(),
                half_range: JointValues::Uniform(1.1),
            }),
        }
    }
}

/// The smooth saturation of eq. 7 for one joint, centred: `y = q_a - c`, returns
/// `(sat(y), sat'(y), sat''(y))` with `gamma = (1 - rho) C`:
///
/// ```text
///     sat(y) = -gamma (1 - exp((y + rho C) / gamma)) - rho C    if y < -rho C
///            =  y                                               if |y| <= rho C
///            =  gamma (1 - exp((rho C - y) / gamma)) + rho C    if y > rho C
/// ```
///
/// Continuous and once differentiable at `+-rho C` (value `+-rho C`, slope 1 on both
/// sides), strictly increasing, `|sat(y)| < C` in exact arithmetic (in floating point,
/// `sat(y)` reaches `+-C` for `|y| - rho C` beyond about `37 gamma`: [`Saturation::apply`]
/// keeps the final `q_r` strictly inside the interval). `sat''` jumps at `+-rho C` (from 0
/// to `-+1/gamma`). Requires `0 < rho < 1`, `C > 0`; `C = +inf` returns `(y, 1, 0)`.
#[inline]
pub fn saturate(y: f64, rho: f64, half_range: f64) -> (f64, f64, f64) {
    if half_range == f64::INFINITY {
        return (y, 1.0, 0.0);
    }
    let knee = rho * half_range;
    let gamma = (1.0 - rho) * half_range;
    if y > knee {
        let e = ((knee - y) / gamma).exp();
        (gamma * (1.0 - e) + knee, e, -e / gamma)
    } else if y < -knee {
        let e = ((y + knee) / gamma).exp();
        (-gamma * (1.0 - e) - knee, e, e / gamma)
    } else {
        (y, 1.0, 0.0)
    }
}

/// The largest float strictly below `x` (finite `x`).
fn next_down(x: f64) -> f64 {
    if x == 0.0 {
        -f64::from_bits(1)
    } else if x > 0.0 {
        f64::from_bits(x.to_bits() - 1)
    } else {
        f64::from_bits(x.to_bits() + 1)
    }
}

/// The smallest float strictly above `x` (finite `x`).
fn next_up(x: f64) -> f64 {
    -next_down(-x)
}

/// The per-joint saturation (eq. 7 with centre `c` and half-range `C` per joint).
#[derive(Clone, Debug, PartialEq)]
pub struct Saturation {
    rho: f64,
    centre: Vec<f64>,
    half_range: Vec<f64>,
    /// Strict bounds: `(next_up(c - C), next_down(c + C))`.
    inner: Vec<(f64, f64)>,
}

impl Saturation {
    /// Validates `config` for `n` joints.
    pub fn new(n: usize, config: &SaturationConfig) -> Result<Self, ConfigError> {
        let rho = config.rho;
        if !(rho > 0.0 && rho < 1.0) {
            return Err(ConfigError::new(
                "rho",
                format!("is {rho}, must lie strictly between 0 and 1"),
            )
            .hint("the paper uses 0.95"));
        }
        let centre = config.centre.resolve("centre", n, Bound::Finite)?;
        let half_range = match &config.half_range {
            JointValues::Uniform(v) if *v == f64::INFINITY => vec![f64::INFINITY; n],
            JointValues::PerJoint(vs) if vs.len() == n => vs
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    if v == f64::INFINITY {
                        Ok(v)
                    } else {
                        Bound::Positive.check(&format!("half_range[{i}]"), v)
                    }
                })
                .collect::<Result<Vec<_>, _>>()?,
            other => other.resolve("half_range", n, Bound::Positive)?,
        };
        let mut inner = Vec::with_capacity(n);
        for i in 0..n {
            let (c, h) = (centre[i], half_range[i]);
            if h.is_finite() {
                let (lo, hi) = (c - h, c + h);
                if !(lo.is_finite() && hi.is_finite() && next_up(lo) < next_down(hi)) {
                    return Err(ConfigError::new(
                        format!("half_range[{i}]"),
                        format!("interval [{lo}, {hi}] is empty or not finite in floating point"),
                    ));
                }
                inner.push((next_up(lo), next_down(hi)));
            } else {
                inner.push((f64::NEG_INFINITY, f64::INFINITY));
            }
        }
        Ok(Saturation {
            rho,
            centre,
            half_range,
            inner,
        })
    }

    /// `rho`.
    pub fn rho(&self) -> f64 {
        self.rho
    }

    /// Centres `c` per joint.
    pub fn centre(&self) -> &[f64] {
        &self.centre
    }

    /// Half-ranges `C` per joint.
    pub fn half_range(&self) -> &[f64] {
        &self.half_range
    }

    /// `(q_r, dq_r/dq_a, d2q_r/dq_a2)` for joint `i` at admittance state `q_a`; `q_r` lies
    /// strictly inside `(c - C, c + C)` for every finite `q_a` (and for `+-inf`).
    #[inline]
    pub fn apply(&self, i: usize, q_a: f64) -> (f64, f64, f64) {
        let c = self.centre[i];
        let (s, ds, dds) = saturate(q_a - c, self.rho, self.half_range[i]);
        let (lo, hi) = self.inner[i];
        ((c + s).clamp(lo, hi), ds, dds)
    }
}

/// Input of one [`Admittance`] step: the desired trajectory and the torque estimate.
#[derive(Clone, Copy, Debug)]
pub struct AdmittanceInput<'a> {
    /// Desired position `q_d`.
    pub q_d: &'a [f64],
    /// Desired velocity `q_d'`.
    pub qdot_d: &'a [f64],
    /// Desired acceleration `q_d''`.
    pub qddot_d: &'a [f64],
    /// Estimated external torque `tau_ext_hat` (docs/method.md section 0 sign).
    pub external_torque_estimate: &'a [f64],
}

/// The admittance model with reference saturation (docs/method.md section 2).
///
/// State: the deviation `x = q_a - q_d` (and `x'` with `M_d`), zero after construction and
/// [`reset`](Self::reset), so that with zero `tau_ext_hat` the admittance state is exactly
/// `q_a = q_d` (and `q_r = q_d` while `q_d` is in the linear zone of the saturation).
///
/// Integration over a step `dt`, with `tau_ext_hat` held over the step (zero-order hold):
/// * first order (no `M_d`): exact, `x <- x_ss + (x - x_ss) exp(-G_d dt / C_d)` with
///   `x_ss = tau_ext_hat / G_d`; then `x' = (tau_ext_hat - G_d x) / C_d`,
///   `x'' = -(G_d / C_d) x'` (the estimate's own derivative is not known and taken as zero);
/// * second order: backward (implicit) Euler, unconditionally stable with the exact steady
///   state: `x' <- (M_d x' + dt (tau - G_d x)) / (M_d + dt C_d + dt^2 G_d)`,
///   `x <- x + dt x'`, `x'' = (tau - C_d x' - G_d x) / M_d`.
///
/// Outputs: `q_a = q_d + x`, `q_a' = q_d' + x'`, `q_a'' = q_d'' + x''`, and by the chain rule
/// `q_r = sat(q_a)`, `q_r' = sat'(q_a) q_a'`, `q_r'' = sat''(q_a) q_a'^2 + sat'(q_a) q_a''`.
///
/// On a fault (wrong lengths, non-finite input, invalid `dt`) the state is not changed, the
/// outputs keep the last `q_r` with zero velocity and acceleration (a reference to hold), and
/// the fault is returned. `step` neither allocates nor panics.
#[derive(Clone, Debug)]
pub struct Admittance {
    n: usize,
    damping: Vec<f64>,
    stiffness: Vec<f64>,
    inertia: Option<Vec<f64>>,
    saturation: Option<Saturation>,
    /// Per-joint deadband on the estimate (issue 31, item 3); empty: none.
    deadband: Vec<f64>,
    x: Vec<f64>,
    xdot: Vec<f64>,
    q_a: Vec<f64>,
    qdot_a: Vec<f64>,
    qddot_a: Vec<f64>,
    q_r: Vec<f64>,
    qdot_r: Vec<f64>,
    qddot_r: Vec<f64>,
    has_output: bool,
}

impl Admittance {
    /// An admittance model for `n` joints.
    pub fn new(n: usize, config: &AdmittanceConfig) -> Result<Self, ConfigError> {
        let damping = config.damping.resolve("damping", n, Bound::Positive)?;
        let stiffness = config.stiffness.resolve("stiffness", n, Bound::Positive)?;
        let inertia = match &config.inertia {
            Some(m) => Some(m.resolve("inertia", n, Bound::Positive)?),
            None => None,
        };
        let saturation = match &config.saturation {
            Some(s) => Some(Saturation::new(n, s).map_err(|e| e.within("saturation"))?),
            None => None,
        };
        Ok(Admittance {
            n,
            damping,
            stiffness,
            inertia,
            saturation,
            deadband: Vec::new(),
            x: vec![0.0; n],
            xdot: vec![0.0; n],
            q_a: vec![0.0; n],
            qdot_a: vec![0.0; n],
            qddot_a: vec![0.0; n],
            q_r: vec![0.0; n],
            qdot_r: vec![0.0; n],
            qddot_r: vec![0.0; n],
            has_output: false,
        })
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// The same model with a deadband on the estimate per joint (N m; docs/method.md
    /// section 2, "Deadband"; issue 31, item 3), e.g. a contact floor's thresholds: an
    /// estimate within it moves nothing, above it only the excess drives the model, through
    /// the smooth knee of [`soft_deadband`](crate::soft_deadband). Values of 0 leave a joint
    /// as without a deadband (the default).
    pub fn with_deadband(mut self, deadband: &[f64]) -> Result<Self, ConfigError> {
        self.set_deadband(deadband)?;
        Ok(self)
    }

    /// Sets the deadband in place (see `with_deadband`); on an error nothing changes.
    pub fn set_deadband(&mut self, deadband: &[f64]) -> Result<(), ConfigError> {
        self.deadband = crate::contact::checked_deadband(deadband, self.n)?;
        Ok(())
    }

    /// The deadband per joint (empty when there is none).
    pub fn deadband(&self) -> &[f64] {
        &self.deadband
    }

    /// The saturation, if configured.
    pub fn saturation(&self) -> Option<&Saturation> {
        self.saturation.as_ref()
    }

    /// Back to `q_a = q_d` (zero deviation).
    pub fn reset(&mut self) {
        self.x.fill(0.0);
        self.xdot.fill(0.0);
        self.has_output = false;
        for v in [
            &mut self.q_a,
            &mut self.qdot_a,
            &mut self.qddot_a,
            &mut self.q_r,
            &mut self.qdot_r,
            &mut self.qddot_r,
        ] {
            v.fill(0.0);
        }
    }

    /// Advances the model by `dt` with `input` and computes the reference (see the type's
    /// documentation).
    pub fn step(&mut self, input: &AdmittanceInput, dt: f64) -> StepStatus {
        if let Err(fault) = self.check(input, dt) {
            self.qdot_r.fill(0.0);
            self.qddot_r.fill(0.0);
            if !self.has_output {
                // Nothing to hold yet: hold the desired position where it is finite.
                for (r, d) in self.q_r.iter_mut().zip(input.q_d) {
                    if d.is_finite() {
                        *r = *d;
                    }
                }
            }
            return StepStatus::Fault(fault);
        }
        for i in 0..self.n {
            let mut tau = input.external_torque_estimate[i];
            if let Some(&d) = self.deadband.get(i) {
                tau = crate::contact::soft_deadband(tau, d);
            }
            let (c, g) = (self.damping[i], self.stiffness[i]);
            let xddot;
            match &self.inertia {
                None => {
                    let x_ss = tau / g;
                    self.x[i] = x_ss + (self.x[i] - x_ss) * (-g * dt / c).exp();
                    self.xdot[i] = (tau - g * self.x[i]) / c;
                    xddot = -(g / c) * self.xdot[i];
                }
                Some(m) => {
                    let m = m[i];
                    let v = (m * self.xdot[i] + dt * (tau - g * self.x[i]))
                        / (m + dt * c + dt * dt * g);
                    self.xdot[i] = v;
                    self.x[i] += dt * v;
                    xddot = (tau - c * v - g * self.x[i]) / m;
                }
            }
            self.q_a[i] = input.q_d[i] + self.x[i];
            self.qdot_a[i] = input.qdot_d[i] + self.xdot[i];
            self.qddot_a[i] = input.qddot_d[i] + xddot;
            match &self.saturation {
                Some(sat) => {
                    let (r, ds, dds) = sat.apply(i, self.q_a[i]);
                    self.q_r[i] = r;
                    self.qdot_r[i] = ds * self.qdot_a[i];
                    self.qddot_r[i] = dds * self.qdot_a[i] * self.qdot_a[i] + ds * self.qddot_a[i];
                }
                None => {
                    self.q_r[i] = self.q_a[i];
                    self.qdot_r[i] = self.qdot_a[i];
                    self.qddot_r[i] = self.qddot_a[i];
                }
            }
        }
        self.has_output = true;
        StepStatus::Ok
    }

    fn check(&self, input: &AdmittanceInput, dt: f64) -> Result<(), Fault> {
        let n = self.n;
        for (argument, v) in [
            ("q_d", input.q_d),
            ("qdot_d", input.qdot_d),
            ("qddot_d", input.qddot_d),
            ("external_torque_estimate", input.external_torque_estimate),
        ] {
            if v.len() != n {
                return Err(Fault::WrongLength {
                    argument,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Fault::InvalidTimeStep);
        }
        for (argument, v) in [
            ("q_d", input.q_d),
            ("qdot_d", input.qdot_d),
            ("qddot_d", input.qddot_d),
        ] {
            if let Some(joint) = first_non_finite(v) {
                return Err(Fault::NonFiniteReference { argument, joint });
            }
        }
        if let Some(joint) = first_non_finite(input.external_torque_estimate) {
            return Err(Fault::NonFiniteEstimate { joint });
        }
        Ok(())
    }

    /// Reference position `q_r`.
    pub fn q_r(&self) -> &[f64] {
        &self.q_r
    }
    /// Reference velocity `q_r'`.
    pub fn qdot_r(&self) -> &[f64] {
        &self.qdot_r
    }
    /// Reference acceleration `q_r''`.
    pub fn qddot_r(&self) -> &[f64] {
        &self.qddot_r
    }
    /// Unsaturated admittance state `q_a`.
    pub fn q_a(&self) -> &[f64] {
        &self.q_a
    }
    /// `q_a'`.
    pub fn qdot_a(&self) -> &[f64] {
        &self.qdot_a
    }
    /// `q_a''`.
    pub fn qddot_a(&self) -> &[f64] {
        &self.qddot_a
    }
    /// Deviation `q_a - q_d`.
    pub fn deviation(&self) -> &[f64] {
        &self.x
    }
}
