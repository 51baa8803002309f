//! Configuration of the task-space admittance (docs/method.md section 2, task-space variant;
//! issue 16 part 1): axes, gains per axis group, the inverse kinematics, the damping of the
//! pseudo-inverses and the joint saturation.

use serde::{Deserialize, Serialize};

use crate::admittance::SaturationConfig;
use crate::config::AxisValues;

/// One axis of the hand's task space, in the base frame: the translations `x`, `y`, `z`
/// and the rotations `rx`, `ry`, `rz` (components of the orientation deviation as a
/// rotation vector).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TaskAxis {
    /// Translation along the base frame's x axis.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation about x.
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
}

impl TaskAxis {
    /// The six axes in task-vector order (linear first, as the Jacobian's rows).
    pub const ALL: [TaskAxis; 6] = [
        TaskAxis::X,
        TaskAxis::Y,
        TaskAxis::Z,
        TaskAxis::Rx,
        TaskAxis::Ry,
        TaskAxis::Rz,
    ];

    /// Index in a task 6-vector (0..3 linear, 3..6 angular).
    pub fn index(self) -> usize {
        self as usize
    }

    /// `"x"`, `"y"`, `"z"`, `"rx"`, `"ry"`, `"rz"`.
    pub fn name(self) -> &'static str {
        ["x", "y", "z", "rx", "ry", "rz"][self.index()]
    }
}

/// The admittance of one axis group (the three translations or the three rotations):
/// `M_d dx'' + C_d dx' + G_d dx = f` per axis, with `dx = x_r - x_d`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisAdmittanceConfig {
    /// Damping `C_d > 0`: N/(m/s) for the translations, N m/(rad/s) for the rotations.
    pub damping: AxisValues,
    /// Stiffness `G_d >= 0`: N/m for the translations, N m/rad for the rotations. Zero is
    /// hand guiding on that axis: the hand drifts with the force and stops when released.
    pub stiffness: AxisValues,
    /// Optional inertia `M_d > 0`: kg for the translations, kg m^2 for the rotations. Makes
    /// the model second order on these axes.
    #[serde(default)]
    pub inertia: Option<AxisValues>,
}

impl AxisAdmittanceConfig {
    /// Default translations: `C_d = 60 N/(m/s)`, `G_d = 100 N/m` (a 10 N push moves the
    /// hand 0.1 m, time constant `C_d / G_d = 0.6 s`, the paper's joint-space ratio 3 / 5).
    pub fn default_linear() -> Self {
        AxisAdmittanceConfig {
            damping: AxisValues::Uniform(60.0),
            stiffness: AxisValues::Uniform(100.0),
            inertia: None,
        }
    }

    /// Default rotations: `C_d = 6 N m/(rad/s)`, `G_d = 10 N m/rad` (1 N m turns the hand
    /// 0.1 rad, time constant 0.6 s).
    pub fn default_angular() -> Self {
        AxisAdmittanceConfig {
            damping: AxisValues::Uniform(6.0),
            stiffness: AxisValues::Uniform(10.0),
            inertia: None,
        }
    }
}

/// The damping of a pseudo-inverse near singularities (see
/// [`TaskSpaceAdmittance`](crate::TaskSpaceAdmittance), "Damped pseudo-inverse").
///
/// Each singular value `s_i` of the Jacobian below `threshold` is damped by
/// `lambda_i^2 = max_damping^2 (1 - (s_i / threshold)^2)`, so the gain `s_i / (s_i^2 +
/// lambda_i^2)` along that direction stays bounded (by `threshold / min(max_damping,
/// threshold)^2`; by `1 / threshold` when `max_damping = threshold`, the default) while
/// directions with `s_i >= threshold` are inverted exactly. Singular values mix units (the
/// linear rows of the Jacobian are in m/rad, the angular rows in rad/rad): for an arm of
/// about 1 m reach both are of order 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SingularityDampingConfig {
    /// Singular values below this are damped (> 0; default 0.1).
    #[serde(default = "default_threshold")]
    pub threshold: f64,
    /// The damping `lambda` at a singular value of zero (> 0; default 0.1).
    #[serde(default = "default_threshold")]
    pub max_damping: f64,
}

fn default_threshold() -> f64 {
    0.1
}

impl Default for SingularityDampingConfig {
    fn default() -> Self {
        SingularityDampingConfig {
            threshold: default_threshold(),
            max_damping: default_threshold(),
        }
    }
}

/// The differential inverse kinematics that maps the compliant hand pose to the joint
/// reference (see [`TaskSpaceAdmittance`](crate::TaskSpaceAdmittance), "Inverse
/// kinematics").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InverseKinematicsConfig {
    /// `K_P > 0` (1/s^2): correction of the pose error (m and rad alike). Default 400.
    #[serde(default = "default_position_gain")]
    pub position_gain: f64,
    /// `K_D > 0` (1/s): correction of the twist error. Default 40 (with `K_P = 400`, the
    /// error decays critically damped at 20 rad/s; keep `K_D dt` well below 1).
    #[serde(default = "default_velocity_gain")]
    pub velocity_gain: f64,
    /// `K_NP >= 0` (1/s^2): null-space pull of the joints towards the desired posture `q_d`
    /// (redundant arms). Default 100.
    #[serde(default = "default_posture_position_gain")]
    pub posture_position_gain: f64,
    /// `K_ND >= 0` (1/s): null-space damping towards `q_d'`. Default 20.
    #[serde(default = "default_posture_velocity_gain")]
    pub posture_velocity_gain: f64,
    /// Damping of the Jacobian's pseudo-inverse at the reference configuration.
    #[serde(default)]
    pub damping: SingularityDampingConfig,
}

fn default_position_gain() -> f64 {
    400.0
}
fn default_velocity_gain() -> f64 {
    40.0
}
fn default_posture_position_gain() -> f64 {
    100.0
}
fn default_posture_velocity_gain() -> f64 {
    20.0
}

impl Default for InverseKinematicsConfig {
    fn default() -> Self {
        InverseKinematicsConfig {
            position_gain: default_position_gain(),
            velocity_gain: default_velocity_gain(),
            posture_position_gain: default_posture_position_gain(),
            posture_velocity_gain: default_posture_velocity_gain(),
            damping: SingularityDampingConfig::default(),
        }
    }
}

/// Where the joint reference is bounded (eq. 7 on each joint, docs/method.md section 2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TaskSaturationConfig {
    /// No saturation: `q_r = q_a`.
    None,
    /// The model's joint position limits: joint `i` stays inside `(lower_i, upper_i)`, with
    /// the linear zone `rho` of the half-range about the middle (default 0.95). Joints
    /// without two finite limits are not saturated.
    JointLimits {
        /// `rho` in `(0, 1)`.
        #[serde(default = "default_rho")]
        rho: f64,
    },
    /// Explicit centre and half-range per joint, as for the joint-space
    /// [`Admittance`](crate::Admittance).
    Explicit(SaturationConfig),
}

fn default_rho() -> f64 {
    0.95
}

impl Default for TaskSaturationConfig {
    fn default() -> Self {
        TaskSaturationConfig::JointLimits { rho: default_rho() }
    }
}

fn all_axes() -> Vec<TaskAxis> {
    TaskAxis::ALL.to_vec()
}

/// Configuration of [`TaskSpaceAdmittance`](crate::TaskSpaceAdmittance). Every field has
/// a default: all six axes tracked and compliant, translations `C_d = 60 N/(m/s)`, `G_d = 100 N/m`,
/// rotations `C_d = 6 N m/(rad/s)`, `G_d = 10 N m/rad`, no `M_d`, the joint reference
/// saturated inside the model's joint limits (`rho = 0.95`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpaceAdmittanceConfig {
    /// The task axes: the hand coordinates that the inverse kinematics tracks and that the
    /// wrench is estimated on (zero on the others). Default: all six. An arm with fewer than
    /// six joints lists those it can move (a planar arm `["x", "z"]`); on the other axes
    /// the hand is left to the posture term.
    #[serde(default = "all_axes")]
    pub task_axes: Vec<TaskAxis>,
    /// The compliant axes, among the task axes (default: all of them). A task axis not
    /// listed follows `x_d` rigidly: its deviation is held at zero whatever the wrench.
    #[serde(default)]
    pub compliant_axes: Option<Vec<TaskAxis>>,
    /// The translations' admittance (x, y, z).
    #[serde(default = "AxisAdmittanceConfig::default_linear")]
    pub linear: AxisAdmittanceConfig,
    /// The rotations' admittance (rx, ry, rz).
    #[serde(default = "AxisAdmittanceConfig::default_angular")]
    pub angular: AxisAdmittanceConfig,
    /// Damping of `J^+T` in the wrench estimate `f_ext_hat = J(q)^+T tau_ext_hat`.
    #[serde(default)]
    pub wrench_damping: SingularityDampingConfig,
    /// The differential inverse kinematics.
    #[serde(default)]
    pub inverse_kinematics: InverseKinematicsConfig,
    /// The joint saturation of the reference.
    #[serde(default)]
    pub saturation: TaskSaturationConfig,
}

impl Default for TaskSpaceAdmittanceConfig {
    fn default() -> Self {
        TaskSpaceAdmittanceConfig {
            task_axes: all_axes(),
            compliant_axes: None,
            linear: AxisAdmittanceConfig::default_linear(),
            angular: AxisAdmittanceConfig::default_angular(),
            wrench_damping: SingularityDampingConfig::default(),
            inverse_kinematics: InverseKinematicsConfig::default(),
            saturation: TaskSaturationConfig::default(),
        }
    }
}
