//! `admittance import` end to end on the test bags of crates/bag/tests/data: the CSV it
//! writes is read by the free-motion reader and trains; bad bags, refused outputs and bad
//! arguments give their exit codes and one clear line.

use std::path::{Path, PathBuf};
use std::process::Command;

use admittance_scenario::FreeMotionData;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bag(name: &str) -> String {
    root()
        .join("crates/bag/tests/data")
        .join(name)
        .display()
        .to_string()
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

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn import_then_read_and_train() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("franka.csv");
    let (code, out, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 0, "{err}");
    for part in [
        "profile: franka",
        "/franka_robot_state_broadcaster/measured_joint_states (sensor_msgs/msg/JointState): 1000 messages",
        "skipped messages: 0",
        "rate: 1000.000000 Hz",
        "rows: 995",
        "wrote ",
    ] {
        assert!(out.contains(part), "{part} not in\n{out}");
    }
    let data = FreeMotionData::load(&csv).unwrap();
    assert_eq!(data.dof(), 7);
    assert_eq!(data.len(), 995);
    assert_eq!(data.joints[0], "fr3_joint1");
    // The same data under the Panda URDF's joint names trains.
    let panda = dir.path().join("panda.csv");
    let text = std::fs::read_to_string(&csv)
        .unwrap()
        .replace("fr3_joint", "panda_joint");
    std::fs::write(&panda, text).unwrap();
    let model = dir.path().join("m.broad");
    let (code, out, err) = admittance(&[
        "train",
        "--data",
        s(&panda),
        "--urdf",
        "models/franka_panda.urdf",
        "--nodes",
        "20",
        "--out",
        s(&model),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("validation nrmse"), "{out}");
    // A second import over its own CSV is allowed, with a rate.
    let (code, out, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
        "--rate",
        "250",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("rate: 250.000000 Hz (--rate)"), "{out}");
}

#[test]
fn exit_codes_and_messages() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("x.csv");
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_sqlite"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("rosbags-convert --src BAG --dst OUT --dst-storage mcap"),
        "{err}"
    );
    let (code, _, err) = admittance(&[
        "import",
        &bag("ur_plain"),
        "--profile",
        "ur",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("torque_constant"), "{err}");
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "kuka",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("franka, ur, lbr"), "{err}");
    let user = dir.path().join("mine.csv");
    std::fs::write(&user, "precious\n").unwrap();
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&user),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("refusing to replace"), "{err}");
    assert_eq!(std::fs::read_to_string(&user).unwrap(), "precious\n");
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
        "--rate",
        "-3",
    ]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!csv.exists());
}
