//! What published arm descriptions contain (issue 13, part 1): massless links written as
//! `<mass value="0"/>`, point masses, grippers with prismatic and mimic fingers, branches
//! hanging off mid-chain. Each loads; the locked and dropped branches are checked against
//! an independent formulation of the same arm (the branch's joints written as fixed, or the
//! branch deleted from the text).

use admittance_dynamics::{crba, rnea, Data, Model, UrdfOptions};

/// A three-joint arm with a camera branch on a moving joint mid-chain (on link1) and a two-finger
/// gripper (one prismatic finger, one mimic finger) at the hand. `{FINGER}`, `{MIMIC}` and
/// `{CAMERA}` are the joint types of the finger, the mimic finger and the camera's pan joint.
const ARM: &str = r#"<?xml version="1.0"?>
<robot name="gripper_arm">
  <link name="world"/>
  <link name="base_link">
    <inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
  </link>
  <link name="link1">
    <inertial><origin xyz="0 0 0.15"/><mass value="3.0"/>
      <inertia ixx="0.03" ixy="0.001" ixz="0" iyy="0.03" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="link2">
    <inertial><origin xyz="0.2 0 0"/><mass value="2.0"/>
      <inertia ixx="0.005" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
  </link>
  <link name="link3">
    <inertial><origin xyz="0.1 0 0"/><mass value="1.0"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.004"/></inertial>
  </link>
  <link name="flange">
    <inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
  </link>
  <link name="tcp"/>
  <link name="finger_left">
    <inertial><origin xyz="0 0.01 0.03"/><mass value="0.1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
  </link>
  <link name="finger_right">
    <inertial><origin xyz="0 -0.01 0.03"/><mass value="0.1"/>
      <inertia ixx="2e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="1e-6"/></inertial>
  </link>
  <link name="camera_link">
    <inertial><origin xyz="0.05 0 0.05"/><mass value="0.4"/>
      <inertia ixx="4e-4" ixy="0" ixz="0" iyy="4e-4" iyz="0" izz="4e-4"/></inertial>
  </link>
  <joint name="world_joint" type="fixed"><parent link="world"/><child link="base_link"/></joint>
  <joint name="joint1" type="revolute">
    <parent link="base_link"/><child link="link1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-2.8" upper="2.8" effort="80" velocity="2"/>
  </joint>
  <joint name="joint2" type="revolute">
    <parent link="link1"/><child link="link2"/><origin xyz="0 0 0.3" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1.7" upper="1.7" effort="80" velocity="2"/>
  </joint>
  <joint name="camera_pan" type="{CAMERA}">
    <parent link="link1"/><child link="camera_link"/><origin xyz="0.2 0 0.05"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="2" velocity="1"/>
  </joint>
  <joint name="joint3" type="revolute">
    <parent link="link2"/><child link="link3"/><origin xyz="0.4 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.8" upper="2.8" effort="40" velocity="2.5"/>
  </joint>
  <joint name="flange_joint" type="fixed"><parent link="link3"/><child link="flange"/><origin xyz="0.2 0 0"/></joint>
  <joint name="tcp_joint" type="fixed"><parent link="flange"/><child link="tcp"/><origin xyz="0.1 0 0"/></joint>
  <joint name="finger_joint1" type="{FINGER}">
    <parent link="flange"/><child link="finger_left"/><origin xyz="0.05 0 0"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.2"/>
  </joint>
  <joint name="finger_joint2" type="{MIMIC}">
    <parent link="flange"/><child link="finger_right"/><origin xyz="0.05 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.2"/>
    {MIMIC_TAG}
  </joint>
</robot>
"#;

fn arm(finger: &str, mimic: &str, camera: &str) -> String {
    let tag = if mimic == "fixed" {
        ""
    } else {
        r#"<mimic joint="finger_joint1"/>"#
    };
    ARM.replace("{FINGER}", finger)
        .replace("{MIMIC}", mimic)
        .replace("{CAMERA}", camera)
        .replace("{MIMIC_TAG}", tag)
}

fn load(text: &str, options: &UrdfOptions) -> Model {
    Model::from_urdf_str_with(text, "gripper_arm.urdf", options)
        .unwrap_or_else(|e| panic!("refused: {e}"))
}

/// Largest difference of RNEA and CRBA of two models at a few states.
fn max_difference(a: &Model, b: &Model) -> f64 {
    assert_eq!(a.nq(), b.nq());
    let (mut da, mut db) = (Data::new(a), Data::new(b));
    let mut worst: f64 = 0.0;
    for k in 0..5 {
        let x = k as f64;
        let q = [0.3 * x - 0.5, 0.7 - 0.2 * x, 0.1 * x];
        let v = [0.4, -0.3 * x, 0.2];
        let acc = [-0.5, 0.1 * x, 0.8];
        let ta = rnea(a, &mut da, &q, &v, &acc).unwrap().clone();
        let tb = rnea(b, &mut db, &q, &v, &acc).unwrap().clone();
        worst = worst.max((ta - tb).amax());
        let ma = crba(a, &mut da, &q).unwrap().clone();
        let mb = crba(b, &mut db, &q).unwrap().clone();
        worst = worst.max((ma - mb).amax());
    }
    worst
}

#[test]
fn massless_links_point_masses_and_the_default_tip() {
    let text = arm("prismatic", "prismatic", "revolute");
    let model = load(&text, &UrdfOptions::default());
    // The hand: past the gripper's fingers (set aside) and the camera branch (shallower),
    // at the end of the fixed joints on joint3's body.
    assert_eq!(model.frames[model.tip_frame].name, "tcp");
    let names: Vec<&str> = model.joint_names().collect();
    assert_eq!(names, ["joint1", "joint2", "joint3"]);
    // `<mass value="0"/>` with a zero inertia is massless, a point mass is a body: no warning.
    assert!(model.warnings().is_empty(), "{:?}", model.warnings());
}

#[test]
fn locked_branches_keep_their_mass_as_if_their_joints_were_fixed() {
    let text = arm("prismatic", "prismatic", "revolute");
    let model = load(&text, &UrdfOptions::default());
    let locked: Vec<&str> = model
        .locked_branches()
        .iter()
        .map(|b| b.joint.as_str())
        .collect();
    assert_eq!(locked.len(), 3, "{locked:?}");
    for j in ["camera_pan", "finger_joint1", "finger_joint2"] {
        assert!(locked.contains(&j), "{j} not listed in {locked:?}");
    }
    let mass: f64 = model.locked_branches().iter().map(|b| b.mass).sum();
    assert!((mass - 0.6).abs() < 1e-12, "locked mass {mass}");
    // The same arm with those joints written as fixed joints.
    let fixed = load(&arm("fixed", "fixed", "fixed"), &UrdfOptions::default());
    assert!(fixed.locked_branches().is_empty());
    let d = max_difference(&model, &fixed);
    assert!(d < 1e-12, "locked branches differ from fixed joints by {d}");
}

#[test]
fn a_lock_position_moves_the_branch_as_a_fixed_joint_there_would() {
    let text = arm("prismatic", "prismatic", "revolute");
    let options = UrdfOptions {
        lock: vec![("camera_pan".into(), 0.6)],
        ..Default::default()
    };
    let locked = load(&text, &options);
    // Independent: the pan joint fixed, its origin rotated by 0.6 rad about z.
    let rotated = arm("prismatic", "prismatic", "fixed").replace(
        r#"<origin xyz="0.2 0 0.05"/><axis xyz="0 0 1"/>"#,
        r#"<origin xyz="0.2 0 0.05" rpy="0 0 0.6"/><axis xyz="0 0 1"/>"#,
    );
    let reference = load(&rotated, &UrdfOptions::default());
    let d = max_difference(&locked, &reference);
    assert!(d < 1e-12, "lock at 0.6 differs by {d}");
    // ... and differs from the lock at 0, so the test can fail.
    let at_zero = load(&text, &UrdfOptions::default());
    assert!(max_difference(&locked, &at_zero) > 1e-6);
}

#[test]
fn dropped_branches_are_left_out_mass_and_all() {
    let text = arm("prismatic", "prismatic", "revolute");
    let options = UrdfOptions {
        drop: vec!["camera_pan".into()],
        ..Default::default()
    };
    let dropped = load(&text, &options);
    assert_eq!(dropped.dropped_branches().len(), 1);
    assert!((dropped.dropped_branches()[0].mass - 0.4).abs() < 1e-12);
    let start = text.find(r#"<joint name="camera_pan""#).unwrap();
    let end = start + text[start..].find("</joint>").unwrap() + "</joint>".len();
    let without = text[..start].to_string() + &text[end..];
    let start = without.find(r#"<link name="camera_link">"#).unwrap();
    let end = start + without[start..].find("</link>").unwrap() + "</link>".len();
    let without = without[..start].to_string() + &without[end..];
    let reference = load(&without, &UrdfOptions::default());
    let d = max_difference(&dropped, &reference);
    assert!(d < 1e-12, "dropped branch differs by {d}");
}

#[test]
fn unknown_names_in_lock_and_drop_are_errors_naming_them() {
    let text = arm("prismatic", "prismatic", "revolute");
    for options in [
        UrdfOptions {
            lock: vec![("camera_tilt".into(), 0.1)],
            ..Default::default()
        },
        UrdfOptions {
            drop: vec!["camera_tilt".into()],
            ..Default::default()
        },
    ] {
        let err = Model::from_urdf_str_with(&text, "gripper_arm.urdf", &options)
            .unwrap_err()
            .to_string();
        assert!(err.contains("camera_tilt"), "{err}");
    }
}

#[test]
fn locking_a_joint_of_the_chain_says_how_to_hold_it() {
    let panda = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/franka_panda.urdf"),
    )
    .unwrap();
    let options = UrdfOptions {
        lock: vec![("panda_joint7".into(), 0.5)],
        ..Default::default()
    };
    let err = Model::from_urdf_str_with(&panda, "franka_panda.urdf", &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("joint 'panda_joint7' is on the chain")
            && err.contains("--tip panda_link6, or start it after, --base panda_link7"),
        "{err}"
    );
}

#[test]
fn a_mimic_joint_on_the_chain_is_an_error_naming_it() {
    let text = arm("prismatic", "prismatic", "revolute");
    let options = UrdfOptions {
        tip: Some("finger_right".into()),
        ..Default::default()
    };
    let err = Model::from_urdf_str_with(&text, "gripper_arm.urdf", &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("finger_joint2") && err.contains("mimic"),
        "{err}"
    );
}

#[test]
fn a_negative_mass_off_the_chain_does_not_stop_the_arm() {
    // A broken body on a dropped branch is not validated.
    let text = arm("prismatic", "prismatic", "revolute")
        .replace(r#"<mass value="0.4"/>"#, r#"<mass value="-0.4"/>"#);
    let options = UrdfOptions {
        drop: vec!["camera_pan".into()],
        ..Default::default()
    };
    load(&text, &options);
    // Locked (carried), the same body is an error naming the link.
    let err = Model::from_urdf_str_with(&text, "gripper_arm.urdf", &UrdfOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("camera_link"), "{err}");
}
