//! `[arm]` options of a scenario (issue 13): a description with a physically impossible
//! inertia runs with a warning that the run prints and summary.json lists; `strict`
//! refuses it; `lock` and `drop` name unknown joints.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Baxter with the hand's inertia broken (ixx far above iyy + izz: no rigid body has it),
/// and a short PD scenario on it.
fn setup(dir: &Path) -> String {
    let urdf = std::fs::read_to_string(root().join("models/baxter_left_arm.urdf")).unwrap();
    let broken = urdf.replace(r#"ixx="0.00017588""#, r#"ixx="0.5""#);
    assert_ne!(urdf, broken, "the fixture's inertia moved");
    std::fs::write(dir.join("arm.urdf"), broken).unwrap();
    let scenario = r#"name = "broken_inertia"
description = "a short run on an arm whose hand has an impossible inertia"
duration = 0.1
evaluation_start = 0.0

[arm]
urdf = "arm.urdf"
tip = "left_hand"

[trajectory]
offset = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5]

[plant]
sensors = { filter_cutoff_hz = 40.0 }

[controller]
kind = "pd"

[controller.pd]
kp = [240.0, 360.0, 180.0, 120.0, 24.0, 24.0, 2.4]
kd = [20.0, 30.0, 15.0, 10.0, 1.0, 1.0, 0.05]
gravity_compensation = true
"#;
    let file = dir.join("s.toml");
    std::fs::write(&file, scenario).unwrap();
    file.to_str().unwrap().to_string()
}

fn admittance(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn an_impossible_inertia_runs_with_a_warning_and_strict_refuses_it() {
    let tmp = tempfile::tempdir().unwrap();
    let s = setup(tmp.path());
    let out = tmp.path().join("run");
    let out_s = out.to_str().unwrap();
    let (code, err) = admittance(&["run", &s, "--out", out_s, "--no-recording"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning") && err.contains("left_hand") && err.contains("triangle"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let warnings = summary["warnings"]
        .as_array()
        .expect("summary lists warnings");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].as_str().unwrap().contains("left_hand"));

    let strict = tmp.path().join("strict");
    let (code, err) = admittance(&[
        "run",
        &s,
        "--out",
        strict.to_str().unwrap(),
        "--set",
        "arm.strict=true",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("arm.urdf") && err.contains("left_hand"),
        "{err}"
    );
    assert!(!strict.exists());
}

#[test]
fn lock_and_drop_name_unknown_joints() {
    let tmp = tempfile::tempdir().unwrap();
    let s = setup(tmp.path());
    for set in ["arm.lock.gripper_finger=0.02", "arm.drop=[\"head_pan\"]"] {
        let out = tmp.path().join("run");
        let (code, err) = admittance(&["run", &s, "--out", out.to_str().unwrap(), "--set", set]);
        assert_eq!(code, 3, "{set}: {err}");
        let joint = if set.contains("gripper") {
            "gripper_finger"
        } else {
            "head_pan"
        };
        assert!(
            err.contains(joint) && err.contains("arm.urdf"),
            "{set}: {err}"
        );
    }
}
