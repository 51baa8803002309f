//! The `#[repr(C)]` types and constants of the C ABI (what `include/admittance.h` declares).
//!
//! Units are SI; joint arrays are in the URDF chain order from `[arm] base` to `[arm] tip`
//! (the order `admittance model --urdf ...` prints), with the URDF's joint axes and signs.
//! Only the first `n_joints` entries of an array are read or written; the rest of an output
//! array is zero. Every struct is laid out without padding, so two outputs can be compared
//! with `memcmp`.

use std::os::raw::c_char;

/// Version of this ABI: bumped whenever a struct, a constant or a function changes.
/// `AdmConfig::abi_version` must equal it.
pub const ADM_ABI_VERSION: u32 = 3;

/// Capacity of every joint array (a chain may have fewer joints, never more).
pub const ADM_MAX_JOINTS: usize = 16;

/// The step ran its normal law.
pub const ADM_OK: i32 = 0;
/// The step ran, and a fault was detected (no angle yet, an implausible or non-finite or
/// stale measurement, a non-finite reference or estimate, ...): the output is the safe
/// value (zero before the first angles, else the controller's safe hold, or the law on
/// held signals) and should be sent; `AdmOutput::fault` says which.
pub const ADM_FAULT: i32 = 1;
/// A pointer argument was null. Nothing was read or written.
pub const ADM_ERR_NULL: i32 = -1;
/// `AdmInput::n_joints` is not the handle's joint count. The output holds the last step's.
pub const ADM_ERR_JOINTS: i32 = -2;
/// `AdmInput::time` is not finite. The output holds the last step's.
pub const ADM_ERR_TIME: i32 = -3;
/// The step panicked (a bug): the panic was caught at the boundary, the output holds the
/// last good step's with `ADM_OUT_HELD` set, and `adm_last_error` has the message. The
/// handle refuses every later step with `ADM_ERR_POISONED`: destroy it.
pub const ADM_ERR_PANIC: i32 = -4;
/// An earlier step panicked; the output holds the last good step's (`ADM_OUT_HELD`).
pub const ADM_ERR_POISONED: i32 = -5;

/// `AdmInput::flags`: `qdot` holds measured joint velocities; they replace the ones the
/// loop differentiates from `q` (for the controller and for an observer fed without a
/// second conditioning stage). Without it the velocities are differentiated, as in the data
/// the learned observers were trained on.
pub const ADM_INPUT_QDOT: u32 = 1;
/// `AdmInput::flags`: `tau` holds the measured joint torques. Without it the loop uses its
/// own last command in their place (as the simulator does).
pub const ADM_INPUT_TAU: u32 = 1 << 1;
/// `AdmInput::flags`: `q_d`, `qdot_d`, `qddot_d` hold the desired trajectory. Without it
/// the loop holds the first measured pose (`ADM_OUT_HOLDING_POSE`).
pub const ADM_INPUT_DESIRED: u32 = 1 << 2;

/// `AdmOutput::flags`: the controller reported a fault and wrote its safe hold.
pub const ADM_OUT_CONTROLLER_FAULT: u32 = 1;
/// `AdmOutput::flags`: the observer's update failed (its estimate was held or zeroed).
pub const ADM_OUT_OBSERVER_FAULT: u32 = 1 << 1;
/// `AdmOutput::flags`: an input value the step read was NaN or infinite.
pub const ADM_OUT_NONFINITE_INPUT: u32 = 1 << 2;
/// `AdmOutput::flags`: the estimate is still held at zero (`observer.warmup`).
pub const ADM_OUT_WARMUP: u32 = 1 << 3;
/// `AdmOutput::flags`: this output is a held copy of the last good step's (after a panic).
pub const ADM_OUT_HELD: u32 = 1 << 4;
/// `AdmOutput::flags`: `wrench` and `wrench_tip` hold an estimate (`ADM_CONFIG_WRENCH`).
pub const ADM_OUT_WRENCH: u32 = 1 << 5;
/// `AdmOutput::flags`: a measured value of this step was implausible (an angle beyond its
/// joint's limits by `signals.gates.angle_margin`, a jump faster than
/// `signals.gates.jump_factor` times the velocity limit, a torque beyond
/// `signals.gates.torque_factor` times the effort limit): it was replaced by NaN before
/// any filter, observer or admittance state saw it, and counted
/// (`AdmOutput::implausible_samples`). `fault` is `ADM_FAULT_IMPLAUSIBLE_MEASUREMENT`.
pub const ADM_OUT_IMPLAUSIBLE_INPUT: u32 = 1 << 6;
/// `AdmOutput::flags`: some joint has not yet delivered a valid angle: the command is zero
/// (`fault` is `ADM_FAULT_NO_ANGLE_YET`).
pub const ADM_OUT_WAITING_FOR_ANGLES: u32 = 1 << 7;
/// `AdmOutput::flags`: no desired motion was given (`ADM_INPUT_DESIRED` unset): the loop
/// holds the first pose at which every joint had a valid angle.
pub const ADM_OUT_HOLDING_POSE: u32 = 1 << 8;
/// `AdmOutput::flags`: the contact detector (a deployment with `[contact]`) sees a contact;
/// `contact_link` names the last loaded joint.
pub const ADM_OUT_CONTACT: u32 = 1 << 9;
/// `AdmOutput::flags`: the contact detector sees a collision (the upper level).
pub const ADM_OUT_COLLISION: u32 = 1 << 10;
/// `AdmOutput::flags`: some joint's angle is a reading repeated while the joint was moving
/// (a driver repeating its last packet, a frozen encoder), from its first stale sample; the
/// controller's safe hold (`ADM_FAULT_STALE_MEASUREMENT`) follows if it lasts.
pub const ADM_OUT_STALE_INPUT: u32 = 1 << 11;
/// `AdmOutput::flags`: some joint's measured angle lies outside the positions the
/// observer's identification was fitted on (its `summary.training_range`): the model
/// extrapolates there and the estimate may hold a false torque the floor did not see.
pub const ADM_OUT_OUTSIDE_TRAINING_RANGE: u32 = 1 << 12;
/// `AdmOutput::flags`: some joint moved faster than the observer's identification was
/// fitted at (its `summary.training_speed`, by more than its margin): the friction
/// extrapolates there and the estimate may hold a false torque the floor did not see.
pub const ADM_OUT_FASTER_THAN_TRAINING: u32 = 1 << 13;

/// `AdmConfig::flags`: estimate the hand wrench each step (`AdmOutput::wrench`), about
/// 1 us more per step on a 7-joint arm.
pub const ADM_CONFIG_WRENCH: u32 = 1;

/// `AdmOutput::fault`: no fault.
pub const ADM_FAULT_NONE: i32 = 0;
/// `AdmOutput::fault`: an argument had the wrong length (a bug of the library).
pub const ADM_FAULT_WRONG_LENGTH: i32 = 1;
/// `AdmOutput::fault`: a measured `q` or `qdot` was NaN or infinite (`fault_joint`).
pub const ADM_FAULT_NONFINITE_MEASUREMENT: i32 = 2;
/// `AdmOutput::fault`: a joint's measured position repeated bit for bit while it should
/// move (a frozen encoder or dropped samples; `fault_joint`).
pub const ADM_FAULT_STALE_MEASUREMENT: i32 = 3;
/// `AdmOutput::fault`: a reference (desired trajectory or `q_r`) was NaN or infinite.
pub const ADM_FAULT_NONFINITE_REFERENCE: i32 = 4;
/// `AdmOutput::fault`: the external-torque estimate was NaN or infinite.
pub const ADM_FAULT_NONFINITE_ESTIMATE: i32 = 5;
/// `AdmOutput::fault`: the control period is not finite and positive.
pub const ADM_FAULT_INVALID_TIME_STEP: i32 = 6;
/// `AdmOutput::fault`: the control law produced a non-finite torque.
pub const ADM_FAULT_NONFINITE_OUTPUT: i32 = 7;
/// `AdmOutput::fault`: a dynamics or network call failed (reported, never a panic).
pub const ADM_FAULT_INTERNAL: i32 = 8;
/// `AdmOutput::fault`: a measured value was implausible (`ADM_OUT_IMPLAUSIBLE_INPUT`;
/// `fault_joint`): the step ran on the held signals, the controller's safe hold when it
/// was an angle.
pub const ADM_FAULT_IMPLAUSIBLE_MEASUREMENT: i32 = 9;
/// `AdmOutput::fault`: some joint has not yet delivered a valid angle: the command is zero.
pub const ADM_FAULT_NO_ANGLE_YET: i32 = 10;

/// What `adm_create` builds the loop from. Zero-initialise it, then set the fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AdmConfig {
    /// Must be `ADM_ABI_VERSION` (the header the caller was compiled with).
    pub abi_version: u32,
    /// The joint count the caller will send: checked against the arm's chain at create.
    pub n_joints: u32,
    /// Path of a deployment folder (UTF-8, NUL-terminated) written by `admittance deploy`:
    /// `loop.toml` (arm, rate, signal chain, controller, admittance model, observer,
    /// contact), the URDF, the identification and networks it names, and `manifest.json`
    /// with every file's checksum. `adm_create` never trains; a scenario file is refused
    /// with the `admittance deploy` command to run.
    pub deployment_path: *const c_char,
    /// Overrides of `loop.toml`, or null: `KEY=VALUE` lines separated by newlines
    /// (`controller.pd.kp=[100, 150, 50, 50, 10, 10, 2]`).
    pub overrides: *const c_char,
    /// `ADM_CONFIG_*` bits.
    pub flags: u32,
    /// Reserved, zero.
    pub reserved: u32,
    /// Damping (in the units of the Jacobian's singular values, m) of the wrench's damped
    /// pseudo-inverse with `ADM_CONFIG_WRENCH`; 0 picks 1e-3.
    pub wrench_damping: f64,
}

/// One control period's inputs.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AdmInput {
    /// Time of the sample (s), from any origin: the loop's warm-up counts from 0. One call
    /// per control period (`control_rate_hz` of `loop.toml`): the filters assume that
    /// period.
    pub time: f64,
    /// The number of joints filled in: must be the handle's.
    pub n_joints: u32,
    /// `ADM_INPUT_*` bits: which optional arrays are filled in.
    pub flags: u32,
    /// Measured joint positions (rad; m for a prismatic joint), encoder side.
    pub q: [f64; ADM_MAX_JOINTS],
    /// Measured joint velocities (rad/s or m/s), read with `ADM_INPUT_QDOT`.
    pub qdot: [f64; ADM_MAX_JOINTS],
    /// Measured joint torques (N m; N for a prismatic joint), the torque the drives apply
    /// to the links (Franka's `tau_J`, a KUKA's measured torque), read with
    /// `ADM_INPUT_TAU`: the quantity the learned observers' free-motion data record.
    pub tau: [f64; ADM_MAX_JOINTS],
    /// Desired joint positions (rad), read with `ADM_INPUT_DESIRED`.
    pub q_d: [f64; ADM_MAX_JOINTS],
    /// Desired joint velocities (rad/s), read with `ADM_INPUT_DESIRED`.
    pub qdot_d: [f64; ADM_MAX_JOINTS],
    /// Desired joint accelerations (rad/s^2), read with `ADM_INPUT_DESIRED`.
    pub qddot_d: [f64; ADM_MAX_JOINTS],
}

/// One control period's outputs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdmOutput {
    /// The input's time (s).
    pub time: f64,
    /// Steps run on this handle so far, this one included.
    pub step: u64,
    /// The handle's joint count.
    pub n_joints: u32,
    /// `ADM_OUT_*` bits.
    pub flags: u32,
    /// `ADM_FAULT_*`: the fault of this step, if any.
    pub fault: i32,
    /// The first joint the fault names (chain order, 0-based), or 0.
    pub fault_joint: u32,
    /// Samples refused by the plausibility gates since `adm_create`.
    pub implausible_samples: u64,
    /// With `ADM_OUT_CONTACT`: the last loaded joint (chain order); else -1.
    pub contact_link: i32,
    /// Reserved, zero.
    pub reserved: u32,
    /// The torque command to send (N m): finite and within the URDF's effort limits. With
    /// a controller fault it is the controller's safe hold; before every joint has
    /// delivered a valid angle it is zero.
    pub tau_cmd: [f64; ADM_MAX_JOINTS],
    /// The external-torque estimate (N m): the torque the environment (a person, a
    /// contact) applies to the robot's joints, low-passed (`observer.cutoff_hz`), zero
    /// during the warm-up.
    pub tau_ext: [f64; ADM_MAX_JOINTS],
    /// The compliant reference `q_r` (rad) the controller tracks: the desired trajectory
    /// shaped by the admittance model (`q_d` without one).
    pub q_r: [f64; ADM_MAX_JOINTS],
    /// `q_r'` (rad/s).
    pub qdot_r: [f64; ADM_MAX_JOINTS],
    /// `q_r''` (rad/s^2).
    pub qddot_r: [f64; ADM_MAX_JOINTS],
    /// The estimated wrench the environment applies to the hand (`ADM_OUT_WRENCH`, with
    /// `ADM_CONFIG_WRENCH`): force x, y, z (N) at the origin of the `[arm] tip` link, then
    /// moment x, y, z (N m) about it, in the axes of the `[arm] base` link;
    /// `f = (J J^T + d^2 I)^-1 J tau_ext` with `J` the tip's geometric Jacobian at the
    /// measured `q` and `d = AdmConfig::wrench_damping`. Zero without `ADM_OUT_WRENCH`.
    pub wrench: [f64; 6],
    /// The same wrench in the axes of the `[arm] tip` link: what a force-torque sensor
    /// mounted at the tip would report (ros2_control's `ft_sensor`, `ft_sensor.frame.id` =
    /// the tip link).
    pub wrench_tip: [f64; 6],
    /// With `ADM_OUT_CONTACT`: the wrench the environment applies at the touched link (the
    /// origin of joint `contact_link`'s child link), from the estimate of that joint and
    /// the ones before it (a force on a link loads those only), in the `[arm] base` axes:
    /// force x, y, z (N), moment x, y, z (N m); with fewer than six joints before the link,
    /// the smallest wrench that explains their estimate. Zero without a contact.
    pub contact_wrench: [f64; 6],
    /// The same wrench in the touched link's axes.
    pub contact_wrench_link: [f64; 6],
}

impl AdmOutput {
    /// All zero (`contact_link` -1: no contact).
    pub const ZERO: AdmOutput = AdmOutput {
        time: 0.0,
        step: 0,
        n_joints: 0,
        flags: 0,
        fault: 0,
        fault_joint: 0,
        implausible_samples: 0,
        contact_link: -1,
        reserved: 0,
        tau_cmd: [0.0; ADM_MAX_JOINTS],
        tau_ext: [0.0; ADM_MAX_JOINTS],
        q_r: [0.0; ADM_MAX_JOINTS],
        qdot_r: [0.0; ADM_MAX_JOINTS],
        qddot_r: [0.0; ADM_MAX_JOINTS],
        wrench: [0.0; 6],
        wrench_tip: [0.0; 6],
        contact_wrench: [0.0; 6],
        contact_wrench_link: [0.0; 6],
    };
}

impl AdmInput {
    /// All zero (no optional array flagged).
    pub const ZERO: AdmInput = AdmInput {
        time: 0.0,
        n_joints: 0,
        flags: 0,
        q: [0.0; ADM_MAX_JOINTS],
        qdot: [0.0; ADM_MAX_JOINTS],
        tau: [0.0; ADM_MAX_JOINTS],
        q_d: [0.0; ADM_MAX_JOINTS],
        qdot_d: [0.0; ADM_MAX_JOINTS],
        qddot_d: [0.0; ADM_MAX_JOINTS],
    };
}

// No padding anywhere: the sizes are the sums of the fields.
const _: () = assert!(std::mem::size_of::<AdmInput>() == 16 + 6 * 8 * ADM_MAX_JOINTS);
const _: () = assert!(std::mem::size_of::<AdmOutput>() == 48 + 5 * 8 * ADM_MAX_JOINTS + 4 * 48);
