//! Environments: what acts on the arm from outside (`tau_ext`, docs/method.md section 1), each
//! active in a time window `[t_start, t_end)`.
//!
//! * **Joint-space spring-damper-mass** on selected joints:
//!   `-tau_ext = M_E qddot + C_E qdot + G_E (q - q_E)`, with `q_E` the position at contact
//!   start (default: no torque step when contact begins) or zero. `M_E` is added to the
//!   diagonal of the mass matrix in the solve (coupled, not lagged), `C_E` joins the
//!   implicit damping of the velocity update, `G_E` is explicit.
//! * **Cartesian wall** at a frame (default the tip): a plane through `point` with unit
//!   `normal` pointing into free space; while the frame's origin is behind it by a depth
//!   `d > 0`, a force `f = max(0, k d + c d') normal` acts on it (no adhesion), i.e.
//!   `tau_ext = J_v^T f`.
//! * **Scripted joint torque** on one joint and **scripted force** at a frame,
//!   piecewise-linear in absolute time between the given points, holding the end values
//!   outside them, zero outside the window.
//!
//! Activity is decided once per plant step from the step's start time, so that an
//! environment does not switch on or off between the stages of one step.

use admittance_dynamics::{frame_jacobian, Data, Model};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::checks::{finite, frame_index, joint_index, non_negative, window};
use crate::plant::error::SimError;

fn infinity() -> f64 {
    f64::INFINITY
}

/// The environments of a scenario, by kind.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvironmentConfig {
    /// Joint-space spring-damper-mass environments.
    pub joint_springs: Vec<JointSpringConfig>,
    /// Cartesian walls.
    pub walls: Vec<WallConfig>,
    /// Scripted joint torques.
    pub joint_torque_profiles: Vec<JointTorqueProfileConfig>,
    /// Scripted forces at a frame.
    pub tip_force_profiles: Vec<TipForceProfileConfig>,
}

/// Where the joint-space spring is relaxed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Anchor {
    /// `q_E` = the joint positions when the window opens (no torque step; docs/method.md
    /// section 7).
    #[default]
    ContactStart,
    /// `q_E = 0` (the paper's `-tau_ext = 0.01 q'' + 0.15 q' + 1.1 q` literally).
    Zero,
}

/// `-tau_ext = M_E qddot + C_E qdot + G_E (q - q_E)` on `joints`. `mass`, `damping` and
/// `stiffness` hold one value per listed joint, or a single value for all of them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JointSpringConfig {
    /// Joint names.
    pub joints: Vec<String>,
    /// M_E (kg m^2 or kg), >= 0.
    pub mass: Vec<f64>,
    /// C_E (N m s/rad), >= 0.
    pub damping: Vec<f64>,
    /// G_E (N m/rad), >= 0.
    pub stiffness: Vec<f64>,
    /// Where the spring is relaxed. Default `contact_start`.
    pub anchor: Anchor,
    /// Window start (s). Default 0.
    pub t_start: f64,
    /// Window end (s), exclusive. Default `inf`.
    #[serde(default = "infinity")]
    pub t_end: f64,
}

impl Default for JointSpringConfig {
    fn default() -> Self {
        Self {
            joints: Vec::new(),
            mass: vec![0.0],
            damping: vec![0.0],
            stiffness: vec![0.0],
            anchor: Anchor::ContactStart,
            t_start: 0.0,
            t_end: f64::INFINITY,
        }
    }
}

/// A plane the frame origin cannot enter without a restoring force.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WallConfig {
    /// The frame (URDF link) in contact; default the model's tip.
    pub frame: Option<String>,
    /// A point of the plane, base frame (m).
    pub point: [f64; 3],
    /// The plane's normal, pointing into free space (normalised on load; non-zero).
    pub normal: [f64; 3],
    /// Normal stiffness k (N/m), >= 0. Default 5000.
    pub stiffness: f64,
    /// Normal damping c (N s/m), >= 0. Default 50.
    pub damping: f64,
    /// Window start (s). Default 0.
    pub t_start: f64,
    /// Window end (s), exclusive. Default `inf`.
    #[serde(default = "infinity")]
    pub t_end: f64,
}

impl Default for WallConfig {
    fn default() -> Self {
        Self {
            frame: None,
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            stiffness: 5000.0,
            damping: 50.0,
            t_start: 0.0,
            t_end: f64::INFINITY,
        }
    }
}

/// A scripted torque on one joint: `points = [[t, tau], ...]`, times non-decreasing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JointTorqueProfileConfig {
    /// Joint name.
    pub joint: String,
    /// `[time (s), torque (N m)]` pairs, at least one, times non-decreasing.
    pub points: Vec<[f64; 2]>,
    /// Window start (s). Default 0.
    pub t_start: f64,
    /// Window end (s), exclusive. Default `inf`.
    #[serde(default = "infinity")]
    pub t_end: f64,
}

impl Default for JointTorqueProfileConfig {
    fn default() -> Self {
        Self {
            joint: String::new(),
            points: Vec::new(),
            t_start: 0.0,
            t_end: f64::INFINITY,
        }
    }
}

/// A scripted force at a frame's origin (a person pushing the hand):
/// `points = [[t, fx, fy, fz], ...]` in base-frame axes, times non-decreasing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TipForceProfileConfig {
    /// The frame (URDF link); default the model's tip.
    pub frame: Option<String>,
    /// `[time (s), fx, fy, fz (N)]`, at least one, times non-decreasing.
    pub points: Vec<[f64; 4]>,
    /// Window start (s). Default 0.
    pub t_start: f64,
    /// Window end (s), exclusive. Default `inf`.
    #[serde(default = "infinity")]
    pub t_end: f64,
}

impl Default for TipForceProfileConfig {
    fn default() -> Self {
        Self {
            frame: None,
            points: Vec::new(),
            t_start: 0.0,
            t_end: f64::INFINITY,
        }
    }
}

fn per_joint(key: String, values: &[f64], joints: usize) -> Result<(), SimError> {
    if values.len() == 1 || values.len() == joints {
        for (k, v) in values.iter().enumerate() {
            non_negative(|| format!("{key}[{k}]"), *v)?;
        }
        Ok(())
    } else {
        Err(SimError::config(
            key,
            format!(
                "needs one value, or one per listed joint ({joints}), got {}",
                values.len()
            ),
        ))
    }
}

fn check_times<const N: usize>(prefix: &str, points: &[[f64; N]]) -> Result<(), SimError> {
    if points.is_empty() {
        return Err(SimError::config(
            format!("{prefix}.points"),
            "needs at least one point",
        ));
    }
    for (k, p) in points.iter().enumerate() {
        for (c, v) in p.iter().enumerate() {
            finite(|| format!("{prefix}.points[{k}][{c}]"), *v)?;
        }
        if k > 0 && p[0] < points[k - 1][0] {
            return Err(SimError::config(
                format!("{prefix}.points[{k}][0]"),
                format!(
                    "times must not decrease ({} after {})",
                    p[0],
                    points[k - 1][0]
                ),
            ));
        }
    }
    Ok(())
}

impl EnvironmentConfig {
    /// Checks values and names; `prefix` is the key of this table (e.g. `"environment"`).
    pub fn validate(&self, model: &Model, prefix: &str) -> Result<(), SimError> {
        for (k, s) in self.joint_springs.iter().enumerate() {
            let p = format!("{prefix}.joint_springs[{k}]");
            if s.joints.is_empty() {
                return Err(SimError::config(format!("{p}.joints"), "lists no joint"));
            }
            for (j, name) in s.joints.iter().enumerate() {
                joint_index(model, || format!("{p}.joints[{j}]"), name)?;
            }
            per_joint(format!("{p}.mass"), &s.mass, s.joints.len())?;
            per_joint(format!("{p}.damping"), &s.damping, s.joints.len())?;
            per_joint(format!("{p}.stiffness"), &s.stiffness, s.joints.len())?;
            window(&p, s.t_start, s.t_end)?;
        }
        for (k, w) in self.walls.iter().enumerate() {
            let p = format!("{prefix}.walls[{k}]");
            frame_index(model, || format!("{p}.frame"), w.frame.as_deref())?;
            for c in 0..3 {
                finite(|| format!("{p}.point[{c}]"), w.point[c])?;
                finite(|| format!("{p}.normal[{c}]"), w.normal[c])?;
            }
            if Vector3::from(w.normal).norm() < 1e-12 {
                return Err(SimError::config(
                    format!("{p}.normal"),
                    "must be a non-zero vector",
                ));
            }
            non_negative(|| format!("{p}.stiffness"), w.stiffness)?;
            non_negative(|| format!("{p}.damping"), w.damping)?;
            window(&p, w.t_start, w.t_end)?;
        }
        for (k, t) in self.joint_torque_profiles.iter().enumerate() {
            let p = format!("{prefix}.joint_torque_profiles[{k}]");
            joint_index(model, || format!("{p}.joint"), &t.joint)?;
            check_times(&p, &t.points)?;
            window(&p, t.t_start, t.t_end)?;
        }
        for (k, f) in self.tip_force_profiles.iter().enumerate() {
            let p = format!("{prefix}.tip_force_profiles[{k}]");
            frame_index(model, || format!("{p}.frame"), f.frame.as_deref())?;
            check_times(&p, &f.points)?;
            window(&p, f.t_start, f.t_end)?;
        }
        Ok(())
    }

    /// Whether no environment is configured.
    pub fn is_empty(&self) -> bool {
        self.joint_springs.is_empty()
            && self.walls.is_empty()
            && self.joint_torque_profiles.is_empty()
            && self.tip_force_profiles.is_empty()
    }
}

/// Linear interpolation in a table whose first column is non-decreasing time; holds the
/// end values outside it. Column `c` of the row type.
#[inline]
fn interpolate<const N: usize>(points: &[[f64; N]], t: f64, c: usize) -> f64 {
    let last = points.len() - 1;
    if t <= points[0][0] {
        return points[0][c];
    }
    if t >= points[last][0] {
        return points[last][c];
    }
    for k in 1..=last {
        let (a, b) = (&points[k - 1], &points[k]);
        if t < b[0] {
            let span = b[0] - a[0];
            if span <= 0.0 {
                return b[c];
            }
            let s = (t - a[0]) / span;
            return a[c] + s * (b[c] - a[c]);
        }
    }
    points[last][c]
}

#[derive(Clone, Copy, Debug)]
struct Window {
    start: f64,
    end: f64,
}

impl Window {
    #[inline(always)]
    fn contains(&self, t: f64) -> bool {
        self.start <= t && t < self.end
    }
}

#[derive(Clone, Debug)]
struct JointSpring {
    joints: Vec<usize>,
    mass: Vec<f64>,
    damping: Vec<f64>,
    stiffness: Vec<f64>,
    anchor: Anchor,
    window: Window,
    /// q_E per listed joint, set when the window opens.
    q_e: Vec<f64>,
    engaged: bool,
    active: bool,
}

#[derive(Clone, Debug)]
struct Wall {
    frame: usize,
    point: Vector3<f64>,
    normal: Vector3<f64>,
    stiffness: f64,
    damping: f64,
    window: Window,
    active: bool,
}

#[derive(Clone, Debug)]
struct TorqueProfile {
    joint: usize,
    points: Vec<[f64; 2]>,
    window: Window,
    active: bool,
}

#[derive(Clone, Debug)]
struct ForceProfile {
    frame: usize,
    points: Vec<[f64; 4]>,
    window: Window,
    active: bool,
}

/// The environments of a plant at run time (built from an [`EnvironmentConfig`]).
#[derive(Clone, Debug)]
pub struct Environment {
    springs: Vec<JointSpring>,
    walls: Vec<Wall>,
    torques: Vec<TorqueProfile>,
    forces: Vec<ForceProfile>,
    /// Sum of the active springs' M_E per joint.
    mass_diag: Vec<f64>,
    /// Sum of the active springs' C_E per joint.
    damping_diag: Vec<f64>,
    /// Whether a wall pushed at the last evaluation.
    in_contact: bool,
    /// Normal force of each wall at the last evaluation (N).
    wall_forces: Vec<f64>,
    tip_frame: usize,
    tip_force: Vector3<f64>,
}

impl Environment {
    /// Builds the run-time environments after validating `config` against `model`.
    pub fn new(model: &Model, config: &EnvironmentConfig) -> Result<Self, SimError> {
        config.validate(model, "environment")?;
        let n = model.nq();
        let pick = |values: &[f64], k: usize| {
            if values.len() == 1 {
                values[0]
            } else {
                values[k]
            }
        };
        let springs = config
            .joint_springs
            .iter()
            .map(|s| {
                let m = s.joints.len();
                JointSpring {
                    joints: s
                        .joints
                        .iter()
                        .map(|name| model.joint_index(name).unwrap_or(0))
                        .collect(),
                    mass: (0..m).map(|k| pick(&s.mass, k)).collect(),
                    damping: (0..m).map(|k| pick(&s.damping, k)).collect(),
                    stiffness: (0..m).map(|k| pick(&s.stiffness, k)).collect(),
                    anchor: s.anchor,
                    window: Window {
                        start: s.t_start,
                        end: s.t_end,
                    },
                    q_e: vec![0.0; m],
                    engaged: false,
                    active: false,
                }
            })
            .collect();
        let walls: Vec<Wall> = config
            .walls
            .iter()
            .map(|w| Wall {
                frame: w
                    .frame
                    .as_deref()
                    .and_then(|f| model.frame_index(f))
                    .unwrap_or(model.tip_frame),
                point: Vector3::from(w.point),
                normal: Vector3::from(w.normal).normalize(),
                stiffness: w.stiffness,
                damping: w.damping,
                window: Window {
                    start: w.t_start,
                    end: w.t_end,
                },
                active: false,
            })
            .collect();
        let torques = config
            .joint_torque_profiles
            .iter()
            .map(|t| TorqueProfile {
                joint: model.joint_index(&t.joint).unwrap_or(0),
                points: t.points.clone(),
                window: Window {
                    start: t.t_start,
                    end: t.t_end,
                },
                active: false,
            })
            .collect();
        let forces = config
            .tip_force_profiles
            .iter()
            .map(|f| ForceProfile {
                frame: f
                    .frame
                    .as_deref()
                    .and_then(|name| model.frame_index(name))
                    .unwrap_or(model.tip_frame),
                points: f.points.clone(),
                window: Window {
                    start: f.t_start,
                    end: f.t_end,
                },
                active: false,
            })
            .collect();
        let n_walls = walls.len();
        Ok(Self {
            springs,
            walls,
            torques,
            forces,
            mass_diag: vec![0.0; n],
            damping_diag: vec![0.0; n],
            in_contact: false,
            wall_forces: vec![0.0; n_walls],
            tip_frame: model.tip_frame,
            tip_force: Vector3::zeros(),
        })
    }

    /// Back to the state before the first step (anchors released).
    pub fn reset(&mut self) {
        for s in &mut self.springs {
            s.engaged = false;
            s.active = false;
            s.q_e.fill(0.0);
        }
        for w in &mut self.walls {
            w.active = false;
        }
        for t in &mut self.torques {
            t.active = false;
        }
        for f in &mut self.forces {
            f.active = false;
        }
        self.mass_diag.fill(0.0);
        self.damping_diag.fill(0.0);
        self.in_contact = false;
        self.wall_forces.fill(0.0);
        self.tip_force = Vector3::zeros();
    }

    /// Decides which environments act during the step that starts at `t` from position
    /// `q`, engages spring anchors whose window opens, and sums M_E and C_E per joint.
    pub(crate) fn begin_step(&mut self, t: f64, q: &[f64]) {
        self.mass_diag.fill(0.0);
        self.damping_diag.fill(0.0);
        for s in &mut self.springs {
            s.active = s.window.contains(t);
            if s.active {
                if !s.engaged {
                    s.engaged = true;
                    for (k, &j) in s.joints.iter().enumerate() {
                        s.q_e[k] = match s.anchor {
                            Anchor::ContactStart => q[j],
                            Anchor::Zero => 0.0,
                        };
                    }
                }
                for (k, &j) in s.joints.iter().enumerate() {
                    self.mass_diag[j] += s.mass[k];
                    self.damping_diag[j] += s.damping[k];
                }
            }
        }
        for w in &mut self.walls {
            w.active = w.window.contains(t);
        }
        for p in &mut self.torques {
            p.active = p.window.contains(t);
        }
        for p in &mut self.forces {
            p.active = p.window.contains(t);
        }
    }

    /// M_E per joint for the current step (zero where no spring acts).
    pub fn mass_diag(&self) -> &[f64] {
        &self.mass_diag
    }

    /// C_E per joint for the current step.
    pub fn damping_diag(&self) -> &[f64] {
        &self.damping_diag
    }

    /// Whether any spring with a mass acts in the current step.
    pub(crate) fn has_mass(&self) -> bool {
        self.mass_diag.iter().any(|m| *m != 0.0)
    }

    /// Whether a wall pushed the arm at the last evaluation.
    pub fn in_contact(&self) -> bool {
        self.in_contact
    }

    /// Normal force of each wall (N, >= 0) at the last evaluation, in configuration order.
    pub fn wall_forces(&self) -> &[f64] {
        &self.wall_forces
    }

    /// The force of the walls and the scripted forces on the model's tip frame (the hand)
    /// at the last evaluation (N, base axes): what a force sensor at the hand would read.
    pub fn tip_force(&self) -> [f64; 3] {
        [self.tip_force.x, self.tip_force.y, self.tip_force.z]
    }

    /// The explicitly integrated part of `tau_ext` at time `t`, state `(q, v)`, written to
    /// `out`: `-G_E (q - q_E)` of the active springs, the walls' `J^T f`, the scripted
    /// torques and forces. (`-M_E qddot` and `-C_E qdot` are handled implicitly by the
    /// integrator.) Uses `data` for the Jacobians.
    pub(crate) fn explicit_torque(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) {
        out.fill(0.0);
        for s in &self.springs {
            if s.active {
                for (k, &j) in s.joints.iter().enumerate() {
                    out[j] -= s.stiffness[k] * (q[j] - s.q_e[k]);
                }
            }
        }
        for p in &self.torques {
            if p.active {
                out[p.joint] += interpolate(&p.points, t, 1);
            }
        }
        self.in_contact = false;
        self.tip_force = Vector3::zeros();
        for (w, force) in self.walls.iter().zip(self.wall_forces.iter_mut()) {
            *force = 0.0;
            if !w.active {
                continue;
            }
            if frame_jacobian(model, data, q, w.frame).is_err() {
                continue;
            }
            let jac = &data.jacobian;
            let p = data.frame_placements[w.frame].translation;
            let depth = (w.point - p).dot(&w.normal);
            if depth <= 0.0 {
                continue;
            }
            // Normal velocity of the frame origin: n . (J_v v).
            let mut vn = 0.0;
            for (j, vj) in v.iter().enumerate() {
                vn += (w.normal.x * jac[(0, j)]
                    + w.normal.y * jac[(1, j)]
                    + w.normal.z * jac[(2, j)])
                    * vj;
            }
            let fn_ = (w.stiffness * depth - w.damping * vn).max(0.0);
            if fn_ == 0.0 {
                continue;
            }
            *force = fn_;
            self.in_contact = true;
            let f = w.normal * fn_;
            if w.frame == self.tip_frame {
                self.tip_force += f;
            }
            for (j, o) in out.iter_mut().enumerate() {
                *o += jac[(0, j)] * f.x + jac[(1, j)] * f.y + jac[(2, j)] * f.z;
            }
        }
        for p in &self.forces {
            if !p.active {
                continue;
            }
            let f = Vector3::new(
                interpolate(&p.points, t, 1),
                interpolate(&p.points, t, 2),
                interpolate(&p.points, t, 3),
            );
            if f == Vector3::zeros() {
                continue;
            }
            if p.frame == self.tip_frame {
                self.tip_force += f;
            }
            if frame_jacobian(model, data, q, p.frame).is_err() {
                continue;
            }
            let jac = &data.jacobian;
            for (j, o) in out.iter_mut().enumerate() {
                *o += jac[(0, j)] * f.x + jac[(1, j)] * f.y + jac[(2, j)] * f.z;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_holds_ends_and_is_linear_inside() {
        let pts = [[1.0, 0.0], [2.0, 10.0], [2.0, 20.0], [4.0, 0.0]];
        assert_eq!(interpolate(&pts, 0.0, 1), 0.0);
        assert_eq!(interpolate(&pts, 1.5, 1), 5.0);
        assert_eq!(interpolate(&pts, 2.0, 1), 20.0);
        assert_eq!(interpolate(&pts, 3.0, 1), 10.0);
        assert_eq!(interpolate(&pts, 9.0, 1), 0.0);
    }
}
