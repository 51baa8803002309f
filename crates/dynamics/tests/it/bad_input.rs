//! Malformed and hostile URDFs: each gives an error that names the file and the element
//! (and the line where it is known); none panics.

use crate::common;
use admittance_dynamics::{DynamicsError, Model};
use proptest::prelude::*;

const GOOD: &str = r#"<?xml version="1.0"?>
<robot name="two">
  <link name="base"/>
  <link name="upper">
    <inertial>
      <origin xyz="0 0 0.2" rpy="0 0 0"/>
      <mass value="2.0"/>
      <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.02" iyz="0" izz="0.01"/>
    </inertial>
  </link>
  <link name="lower">
    <inertial>
      <origin xyz="0 0 0.15"/>
      <mass value="1.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.005"/>
    </inertial>
  </link>
  <link name="hand"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="upper"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="50" velocity="2"/>
    <dynamics damping="0.1" friction="0.2"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/>
    <child link="lower"/>
    <origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="30" velocity="2"/>
  </joint>
  <joint name="hand" type="fixed">
    <parent link="lower"/>
    <child link="hand"/>
    <origin xyz="0 0 0.3"/>
  </joint>
</robot>
"#;

fn load(text: &str) -> Result<Model, DynamicsError> {
    Model::from_urdf_str(text, "arm.urdf", None, None)
}

/// Loads a mutated copy of GOOD and checks the error mentions every fragment.
fn expect_error(text: &str, fragments: &[&str]) {
    let err = match load(text) {
        Ok(_) => panic!("accepted a bad URDF; expected an error mentioning {fragments:?}"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.starts_with("arm.urdf"),
        "error does not name the file: {err}"
    );
    for f in fragments {
        assert!(err.contains(f), "error {err:?} does not mention {f:?}");
    }
    assert!(!err.contains('\n'), "error should be one line: {err:?}");
}

#[test]
fn the_good_arm_loads_with_limits_and_dynamics() {
    let model = load(GOOD).unwrap();
    assert_eq!(model.nq(), 2);
    assert_eq!(model.tip().name, "hand");
    assert_eq!(model.joints[0].limits.effort, 50.0);
    assert_eq!(model.joints[0].damping, 0.1);
    assert_eq!(model.joints[0].friction, 0.2);
    assert!((model.total_moving_mass() - 3.0).abs() < 1e-12);
}

#[test]
fn not_xml() {
    expect_error("this is not xml <robot", &["XML", "not well-formed"]);
    expect_error("", &["XML"]);
}

#[test]
fn wrong_root_element() {
    expect_error("<sdf><link name='a'/></sdf>", &["<sdf>", "<robot>"]);
}

#[test]
fn missing_parent_or_child_link() {
    expect_error(
        &GOOD.replace(r#"<parent link="upper"/>"#, r#"<parent link="nowhere"/>"#),
        &["joint 'elbow'", "<parent>", "'nowhere'"],
    );
    expect_error(
        &GOOD.replace(r#"<child link="lower"/>"#, ""),
        &["joint 'elbow'", "missing <child>"],
    );
}

#[test]
fn loops_and_two_parents() {
    // lower -> upper closes a loop upper -> lower -> upper.
    let looped = GOOD.replace(
        "</robot>",
        r#"<joint name="back" type="fixed"><parent link="hand"/><child link="base"/></joint></robot>"#,
    );
    expect_error(&looped, &["loop"]);
    let two_parents = GOOD.replace(
        "</robot>",
        r#"<joint name="second" type="fixed"><parent link="base"/><child link="lower"/></joint></robot>"#,
    );
    expect_error(
        &two_parents,
        &["joint 'second'", "already the child of joint 'elbow'"],
    );
}

#[test]
fn duplicate_names() {
    expect_error(
        &GOOD.replace(
            r#"<link name="hand"/>"#,
            r#"<link name="hand"/><link name="upper"/>"#,
        ),
        &["link 'upper'", "duplicate link name"],
    );
    expect_error(
        &GOOD.replace(r#"name="elbow""#, r#"name="shoulder""#),
        &["joint 'shoulder'", "duplicate joint name"],
    );
}

#[test]
fn unsupported_and_unknown_joint_types() {
    expect_error(
        &GOOD.replace(
            r#"name="elbow" type="revolute""#,
            r#"name="elbow" type="spherical""#,
        ),
        &["joint 'elbow'", "unknown joint type 'spherical'"],
    );
    expect_error(
        &GOOD.replace(
            r#"name="elbow" type="revolute""#,
            r#"name="elbow" type="floating""#,
        ),
        &["joint 'elbow'", "'floating' on the chain is not supported"],
    );
    expect_error(
        &GOOD.replace(
            r#"name="elbow" type="revolute""#,
            r#"name="elbow" type="planar""#,
        ),
        &["joint 'elbow'", "'planar'"],
    );
    expect_error(
        &GOOD.replace(
            r#"<axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="30""#,
            r#"<axis xyz="0 1 0"/><mimic joint="shoulder"/>
    <limit lower="-2" upper="2" effort="30""#,
        ),
        &["joint 'elbow' <mimic>", "a mimic joint", "is on the chain"],
    );
}

#[test]
fn bad_masses() {
    // A zero mass with a non-zero inertia is no rigid body: a warning, an error when strict.
    let zero = GOOD.replace(r#"<mass value="1.0"/>"#, r#"<mass value="0"/>"#);
    expect_warning(&zero, &["link 'lower'"]);
    // A negative mass on the chain is always an error.
    expect_error(
        &GOOD.replace(r#"<mass value="1.0"/>"#, r#"<mass value="-3"/>"#),
        &["link 'lower'", "negative"],
    );
    expect_error(
        &GOOD.replace(r#"<mass value="1.0"/>"#, r#"<mass/>"#),
        &["link 'lower'", "missing attribute 'value'"],
    );
}

/// Loads a mutated copy of GOOD: it loads with a warning naming every fragment, and strict
/// loading refuses it with an error naming them too.
fn expect_warning(text: &str, fragments: &[&str]) {
    let model = load(text).unwrap_or_else(|e| panic!("refused with default options: {e}"));
    let warnings: Vec<String> = model.warnings().iter().map(|w| w.to_string()).collect();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    for f in fragments {
        assert!(
            warnings[0].contains(f),
            "warning {warnings:?} does not mention {f:?}"
        );
    }
    assert!(warnings[0].starts_with("arm.urdf:"), "{warnings:?}");
    let options = admittance_dynamics::UrdfOptions {
        strict: true,
        ..Default::default()
    };
    let err = Model::from_urdf_str_with(text, "arm.urdf", &options)
        .expect_err("strict loading accepted it")
        .to_string();
    for f in fragments {
        assert!(
            err.contains(f),
            "strict error {err:?} does not mention {f:?}"
        );
    }
}

#[test]
fn bad_inertia_tensors() {
    let not_pd = GOOD.replace(
        r#"ixx="0.01" ixy="0" ixz="0" iyy="0.01""#,
        r#"ixx="-0.01" ixy="0" ixz="0" iyy="0.01""#,
    );
    // Vendor files carry such inertias; Pinocchio and MuJoCo load them: so do we, with a
    // warning (an error when strict).
    expect_warning(&not_pd, &["link 'lower' <inertial> <inertia>"]);
    let triangle = GOOD.replace(r#"izz="0.005""#, r#"izz="0.5""#);
    expect_warning(
        &triangle,
        &["link 'lower' <inertial> <inertia>", "triangle inequality"],
    );
}

#[test]
fn non_finite_and_malformed_numbers() {
    expect_error(
        &GOOD.replace(r#"<origin xyz="0 0 0.4"/>"#, r#"<origin xyz="0 NaN 0.4"/>"#),
        &["joint 'elbow' <origin>", "'xyz'", "not a finite number"],
    );
    expect_error(
        &GOOD.replace(r#"<mass value="2.0"/>"#, r#"<mass value="inf"/>"#),
        &["link 'upper'", "not a finite number"],
    );
    expect_error(
        &GOOD.replace(r#"effort="30""#, r#"effort="lots""#),
        &["joint 'elbow' <limit>", "'effort'", "not a number"],
    );
    expect_error(
        &GOOD.replace(r#"<origin xyz="0 0 0.4"/>"#, r#"<origin xyz="0 0.4"/>"#),
        &["joint 'elbow' <origin>", "expected 3 numbers"],
    );
}

#[test]
fn limits_and_axes() {
    expect_error(
        &GOOD.replace(
            r#"<limit lower="-2" upper="2" effort="30" velocity="2"/>"#,
            "",
        ),
        &["joint 'elbow'", "needs <limit"],
    );
    expect_error(
        &GOOD.replace(
            r#"lower="-2" upper="2" effort="30""#,
            r#"lower="2" upper="-2" effort="30""#,
        ),
        &["joint 'elbow' <limit>", "above upper"],
    );
    expect_error(
        &GOOD.replace(
            r#"<origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/>"#,
            r#"<origin xyz="0 0 0.4"/>
    <axis xyz="0 0 0"/>"#,
        ),
        &["joint 'elbow' <axis>", "zero length"],
    );
}

#[test]
fn tip_and_base_errors() {
    let err = Model::from_urdf_str(GOOD, "arm.urdf", None, Some("gripper"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("tip link 'gripper'") && err.contains("no link of that name"),
        "{err}"
    );
    let err = Model::from_urdf_str(GOOD, "arm.urdf", Some("lower"), Some("upper"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("not below the base link 'lower'"), "{err}");
    let branched = GOOD.replace(
        "</robot>",
        r#"<link name="camera"/><joint name="cam" type="fixed"><parent link="upper"/><child link="camera"/></joint></robot>"#,
    );
    // The default tip is the hand: the deepest moving joint's body, not a camera on the
    // upper arm.
    let model = load(&branched).unwrap();
    assert_eq!(model.frames[model.tip_frame].name, "hand");
    // Naming the tip gives the same, and the camera's frame stays addressable.
    let model = Model::from_urdf_str(&branched, "arm.urdf", None, Some("hand")).unwrap();
    assert!(model.frame_index("camera").is_some());
}

#[test]
fn a_massless_last_body_is_rejected() {
    let text = GOOD.replace(
        r#"<inertial>
      <origin xyz="0 0 0.15"/>
      <mass value="1.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.005"/>
    </inertial>"#,
        "",
    );
    expect_error(&text, &["joint 'elbow'", "moves no mass"]);
}

#[test]
fn missing_file_names_the_path() {
    let err = Model::from_urdf_file("/nonexistent/arm.urdf".as_ref(), None, None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("/nonexistent/arm.urdf") && err.contains("cannot read"),
        "{err}"
    );
}

#[test]
fn the_baxter_name_clash_is_handled() {
    // A fixed joint and a link are both called `left_hand` in the published description.
    let model = common::baxter();
    assert_eq!(model.tip().name, "left_hand");
    assert_eq!(
        model.joint_names().collect::<Vec<_>>(),
        ["left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2"]
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Truncations and byte substitutions of a valid URDF load or fail cleanly.
    #[test]
    fn mutated_urdfs_never_panic(cut in 0usize..GOOD.len(), at in 0usize..GOOD.len(), byte in 0u8..128) {
        let _ = load(&GOOD[..cut]);
        let mut bytes = GOOD.as_bytes().to_vec();
        bytes[at] = byte;
        if let Ok(text) = String::from_utf8(bytes) {
            if let Err(e) = load(&text) {
                prop_assert!(e.to_string().starts_with("arm.urdf"));
            }
        }
    }
}
