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

/// An identification file records the mount it was fitted on (the locks, the gravity):
/// loading it from the file alone rebuilds the same model, and a model whose base is
/// turned another way is refused, naming the locks to use.
#[test]
fn an_identification_file_keeps_its_mount() {
    use admittance_dynamics::Identification;
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("hung_arm.urdf");
    std::fs::write(&urdf, ARM).unwrap();
    let load_file = |lock: &[(&str, f64)]| {
        let options = UrdfOptions {
            base: Some("mount".into()),
            tip: Some("lower".into()),
            lock: lock.iter().map(|(j, v)| (j.to_string(), *v)).collect(),
            ..UrdfOptions::default()
        };
        Model::from_urdf_file_with(&urdf, &options).unwrap()
    };
    let tilted = load_file(&[("tilt", 0.7)]);
    let path = dir.path().join("hung.ident.json");
    Identification::from_model(tilted.clone())
        .save(&path, &tilted, Default::default())
        .unwrap();
    let (_, again) = Identification::load_with_urdf(&path).unwrap();
    assert_eq!(again.gravity, tilted.gravity);
    assert_eq!(again.lock_options(), &[("tilt".to_string(), 0.7)]);
    // The same arm (same fingerprint) under another tilt: refused, with the lock to give.
    let upright = load_file(&[]);
    assert_eq!(upright.fingerprint(), tilted.fingerprint());
    let e = Identification::load(&path, &upright)
        .unwrap_err()
        .to_string();
    assert!(e.contains("gravity") && e.contains("tilt=0.7"), "{e}");
    assert!(Identification::load(&path, &tilted).is_ok());
    // A version 1 file (no gravity, no locks recorded) was fitted with (0, 0, -9.81) in the
    // base's axes: refused for the hung arm, taken for the same chain from the root.
    let old = version_1(&path, dir.path().join("old.ident.json"));
    let e = Identification::load(&old, &tilted).unwrap_err().to_string();
    assert!(e.contains("predates"), "{e}");
    let from_root = Model::from_urdf_file_with(
        &urdf,
        &UrdfOptions {
            tip: Some("lower".into()),
            ..UrdfOptions::default()
        },
    )
    .unwrap();
    let root_path = dir.path().join("root.ident.json");
    Identification::from_model(from_root.clone())
        .save(&root_path, &from_root, Default::default())
        .unwrap();
    let old_root = version_1(&root_path, dir.path().join("old_root.ident.json"));
    assert!(Identification::load(&old_root, &from_root).is_ok());
}

/// The identification file at `path` rewritten as version 1 wrote it (no `gravity` or
/// `lock`), checksum included, at `to`.
fn version_1(path: &std::path::Path, to: std::path::PathBuf) -> std::path::PathBuf {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let payload = v["payload"].as_object_mut().unwrap();
    payload.remove("gravity");
    payload.remove("lock");
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in v["payload"].to_string().bytes() {
        h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    v["checksum"] = format!("{h:016x}").into();
    v["format_version"] = 1.into();
    std::fs::write(&to, v.to_string()).unwrap();
    to
}

/// A mimic joint above the base follows its reference's lock position, as a locked
/// branch's mimic joints do.
#[test]
fn a_mimic_joint_above_the_base_follows_its_reference() {
    let text = ARM.replace(
        r#"<joint name="hang" type="fixed">
    <parent link="hanger"/><child link="mount"/>"#,
        r#"<link name="swivel"/>
  <joint name="follower" type="revolute">
    <parent link="hanger"/><child link="swivel"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="100" velocity="1"/>
    <mimic joint="tilt" multiplier="2" offset="0.1"/>
  </joint>
  <joint name="hang" type="fixed">
    <parent link="swivel"/><child link="mount"/>"#,
    );
    assert!(text.contains("follower"));
    let gravity = |lock: &[(&str, f64)]| {
        let options = UrdfOptions {
            base: Some("mount".into()),
            tip: Some("lower".into()),
            lock: lock.iter().map(|(j, v)| (j.to_string(), *v)).collect(),
            ..UrdfOptions::default()
        };
        Model::from_urdf_str_with(&text, "mimic.urdf", &options)
            .unwrap()
            .gravity
    };
    let followed = gravity(&[("tilt", 0.3)]);
    let explicit = gravity(&[("tilt", 0.3), ("follower", 0.7)]);
    assert!(
        (followed - explicit).norm() < 1e-15,
        "{followed} {explicit}"
    );
    let unfollowed = gravity(&[("tilt", 0.3), ("follower", 0.0)]);
    assert!((followed - unfollowed).norm() > 1.0);
}
