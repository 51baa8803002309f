//! A chain whose base link is not the URDF's root: gravity is the root's -z turned into the
//! base's axes by the joints above it (fixed ones, and moving ones at their lock position).
//! Checked against the same arm loaded from the root, where those joints are part of the
//! chain (fixed ones folded into the first placement, a moving one at the same angle).

use admittance_dynamics::{gravity_torque, Data, Model, UrdfOptions};

/// `world` -> `tilt` (revolute about x) -> `hanger` -> fixed, upside down (roll pi) ->
/// `mount` -> `shoulder` (revolute about y) -> `upper` -> `elbow` (revolute about z) -> `lower`.
const ARM: &str = r#"<?xml version="1.0"?>
<robot name="hung_arm">
  <link name="world"/>
  <link name="hanger">
    <inertial><mass value="1.0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="mount"/>
  <link name="upper">
    <inertial><origin xyz="0.3 0.02 0.1"/><mass value="2.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
  </link>
  <link name="lower">
    <inertial><origin xyz="0.2 0 0.05"/><mass value="1.0"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.002"/></inertial>
  </link>
  <joint name="tilt" type="revolute">
    <parent link="world"/><child link="hanger"/><origin xyz="0 0 2.0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="100" velocity="1"/>
  </joint>
  <joint name="hang" type="fixed">
    <parent link="hanger"/><child link="mount"/><origin xyz="0.1 0 0" rpy="3.141592653589793 0 0.4"/>
  </joint>
  <joint name="shoulder" type="revolute">
    <parent link="mount"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="50" velocity="2"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="20" velocity="2"/>
  </joint>
</robot>
"#;

fn load(base: &str, lock: &[(&str, f64)]) -> Model {
    let options = UrdfOptions {
        base: Some(base.into()),
        tip: Some("lower".into()),
        lock: lock.iter().map(|(j, v)| (j.to_string(), *v)).collect(),
        ..UrdfOptions::default()
    };
    Model::from_urdf_str_with(ARM, "hung_arm.urdf", &options).unwrap()
}

fn gravity(model: &Model, q: &[f64]) -> Vec<f64> {
    let mut data = Data::new(model);
    gravity_torque(model, &mut data, q)
        .unwrap()
        .as_slice()
        .to_vec()
}

#[test]
fn gravity_follows_the_mount_of_a_base_below_the_root() {
    for tilt in [0.0, 0.7, -1.9] {
        // From the root: tilt is the chain's first joint, held at `tilt`.
        let whole = load("world", &[]);
        // From the hung mount: tilt above the base, locked at the same angle.
        let hung = load("mount", &[("tilt", tilt)]);
        assert_eq!(hung.nq(), 2);
        assert!((hung.gravity.norm() - 9.81).abs() < 1e-12);
        for q in [[0.0, 0.0], [0.4, -1.1], [-2.0, 2.5]] {
            let reference = gravity(&whole, &[tilt, q[0], q[1]]);
            let ours = gravity(&hung, &q);
            for i in 0..2 {
                assert!(
                    (ours[i] - reference[i + 1]).abs() < 1e-12,
                    "tilt {tilt}, q {q:?}, joint {i}: {} against {}",
                    ours[i],
                    reference[i + 1]
                );
            }
        }
    }
}

#[test]
fn an_upright_base_keeps_the_roots_gravity_exactly() {
    // The root itself, and a link reached through a turn about the vertical only.
    assert_eq!(load("world", &[]).gravity.as_slice(), &[0.0, 0.0, -9.81]);
    let text = ARM.replace("rpy=\"3.141592653589793 0 0.4\"", "rpy=\"0 0 0.4\"");
    let options = UrdfOptions {
        base: Some("mount".into()),
        tip: Some("lower".into()),
        ..UrdfOptions::default()
    };
    let m = Model::from_urdf_str_with(&text, "upright.urdf", &options).unwrap();
    assert_eq!(m.gravity.as_slice(), &[0.0, 0.0, -9.81]);
    assert!(m.gravity.iter().all(|g| g.is_sign_positive() || *g != 0.0));
}
