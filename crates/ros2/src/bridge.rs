//! The bridge's logic without DDS: one `sensor_msgs/JointState` in, one step of the robot's
//! loop (`admittance_loop::RobotLoop` of a deployment folder, the loop `adm_create` wraps:
//! plausibility gates, signal chain, observer, admittance model, controller), the estimate out as a `JointState` (effort: the external joint
//! torques, Franka's `external_joint_torques` convention) and a `WrenchStamped`.
//!
//! The same [`Bridge::process`] runs inside the DDS loop ([`crate::node`]) and offline
//! ([`offline`]), so the published estimate and an offline run over the same messages come
//! from the same code.

use std::path::PathBuf;

use admittance_bag::msgs::{
    Float64MultiArray, Header, JointState, MultiArrayDimension, MultiArrayLayout, Vector3, Wrench,
    WrenchStamped,
};
use admittance_bag::{Profile, FLOAT64_MULTI_ARRAY, JOINT_STATE, WRENCH_STAMPED};
use admittance_loop::{RobotInput, RobotLoop, RobotStatus};

/// The axes of the published wrench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum WrenchFrame {
    /// The arm's base link (`frame_id` = the base link's name), as Franka's
    /// `external_wrench_in_base_frame`.
    Base,
    /// The tip link (`frame_id` = the tip link's name).
    Tip,
}

/// What a bridge is built from.
#[derive(Clone, Debug)]
pub struct BridgeConfig {
    /// The deployment folder (`admittance deploy`: `loop.toml` with the arm, the rate, the
    /// observer, ...; every file checked against its manifest).
    pub deployment: PathBuf,
    /// `KEY=VALUE` overrides of `loop.toml` (the CLI's `--set`).
    pub overrides: Vec<String>,
    /// Which topic and fields give `q`, `qdot`, `tau` (a bag profile).
    pub profile: Profile,
    /// The message's joint names in the arm's chain order, when they differ from the URDF's
    /// (else the profile's `joints`, else the URDF's names).
    pub joints: Option<Vec<String>>,
    /// The axes of the published wrench.
    pub wrench_frame: WrenchFrame,
}

/// Where the bridge reads each signal: the profile's JointState topic and fields.
#[derive(Clone, Debug, PartialEq)]
pub struct InputMap {
    /// The topic (`/franka_robot_state_broadcaster/measured_joint_states`).
    pub topic: String,
    /// The field giving `q`.
    pub q_field: String,
    /// The field giving `qdot`; `None`: differentiated from `q` by the signal chain.
    pub qdot_field: Option<String>,
    /// The field giving `tau`.
    pub tau_field: String,
    /// Per joint, multiplies the `tau` field (a motor current's torque constant), in chain
    /// order.
    pub tau_scale: Option<Vec<f64>>,
}

impl InputMap {
    /// The mapping a profile describes, or an error naming the profile's key when the bridge
    /// cannot subscribe to it (another message type, signals on different topics).
    pub fn from_profile(profile: &Profile) -> Result<Self, String> {
        let p = &profile.name;
        let mut sources = vec![("q", &profile.q)];
        if let Some(s) = &profile.qdot {
            sources.push(("qdot", s));
        }
        sources.push(("tau", &profile.tau));
        for (role, s) in &sources {
            if s.type_name != JOINT_STATE {
                return Err(format!(
                    "profile {p}: [{role}] reads `{}` ({}): the bridge subscribes to one {JOINT_STATE} topic; use a copy of the profile whose q, qdot and tau come from a JointState topic{}",
                    s.topic,
                    s.type_name,
                    if profile.name == "lbr" {
                        " (lbr_fri_ros2_stack: /lbr/joint_states, effort = measured torque)"
                    } else {
                        ""
                    }
                ));
            }
            if *role != "q" && s.topic != profile.q.topic {
                return Err(format!(
                    "profile {p}: [{role}] topic `{}` is not [q]'s `{}`: the bridge subscribes to one topic",
                    s.topic, profile.q.topic
                ));
            }
        }
        Ok(Self {
            topic: profile.q.topic.clone(),
            q_field: profile.q.field.clone(),
            qdot_field: profile.qdot.as_ref().map(|s| s.field.clone()),
            tau_field: profile.tau.field.clone(),
            tau_scale: profile.tau.torque_constant.clone(),
        })
    }
}

/// Why a message was not stepped: the message is skipped and counted, the bridge goes on.
#[derive(Clone, Debug, PartialEq)]
pub struct InputError {
    /// A short fixed reason (the statistics count by it).
    pub reason: &'static str,
    /// The topic, field, joint and values concerned, in words.
    pub detail: String,
}

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.reason, self.detail)
    }
}

/// One message's step: when it was, and the loop's report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stepped {
    /// The message's header stamp (ns since the epoch).
    pub stamp_ns: i64,
    /// The loop's time: seconds since the first stepped message's stamp.
    pub time: f64,
    /// The loop's status (faults, implausible samples, contact).
    pub status: RobotStatus,
}

/// The bridge: a loop and the mapping of one JointState topic onto it.
pub struct Bridge {
    rust_loop: RobotLoop,
    map: InputMap,
    /// The names the messages use, in chain order.
    names: Vec<String>,
    /// Per chain joint, its index in the last message's `name` (cached while the names
    /// repeat).
    index: Vec<usize>,
    cached_names: Vec<String>,
    q: Vec<f64>,
    qdot: Vec<f64>,
    tau: Vec<f64>,
    first_stamp: Option<i64>,
    last_stamp: Option<i64>,
    base_link: String,
    tip_link: String,
    wrench_frame: WrenchFrame,
}

impl Bridge {
    /// Builds the loop from the deployment folder (errors name the file and key; nothing is
    /// trained) and checks the profile against it.
    pub fn new(config: &BridgeConfig) -> Result<Self, String> {
        let map = InputMap::from_profile(&config.profile)?;
        let overrides: Vec<&str> = config.overrides.iter().map(String::as_str).collect();
        let dir = &config.deployment;
        let mut rust_loop = RobotLoop::load(dir, &overrides).map_err(|e| e.text())?;
        rust_loop.enable_wrench(0.0).map_err(|e| e.text())?;
        let n = rust_loop.dof();
        let names: Vec<String> = match (&config.joints, &config.profile.joints) {
            (Some(j), _) => j.clone(),
            (None, Some(j)) => j.clone(),
            (None, None) => rust_loop.joints().to_vec(),
        };
        if names.len() != n {
            return Err(format!(
                "{} joint names given ({}) for the {n} joints of {}'s [arm] chain ({})",
                names.len(),
                names.join(", "),
                config.deployment.display(),
                rust_loop.joints().join(", ")
            ));
        }
        if let Some(k) = &map.tau_scale {
            if k.len() != n {
                return Err(format!(
                    "profile {}: [tau] torque_constant has {} values for {n} joints",
                    config.profile.name,
                    k.len()
                ));
            }
        }
        let model = rust_loop.model();
        let base_link = model.base_link.clone();
        let tip_link = model.tip().name.clone();
        Ok(Self {
            map,
            names,
            index: vec![0; n],
            cached_names: Vec::new(),
            q: vec![0.0; n],
            qdot: vec![0.0; n],
            tau: vec![0.0; n],
            first_stamp: None,
            last_stamp: None,
            base_link,
            tip_link,
            wrench_frame: config.wrench_frame,
            rust_loop,
        })
    }

    /// The topic and fields read.
    pub fn input_map(&self) -> &InputMap {
        &self.map
    }

    /// The message joint names, in chain order.
    pub fn joint_names(&self) -> &[String] {
        &self.names
    }

    /// The loop's control period (s): the period the messages are expected at.
    pub fn dt(&self) -> f64 {
        self.rust_loop.dt()
    }

    /// The loop (its estimate, reference, wrench of the last step).
    pub fn rust_loop(&self) -> &RobotLoop {
        &self.rust_loop
    }

    /// The `frame_id` of the published wrench.
    pub fn wrench_frame_id(&self) -> &str {
        match self.wrench_frame {
            WrenchFrame::Base => &self.base_link,
            WrenchFrame::Tip => &self.tip_link,
        }
    }

    /// Maps the message's names onto the chain (cached while they repeat).
    fn map_names(&mut self, msg: &JointState) -> Result<(), InputError> {
        if msg.name == self.cached_names {
            return Ok(());
        }
        for (k, wanted) in self.names.iter().enumerate() {
            match msg.name.iter().position(|n| n == wanted) {
                Some(i) => self.index[k] = i,
                None => {
                    self.cached_names.clear();
                    return Err(InputError {
                        reason: "joint missing",
                        detail: format!(
                            "{}: field `name` has no joint `{wanted}` (names: [{}]; the arm's joints: [{}]; pass --joints or a profile's `joints` when the robot names them otherwise)",
                            self.map.topic,
                            msg.name.join(", "),
                            self.names.join(", ")
                        ),
                    });
                }
            }
        }
        self.cached_names.clone_from(&msg.name);
        Ok(())
    }

    /// Gathers one field into `dst` in chain order, checking its length and values.
    fn gather(
        topic: &str,
        msg: &JointState,
        field: &str,
        index: &[usize],
        names: &[String],
        dst: &mut [f64],
    ) -> Result<(), InputError> {
        let values: &[f64] = match field {
            "position" => &msg.position,
            "velocity" => &msg.velocity,
            "effort" => &msg.effort,
            other => {
                return Err(InputError {
                    reason: "unknown field",
                    detail: format!("{topic}: JointState has no field `{other}`"),
                })
            }
        };
        if values.len() != msg.name.len() {
            return Err(InputError {
                reason: "wrong length",
                detail: format!(
                    "{topic}: field `{field}` has {} values for {} names",
                    values.len(),
                    msg.name.len()
                ),
            });
        }
        for (k, &i) in index.iter().enumerate() {
            let v = values[i];
            if !v.is_finite() {
                return Err(InputError {
                    reason: "non-finite value",
                    detail: format!("{topic}: field `{field}` of joint `{}` is {v}", names[k]),
                });
            }
            dst[k] = v;
        }
        Ok(())
    }

    /// One message: checks it (names, lengths, finite values, a stamp after the previous
    /// one), steps the loop at the message's stamp (seconds since the first stepped
    /// message), and returns what was stepped. A rejected message changes nothing.
    pub fn process(&mut self, msg: &JointState) -> Result<Stepped, InputError> {
        let stamp = msg.header.stamp.nanos();
        let topic = &self.map.topic;
        if msg.header.stamp.is_zero() {
            return Err(InputError {
                reason: "zero stamp",
                detail: format!(
                    "{topic}: header.stamp is zero: the observer is timed by the stamps"
                ),
            });
        }
        if let Some(last) = self.last_stamp {
            if stamp <= last {
                return Err(InputError {
                    reason: "stamp not increasing",
                    detail: format!(
                        "{topic}: header.stamp {} ns is not after the previous message's {} ns",
                        stamp, last
                    ),
                });
            }
        }
        self.map_names(msg)?;
        let topic = self.map.topic.as_str();
        Self::gather(
            topic,
            msg,
            &self.map.q_field,
            &self.index,
            &self.names,
            &mut self.q,
        )?;
        if let Some(f) = &self.map.qdot_field {
            Self::gather(topic, msg, f, &self.index, &self.names, &mut self.qdot)?;
        }
        Self::gather(
            topic,
            msg,
            &self.map.tau_field,
            &self.index,
            &self.names,
            &mut self.tau,
        )?;
        if let Some(k) = &self.map.tau_scale {
            for (t, k) in self.tau.iter_mut().zip(k) {
                *t *= k;
            }
        }
        let first = *self.first_stamp.get_or_insert(stamp);
        self.last_stamp = Some(stamp);
        let time = (stamp - first) as f64 * 1e-9;
        let status = self.rust_loop.step(&RobotInput {
            time,
            q: &self.q,
            qdot: self.map.qdot_field.is_some().then_some(&self.qdot[..]),
            tau: Some(&self.tau),
            desired: None,
        });
        Ok(Stepped {
            stamp_ns: stamp,
            time,
            status,
        })
    }

    /// The external joint torques of the last step as a JointState (names in chain order,
    /// `effort` the estimate, position and velocity empty), stamped with `header`.
    pub fn torque_message(&self, header: &Header) -> JointState {
        JointState {
            header: header.clone(),
            name: self.names.clone(),
            position: Vec::new(),
            velocity: Vec::new(),
            effort: self.rust_loop.external_torque_estimate().to_vec(),
        }
    }

    /// The compliant reference of the last step (`q_r` as position, `q_r'` as velocity).
    pub fn reference_message(&self, header: &Header) -> JointState {
        let [q_r, qdot_r, _] = self.rust_loop.reference();
        JointState {
            header: header.clone(),
            name: self.names.clone(),
            position: q_r.to_vec(),
            velocity: qdot_r.to_vec(),
            effort: Vec::new(),
        }
    }

    /// The hand wrench of the last step, in the configured axes, `frame_id` their link.
    pub fn wrench_message(&self, header: &Header) -> WrenchStamped {
        let w = self
            .rust_loop
            .wrench()
            .map(|(base, tip)| match self.wrench_frame {
                WrenchFrame::Base => base,
                WrenchFrame::Tip => tip,
            })
            .unwrap_or(&[0.0; 6]);
        WrenchStamped {
            header: Header {
                stamp: header.stamp,
                frame_id: self.wrench_frame_id().to_string(),
            },
            wrench: Wrench {
                force: Vector3 {
                    x: w[0],
                    y: w[1],
                    z: w[2],
                },
                torque: Vector3 {
                    x: w[3],
                    y: w[4],
                    z: w[5],
                },
            },
        }
    }
}

/// The contact flags of a step (issue 31), when the loop has a contact floor: a
/// `std_msgs/msg/Float64MultiArray` `[contact, collision, link, fx, fy, fz, mx, my, mz]`: 1
/// or 0, 1 or 0, the last loaded joint (from 0, in chain order; -1 when none), then the
/// wrench at that joint's child link in the base axes (`RobotLoop::contact_wrench`: N, then
/// N m about the link's origin; zero without a contact), its layout's one dimension labelled
/// with those names. The message has no header: one is published per torque message, after
/// it.
pub fn contact_message(status: &RobotStatus, wrench: Option<&[f64]>) -> Option<Float64MultiArray> {
    let c = status.contact?;
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    let mut data = vec![flag(c.contact), flag(c.collision), f64::from(c.link)];
    data.extend((0..6).map(|k| wrench.and_then(|w| w.get(k)).copied().unwrap_or(0.0)));
    Some(Float64MultiArray {
        layout: MultiArrayLayout {
            dim: vec![MultiArrayDimension {
                label: CONTACT_LABEL.into(),
                size: 9,
                stride: 9,
            }],
            data_offset: 0,
        },
        data,
    })
}

/// The label of the contact message's dimension: what each value is.
pub const CONTACT_LABEL: &str = "contact,collision,link,fx,fy,fz,mx,my,mz";

/// The loop's status of a step as a `std_msgs/msg/Float64MultiArray` of flags, 1 or 0 in the
/// order of [`STATUS_LABEL`] (the C ABI's `ADM_OUT_*` bits of the same names): what the
/// estimate beside it can be trusted for. Published after each torque message, with or
/// without a contact floor; like the contact message it has no header.
pub fn status_message(status: &RobotStatus) -> Float64MultiArray {
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    let data = vec![
        flag(status.controller_fault.is_some()),
        flag(status.observer_fault),
        flag(status.nonfinite_input),
        flag(status.implausible.is_some()),
        flag(status.waiting_for_angles),
        flag(status.warmup),
        flag(status.holding_pose),
        flag(status.stale_input),
        flag(status.outside_training_range),
        flag(status.faster_than_training),
    ];
    Float64MultiArray {
        layout: MultiArrayLayout {
            dim: vec![MultiArrayDimension {
                label: STATUS_LABEL.into(),
                size: data.len() as u32,
                stride: data.len() as u32,
            }],
            data_offset: 0,
        },
        data,
    }
}

/// The label of the status message's dimension: the flags in order.
pub const STATUS_LABEL: &str = "controller_fault,observer_fault,nonfinite_input,implausible_input,\
waiting_for_angles,warmup,holding_pose,stale_input,outside_training_range,faster_than_training";

/// The message types the bridge publishes (for the node and the docs).
pub const OUTPUT_TYPES: [&str; 3] = [JOINT_STATE, WRENCH_STAMPED, FLOAT64_MULTI_ARRAY];

/// The same bridge run offline over `messages` in order: per message, the estimate (or
/// why it was skipped).
pub fn offline<'a>(
    config: &BridgeConfig,
    messages: impl IntoIterator<Item = &'a JointState>,
) -> Result<Vec<Result<(Stepped, Vec<f64>), InputError>>, String> {
    let mut bridge = Bridge::new(config)?;
    Ok(messages
        .into_iter()
        .map(|m| {
            bridge
                .process(m)
                .map(|s| (s, bridge.rust_loop.external_torque_estimate().to_vec()))
        })
        .collect())
}
