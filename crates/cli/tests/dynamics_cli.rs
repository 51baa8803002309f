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
