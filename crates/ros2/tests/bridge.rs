//! The bridge's logic without DDS: name mapping, bad messages (skipped with the topic,
//! field and joint named, nothing stepped), profiles it cannot subscribe to, and the
//! estimate equal to the loop of `adm_create` stepped directly.

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use admittance_bag::msgs::JointState;
use admittance_bag::Profile;
use admittance_loop::{RobotInput, RobotLoop};
use admittance_ros2::node::fake_sample;
use admittance_ros2::{
    contact_message, offline, status_message, Bridge, BridgeConfig, WrenchFrame,
};

/// The deployment folder, written once for the whole test binary.
fn deployment() -> PathBuf {
    static DIR: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, dir) = DIR.get_or_init(common::deploy);
    Path::new(dir).to_path_buf()
}

fn chain() -> Vec<String> {
    (1..=7).map(|i| format!("panda_joint{i}")).collect()
}

fn config(profile: &str) -> BridgeConfig {
    BridgeConfig {
        deployment: deployment(),
        overrides: Vec::new(),
        profile: Profile::resolve(profile).unwrap(),
        joints: None,
        wrench_frame: WrenchFrame::Base,
    }
}

const T0: i64 = 1_700_000_000_000_000_000;
const MS: i64 = 1_000_000;

fn messages(n: u64, joints: &[String]) -> Vec<JointState> {
    (0..n).map(|k| fake_sample(k, joints, T0, MS)).collect()
}

#[test]
fn estimate_equals_the_loop_stepped_directly_and_names_map_in_any_order() {
    let n = 1500;
    let mut reversed = chain();
    reversed.reverse();
    let by_bridge = offline(&config("franka"), &messages(n, &reversed)).unwrap();

    // The loop adm_create builds, stepped with the chain-order arrays.
    let mut direct = RobotLoop::load(&deployment(), &[]).unwrap();
    let mut nonzero = 0;
    for (k, r) in by_bridge.iter().enumerate() {
        let m = fake_sample(k as u64, &chain(), T0, MS);
        direct.step(&RobotInput {
            time: (k as i64 * MS) as f64 * 1e-9,
            q: &m.position,
            qdot: Some(&m.velocity),
            tau: Some(&m.effort),
            desired: None,
        });
        let (_, est) = r.as_ref().unwrap();
        assert_eq!(
            est.as_slice(),
            direct.external_torque_estimate(),
            "step {k}"
        );
        nonzero += est.iter().any(|x| x.abs() > 1e-3) as usize;
    }
    assert!(nonzero > 900, "{nonzero}");
}

#[test]
fn published_messages_carry_the_stamp_names_and_frame() {
    let mut bridge = Bridge::new(&config("franka")).unwrap();
    let msgs = messages(700, &chain());
    for m in &msgs {
        bridge.process(m).unwrap();
    }
    let last = msgs.last().unwrap();
    let torque = bridge.torque_message(&last.header);
    assert_eq!(torque.header.stamp, last.header.stamp);
    assert_eq!(torque.name, chain());
    assert_eq!(torque.effort, bridge.rust_loop().external_torque_estimate());
    assert!(torque.position.is_empty() && torque.velocity.is_empty());
    let wrench = bridge.wrench_message(&last.header);
    assert_eq!(wrench.header.frame_id, "panda_link0");
    assert_eq!(wrench.header.stamp, last.header.stamp);
    let (base, _) = bridge.rust_loop().wrench().unwrap();
    assert_eq!(wrench.wrench.force.x, base[0]);
    assert_eq!(wrench.wrench.torque.z, base[5]);
    assert!(base.iter().any(|x| x.abs() > 1e-6));
    let mut tip = config("franka");
    tip.wrench_frame = WrenchFrame::Tip;
    assert_eq!(
        Bridge::new(&tip).unwrap().wrench_frame_id(),
        "panda_hand_tcp"
    );
    let reference = bridge.reference_message(&last.header);
    assert_eq!(reference.position, bridge.rust_loop().reference()[0]);
}

/// Each bad message is refused with the topic, field and joint named, and changes nothing:
/// the good messages after it give the estimate of a run without it.
#[test]
fn bad_messages_are_skipped_named_and_change_nothing() {
    let good = messages(300, &chain());
    let topic = "/franka_robot_state_broadcaster/measured_joint_states";
    let mut bad: Vec<(JointState, &str, &str)> = Vec::new();
    let base = fake_sample(150, &chain(), T0, MS);
    let mut m = base.clone();
    m.name[3] = "fr3_joint4".into();
    bad.push((m, "joint missing", "no joint `panda_joint4`"));
    let mut m = base.clone();
    m.effort.pop();
    bad.push((m, "wrong length", "field `effort` has 6 values for 7 names"));
    let mut m = base.clone();
    m.velocity.clear();
    bad.push((m, "wrong length", "field `velocity` has 0 values"));
    let mut m = base.clone();
    m.position[2] = f64::NAN;
    bad.push((
        m,
        "non-finite value",
        "field `position` of joint `panda_joint3` is NaN",
    ));
    let mut m = base.clone();
    m.header.stamp = good[100].header.stamp;
    bad.push((
        m,
        "stamp not increasing",
        "is not after the previous message's",
    ));
    let mut m = base.clone();
    m.header.stamp.sec = 0;
    m.header.stamp.nanosec = 0;
    bad.push((m, "zero stamp", "header.stamp is zero"));

    let mut with_bad = Vec::new();
    for (k, g) in good.iter().enumerate() {
        if k == 150 {
            with_bad.extend(bad.iter().map(|b| b.0.clone()));
        }
        with_bad.push(g.clone());
    }
    let clean = offline(&config("franka"), &good).unwrap();
    let dirty = offline(&config("franka"), &with_bad).unwrap();
    let mut errors = dirty.iter().filter_map(|r| r.as_ref().err());
    for (_, reason, detail) in &bad {
        let e = errors.next().unwrap();
        assert_eq!(e.reason, *reason);
        assert!(e.detail.starts_with(topic), "{e}");
        assert!(e.detail.contains(detail), "{e}");
    }
    assert!(errors.next().is_none());
    let dirty_ok: Vec<_> = dirty.iter().filter_map(|r| r.as_ref().ok()).collect();
    assert_eq!(dirty_ok.len(), clean.len());
    for (a, b) in dirty_ok.iter().zip(&clean) {
        assert_eq!(a.1, b.as_ref().unwrap().1);
    }
}

#[test]
fn profiles_and_joint_lists_it_cannot_use_are_named() {
    // KUKA's LBRState is not a JointState.
    let e = Bridge::new(&config("lbr")).err().unwrap();
    assert!(
        e.contains("/lbr/state") && e.contains("/lbr/joint_states"),
        "{e}"
    );
    // UR: current needs torque constants; with them the effort is scaled.
    // (A copy for a 7-joint arm: the Panda's names, a torque constant of 2 N m/A.)
    let names = chain()
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ");
    let ur = include_str!("../../bag/profiles/ur.toml")
        .replace(
            "unit = \"A\"",
            "unit = \"A\"\ntorque_constant = [2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]",
        )
        .replace(
            "joints = [\"shoulder_pan_joint\", \"shoulder_lift_joint\", \"elbow_joint\", \"wrist_1_joint\", \"wrist_2_joint\", \"wrist_3_joint\"]",
            &format!("joints = [{names}]"),
        );
    let mut c = config("franka");
    c.profile = Profile::parse(&ur, "ur-copy").unwrap();
    let mut bridge = Bridge::new(&c).unwrap();
    assert_eq!(bridge.input_map().topic, "/joint_states");
    // The scaled effort: the same estimate as a franka bridge fed twice the effort.
    let msgs = messages(600, &chain());
    let doubled: Vec<_> = msgs
        .iter()
        .map(|m| {
            let mut d = m.clone();
            d.effort.iter_mut().for_each(|x| *x *= 2.0);
            d
        })
        .collect();
    let mut reference = Bridge::new(&config("franka")).unwrap();
    for (m, d) in msgs.iter().zip(&doubled) {
        bridge.process(m).unwrap();
        reference.process(d).unwrap();
    }
    assert_eq!(
        bridge.rust_loop().external_torque_estimate(),
        reference.rust_loop().external_torque_estimate()
    );
    // A joint list of the wrong length, and a loop.toml error naming its key.
    let mut c = config("franka");
    c.joints = Some(vec!["a".into(), "b".into()]);
    let e = Bridge::new(&c).err().unwrap();
    assert!(
        e.contains("2 joint names given") && e.contains("panda_joint1"),
        "{e}"
    );
    let mut c = config("franka");
    c.overrides = vec!["observer.cutoff_hz=oops".into()];
    let e = Bridge::new(&c).err().unwrap();
    assert!(e.contains("cutoff_hz"), "{e}");
    // --joints renames: a robot calling them fr3_joint1..7.
    let mut c = config("franka");
    let fr3: Vec<String> = (1..=7).map(|i| format!("fr3_joint{i}")).collect();
    c.joints = Some(fr3.clone());
    let mut b = Bridge::new(&c).unwrap();
    b.process(&fake_sample(0, &fr3, T0, MS)).unwrap();
    assert_eq!(b.torque_message(&Default::default()).name, fr3);
}

#[test]
fn contact_flags_are_published_only_with_a_contact_floor() {
    // The test deployment has no floor: no flags, no message.
    let mut bridge = Bridge::new(&config("franka")).unwrap();
    let stepped = bridge.process(&messages(1, &chain())[0]).unwrap();
    assert!(!bridge.rust_loop().has_contact_floor());
    assert!(contact_message(&stepped.status, None).is_none());
    // With flags: [contact, collision, link, wrench at the link] and the layout's label.
    let mut status = stepped.status;
    status.contact = Some(admittance_loop::ContactState {
        contact: true,
        collision: false,
        link: 4,
    });
    let wrench = [1.0, 2.0, 3.0, 0.1, 0.2, 0.3];
    let m = contact_message(&status, Some(&wrench)).unwrap();
    assert_eq!(m.data, [1.0, 0.0, 4.0, 1.0, 2.0, 3.0, 0.1, 0.2, 0.3]);
    assert_eq!(
        m.layout.dim[0].label,
        "contact,collision,link,fx,fy,fz,mx,my,mz"
    );
    assert_eq!(m.values().unwrap().len(), 9);
}

#[test]
fn status_flags_follow_the_loop_and_their_label() {
    let mut bridge = Bridge::new(&config("franka")).unwrap();
    let stepped = bridge.process(&messages(1, &chain())[0]).unwrap();
    let m = status_message(&stepped.status);
    let names: Vec<&str> = m.layout.dim[0].label.split(',').collect();
    assert_eq!(names.len(), m.data.len());
    assert_eq!(m.values().unwrap().len(), names.len());
    let at = |m: &admittance_bag::msgs::Float64MultiArray, name: &str| {
        m.data[names.iter().position(|n| *n == name).unwrap()]
    };
    // The first step: the flags the loop reports, nothing stale or outside the range.
    let st = &stepped.status;
    for (name, set) in [
        ("warmup", st.warmup),
        ("holding_pose", st.holding_pose),
        ("waiting_for_angles", st.waiting_for_angles),
        ("controller_fault", st.controller_fault.is_some()),
    ] {
        assert_eq!(at(&m, name), f64::from(u8::from(set)), "{name}");
    }
    assert_eq!(at(&m, "stale_input"), 0.0);
    assert_eq!(at(&m, "outside_training_range"), 0.0);
    assert_eq!(at(&m, "faster_than_training"), 0.0);
    // Each flag lands under its own name.
    let mut status = stepped.status;
    status.stale_input = true;
    status.outside_training_range = true;
    status.faster_than_training = true;
    let m = status_message(&status);
    assert_eq!(at(&m, "stale_input"), 1.0);
    assert_eq!(at(&m, "outside_training_range"), 1.0);
    assert_eq!(at(&m, "faster_than_training"), 1.0);
    assert_eq!(at(&m, "controller_fault"), 0.0);
    let before = status_message(&stepped.status);
    let changed: Vec<&str> = (0..names.len())
        .filter(|&k| m.data[k] != before.data[k])
        .map(|k| names[k])
        .collect();
    assert_eq!(
        changed,
        [
            "stale_input",
            "outside_training_range",
            "faster_than_training"
        ]
    );
}
