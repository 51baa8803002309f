//! The `admittance dynamics` / `admittance model` contract, checked end to end against
//! Pinocchio's numbers for Baxter (the committed fixture).

use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn admittance(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn join(v: &Value) -> String {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| format!("{:.17e}", x.as_f64().unwrap()))
        .collect::<Vec<_>>()
        .join(",")
}

fn close(ours: &Value, theirs: &Value, what: &str) {
    match (ours, theirs) {
        (Value::Array(a), Value::Array(b)) => {
            assert_eq!(a.len(), b.len(), "{what}: length");
            for (x, y) in a.iter().zip(b) {
                close(x, y, what);
            }
        }
        _ => {
            let (x, y) = (ours.as_f64().unwrap(), theirs.as_f64().unwrap());
            assert!(
                (x - y).abs() <= 1e-9 * (1.0 + y.abs()),
                "{what}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn dynamics_prints_pinocchio_numbers_for_baxter() {
    let fixture: Value = serde_json::from_str(
        &std::fs::read_to_string(
            root().join("crates/dynamics/tests/fixtures/pinocchio/baxter_left_arm.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let case = &fixture["cases"][0];
    let (q, v, a) = (join(&case["q"]), join(&case["v"]), join(&case["a"]));
    let (code, stdout, stderr) = admittance(&[
        "dynamics",
        "--urdf",
        "models/baxter_left_arm.urdf",
        "--base",
        "base",
        "--tip",
        "left_hand",
        "--q",
        &q,
        "--v",
        &v,
        "--a",
        &a,
    ]);
    assert_eq!(code, 0, "{stderr}");
    let out: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(out["joints"], fixture["joints"]);
    close(&out["tau"], &case["tau"], "tau");
    close(&out["mass_matrix"], &case["mass_matrix"], "mass_matrix");
    close(&out["gravity"], &case["gravity_torque"], "gravity");
    close(&out["coriolis"], &case["coriolis"], "coriolis");
    close(&out["position"], &case["tip_position"], "position");
    close(&out["rotation"], &case["tip_rotation"], "rotation");
    close(&out["jacobian"], &case["jacobian"], "jacobian");
}

#[test]
fn defaults_and_gravity_flag() {
    let (code, stdout, _) = admittance(&[
        "dynamics",
        "--urdf",
        "models/baxter_left_arm.urdf",
        "--q",
        "0,0,0,0,0,0,0",
        "--gravity",
        "0,0,0",
    ]);
    assert_eq!(code, 0);
    let out: Value = serde_json::from_str(&stdout).unwrap();
    // Zero gravity, zero velocity and acceleration: no torque at all.
    assert!(out["tau"]
        .as_array()
        .unwrap()
        .iter()
        .all(|t| t.as_f64().unwrap().abs() < 1e-12));
}

#[test]
fn bad_arguments_give_one_line_and_nonzero_exit() {
    for args in [
        vec![
            "dynamics",
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--q",
            "0,1",
        ],
        vec![
            "dynamics",
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--q",
            "0,0,0,x,0,0,0",
        ],
        vec![
            "dynamics",
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--q",
            "0,0,0,nan,0,0,0",
        ],
        vec![
            "dynamics",
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--q",
            "0,0,0,0,0,0,0",
            "--gravity",
            "1,2",
        ],
        vec![
            "dynamics",
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--q",
            "0,0,0,0,0,0,0",
            "--tip",
            "nowhere",
        ],
        vec!["dynamics", "--urdf", "missing.urdf", "--q", "0"],
        vec!["dynamics", "--urdf", "models/baxter_left_arm.urdf"],
        vec!["dynamics", "--bogus"],
    ] {
        let (code, stdout, stderr) = admittance(&args);
        assert_ne!(code, 0, "{args:?} succeeded");
        assert!(stdout.is_empty(), "{args:?} printed {stdout}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    }
}

#[test]
fn model_summary_lists_joints_limits_and_masses() {
    let (code, stdout, stderr) = admittance(&["model", "--urdf", "models/baxter_left_arm.urdf"]);
    assert_eq!(code, 0, "{stderr}");
    for needle in [
        "left_s0",
        "left_w2",
        "revolute",
        "50.0000",
        "15.0000",
        "total moving mass 19.71",
        "left_hand",
    ] {
        assert!(stdout.contains(needle), "missing {needle}:\n{stdout}");
    }
}

/// A base link below the root and turned against it (here hung upside down): the summary
/// says where gravity points in its axes; an upright base's summary has no such line.
#[test]
fn model_summary_states_the_gravity_of_a_turned_base() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("hung.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="hung">
  <link name="world"/>
  <link name="mount"/>
  <link name="upper">
    <inertial><origin xyz="0.3 0 0"/><mass value="2.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
  </link>
  <joint name="hang" type="fixed">
    <parent link="world"/><child link="mount"/><origin xyz="0 0 2" rpy="3.141592653589793 0 0"/>
  </joint>
  <joint name="shoulder" type="revolute">
    <parent link="mount"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="50" velocity="2"/>
  </joint>
</robot>"#,
    )
    .unwrap();
    let path = urdf.to_str().unwrap();
    let (code, stdout, stderr) = admittance(&["model", "--urdf", path, "--base", "mount"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("gravity  (0.0000, 0.0000, 9.8100) m/s^2 in mount's axes"),
        "{stdout}"
    );
    let (code, stdout, stderr) = admittance(&["model", "--urdf", path]);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stdout.contains("gravity"), "{stdout}");
}

/// Issue 14: inputs that overflow the arithmetic are an error naming them, not `null`
/// with exit 0; a missing and a non-UTF-8 URDF are bad input (exit 3).
#[test]
fn overflowing_inputs_and_unreadable_files_are_bad_input() {
    let (code, stdout, stderr) = admittance(&[
        "dynamics",
        "--urdf",
        "models/baxter_left_arm.urdf",
        "--q",
        "0,0,0,0,0,0,0",
        "--v",
        "1e200,0,0,0,0,0,0",
    ]);
    assert_eq!(code, 3, "{stdout}{stderr}");
    assert!(stdout.is_empty(), "{stdout}");
    assert!(
        stderr.contains("overflow") && stderr.contains("1e200"),
        "{stderr}"
    );

    let (code, _, stderr) = admittance(&["model", "--urdf", "missing.urdf"]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("missing.urdf"), "{stderr}");

    let dir = tempfile::tempdir().unwrap();
    let latin1 = dir.path().join("latin1.urdf");
    std::fs::write(&latin1, b"<robot name=\"caf\xe9\"/>").unwrap();
    let (code, _, stderr) = admittance(&["model", "--urdf", latin1.to_str().unwrap()]);
    assert_eq!(code, 3, "{stderr}");
    assert!(
        stderr.contains("UTF-8") && stderr.contains("latin1.urdf"),
        "{stderr}"
    );
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
}

/// A small arm with a two-finger gripper, a camera branch and a questionable inertia.
const GRIPPER_ARM: &str = r#"<robot name="gripper_arm">
  <link name="base"/>
  <link name="link1"><inertial><origin xyz="0 0 0.1"/><mass value="2"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/></inertial></link>
  <link name="link2"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.5"/></inertial></link>
  <link name="hand"><inertial><mass value="0"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="finger"><inertial><mass value="0.05"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="camera"><inertial><mass value="0.3"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="40" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="20" velocity="2"/></joint>
  <joint name="hand_joint" type="fixed"><parent link="link2"/><child link="hand"/>
    <origin xyz="0.3 0 0"/></joint>
  <joint name="finger_joint" type="prismatic"><parent link="hand"/><child link="finger"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="0.04" effort="10" velocity="0.1"/></joint>
  <joint name="cam_pan" type="revolute"><parent link="base"/><child link="camera"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"#;

/// Issue 13: a description with a gripper, a branch and an impossible inertia loads; the
/// model lists the locked branches with their mass and the warning, `--strict` refuses
/// it, `--drop` and `--lock` act, and `dynamics` prints the warning on stderr.
#[test]
fn model_lists_branches_and_warnings_and_the_options_act() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("gripper_arm.urdf");
    std::fs::write(&urdf, GRIPPER_ARM).unwrap();
    let urdf = urdf.to_str().unwrap();
    let (code, stdout, stderr) = admittance(&["model", "--urdf", urdf]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("base -> hand (2 moving joints)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("locked branch at finger_joint: 0.0500 kg"),
        "{stdout}"
    );
    assert!(
        stdout.contains("locked branch at cam_pan: 0.3000 kg"),
        "{stdout}"
    );
    assert!(
        stdout.contains("1 warning(s)") && stdout.contains("link2"),
        "{stdout}"
    );
    assert!(
        stderr.contains("warning") && stderr.contains("link2"),
        "{stderr}"
    );

    let (code, _, stderr) = admittance(&["model", "--urdf", urdf, "--strict"]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("link2"), "{stderr}");

    let (code, stdout, stderr) = admittance(&["model", "--urdf", urdf, "--drop", "cam_pan"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("dropped branch at cam_pan: 0.3000 kg"),
        "{stdout}"
    );
    assert!(!stdout.contains("locked branch at cam_pan"), "{stdout}");

    let (code, _, stderr) = admittance(&["model", "--urdf", urdf, "--lock", "nope=0.1"]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("nope"), "{stderr}");

    // The finger's lock position moves its mass: the gravity torque of j2 changes.
    let gravity = |extra: &[&str]| -> f64 {
        let mut args = vec!["dynamics", "--urdf", urdf, "--q", "0,0.5"];
        args.extend_from_slice(extra);
        let (code, stdout, stderr) = admittance(&args);
        assert_eq!(code, 0, "{stderr}");
        assert!(stderr.contains("warning"), "{stderr}");
        let v: Value = serde_json::from_str(&stdout).unwrap();
        v["gravity"][1].as_f64().unwrap()
    };
    let held_open = gravity(&["--lock", "finger_joint=0.04"]);
    let closed = gravity(&[]);
    assert!((held_open - closed).abs() > 1e-9, "{held_open} {closed}");
}
