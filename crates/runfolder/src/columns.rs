//! Time-series columns (docs/outputs.md, "Time-series columns"). A per-joint column is
//! named `PREFIX.JOINT`, e.g. `q.left_s0`.

/// Time (s), the first column of every series.
pub const TIME: &str = "t";

/// The per-joint signals of `VARIANT.csv`, in the order they are written.
pub const PER_JOINT: [&str; 9] = [
    DESIRED,
    REFERENCE,
    POSITION,
    VELOCITY,
    MEASURED_POSITION,
    COMMAND,
    APPLIED,
    EXTERNAL,
    EXTERNAL_ESTIMATE,
];

/// Desired trajectory `q_d` (rad).
pub const DESIRED: &str = "q_d";
/// Compliant reference `q_r` (rad).
pub const REFERENCE: &str = "q_r";
/// The plant's true angle (rad).
pub const POSITION: &str = "q";
/// The plant's true velocity (rad/s).
pub const VELOCITY: &str = "qdot";
/// What the encoder reported (rad).
pub const MEASURED_POSITION: &str = "q_meas";
/// The controller's command (N m).
pub const COMMAND: &str = "tau_cmd";
/// The torque the actuator applied (N m).
pub const APPLIED: &str = "tau_applied";
/// The true external torque (N m).
pub const EXTERNAL: &str = "tau_ext";
/// The estimate that drove the admittance model (N m).
pub const EXTERNAL_ESTIMATE: &str = "tau_ext_hat";
/// Hand position error (m), one column.
pub const HAND_ERROR: &str = "ee_error";
/// With dynamic nodes: `f` of the true arm (N m), per joint.
pub const F_TRUE: &str = "f";
/// With dynamic nodes: the network's `f_hat` (N m), per joint.
pub const F_ESTIMATE: &str = "f_hat";
/// With the neural controller: node count of the f network, one column.
pub const NODES_F: &str = "nodes.f";
/// How well the observer's input lies inside its network's training data, in [0, 1]
/// (hybrid observers; docs/method.md section 8).
pub const ESTIMATE_COVERAGE: &str = "estimate_coverage";
/// Prefix of the node-count columns, `nodes.NETWORK` (e.g. [`NODES_F`]).
pub const NODES: &str = "nodes";

/// Task-space runs (a Cartesian admittance or a hand contact): the true force of the
/// environment on the hand (N), columns `f_hand.x`, `f_hand.y`, `f_hand.z`.
pub const HAND_FORCE: &str = "f_hand";
/// The estimated hand force `J^{+T} tau_ext_hat` (N), `.x .y .z`.
pub const HAND_FORCE_ESTIMATE: &str = "f_hand_hat";
/// The true hand position (m, base frame), `.x .y .z`.
pub const HAND_POSITION: &str = "x_hand";
/// The hand position of the compliant reference `FK(q_r)` (m), `.x .y .z`.
pub const HAND_REFERENCE: &str = "x_hand_r";
/// The desired hand position `FK(q_d)` (m), `.x .y .z`.
pub const HAND_DESIRED: &str = "x_hand_d";
/// The axis suffixes of the hand columns.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// With `[contact]` (issue 31): 1 while the detector flags a contact, else 0.
pub const CONTACT: &str = "contact";
/// With `[contact]`: 1 while the detector flags a collision, else 0.
pub const COLLISION: &str = "collision";
/// With `[contact]`: the last loaded joint's index in chain order (the touched part of the
/// chain), -1 when no joint is flagged.
pub const CONTACT_LINK: &str = "contact_link";
/// With `[contact]`: each joint's contact level at this step (N m: the floor's threshold
/// grown with the joint's speed and acceleration), per joint.
pub const CONTACT_LEVEL: &str = "contact_level";

/// The per-joint signals of free-motion data (`free_motion.csv`), in the order written.
pub const FREE_MOTION: [&str; 4] = ["q", "qdot", "qddot", "tau"];

/// Validation series: what the network learns, per joint.
pub const VALIDATION_TARGET: &str = "target";
/// Validation series: the network's output, per joint.
pub const VALIDATION_PREDICTION: &str = "prediction";
/// Node-weight series: prefix of a node's column (`w.ID`).
pub const NODE_WEIGHT_PREFIX: &str = "w.";

/// `PREFIX.JOINT`.
pub fn joint(prefix: &str, joint: &str) -> String {
    format!("{prefix}.{joint}")
}

/// `PREFIX.AXIS` of a hand column (`f_hand.x`); `axis` is one of [`AXES`].
pub fn axis(prefix: &str, axis: &str) -> String {
    format!("{prefix}.{axis}")
}

/// The hand signals of a task-space run, in the order they are written.
pub const HAND: [&str; 5] = [
    HAND_FORCE,
    HAND_FORCE_ESTIMATE,
    HAND_POSITION,
    HAND_REFERENCE,
    HAND_DESIRED,
];

/// `PREFIX.JOINT` for every joint, in order.
pub fn per_joint<'a>(prefix: &'a str, joints: &'a [String]) -> impl Iterator<Item = String> + 'a {
    joints.iter().map(move |j| joint(prefix, j))
}
