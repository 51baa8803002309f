//! `admittance gains` (a starting set from the arm's model that passes the gain rules, and
//! that a scenario accepts without a warning) and the exit code of a run that finishes but
//! breaks a health rule.

use std::path::PathBuf;
use std::process::Command;

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

/// The `k2 = [...]` line of the printed TOML.
fn k2(toml_text: &str) -> String {
    let table: toml::Table = toml_text.parse().expect("the output is TOML");
    let k2 = table["controller"]["neural"]["k2"].as_array().unwrap();
    let values: Vec<String> = k2
        .iter()
        .map(|v| format!("{:?}", v.as_float().unwrap()))
        .collect();
    format!("[{}]", values.join(","))
}

#[test]
fn gains_for_the_panda_and_baxter_pass_the_rules_of_their_scenarios() {
    for (urdf, tip, pose, scenario) in [
        (
            "models/franka_panda.urdf",
            "panda_hand_tcp",
            "0,-0.7854,0,-2.3562,0,1.5708,0.7854",
            "scenarios/panda_deadzone.toml",
        ),
        (
            "models/baxter_left_arm.urdf",
            "left_hand",
            "0,-1,1.19,1.94,-0.67,1.03,-0.5",
            "scenarios/deadzone.toml",
        ),
    ] {
        let (code, out, err) = admittance(&[
            "gains",
            "--urdf",
            urdf,
            "--tip",
            tip,
            &format!("--q={pose}"),
        ]);
        assert_eq!(code, 0, "{err}");
        assert!(
            out.contains("# Every value passes the gain rules."),
            "{out}\n{err}"
        );
        assert!(!err.contains("warning"), "{err}");
        // The scenario with these gains runs without a gain warning (0.2 s is enough: the
        // rules are checked when it loads; the start-up transient is not judged here).
        let k2 = k2(&out);
        let dir = tempfile::tempdir().unwrap();
        let out_dir = dir.path().join("run");
        let (code, _, err) = admittance(&[
            "run",
            scenario,
            "--out",
            out_dir.to_str().unwrap(),
            "--variant",
            "nn_compensated",
            "--set",
            "duration=0.2",
            "--set",
            "evaluation_start=0",
            "--set",
            &format!("controller.neural.k2={k2}"),
            "--set",
            "health.max_hand_error=inf",
            "--set",
            "health.max_effort_saturation=inf",
            "--quiet",
            "--no-recording",
        ]);
        assert_eq!(code, 0, "{scenario} k2 = {k2}: {err}");
        assert!(!err.contains("controller.neural.k2"), "{err}");
    }
}

#[test]
fn a_gain_under_the_bound_is_named_with_a_value_to_use() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("run");
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/panda_deadzone.toml",
        "--out",
        out_dir.to_str().unwrap(),
        "--variant",
        "nn_compensated",
        "--set",
        "duration=0.2",
        "--set",
        "evaluation_start=0",
        "--set",
        "controller.neural.k2=[3.0,25.0,15.0,15.0,1.0,1.0,0.2]",
        "--set",
        "health.max_hand_error=inf",
        "--quiet",
        "--no-recording",
    ]);
    assert_eq!(code, 0, "a warning does not fail the run: {err}");
    let line = err
        .lines()
        .find(|l| l.contains("panda_joint1"))
        .unwrap_or_else(|| panic!("{err}"));
    assert!(
        line.starts_with("admittance: warning: --set controller.neural.k2="),
        "{line}"
    );
    assert!(
        line.contains("set controller.neural.k2[0] (panda_joint1) to"),
        "{line}"
    );
}

#[test]
fn a_run_that_breaks_a_health_rule_exits_4_and_says_which() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("run");
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/deadzone.toml",
        "--out",
        out_dir.to_str().unwrap(),
        "--variant",
        "nn_compensated",
        "--set",
        "duration=2",
        "--set",
        "evaluation_start=1",
        "--set",
        "health.max_hand_error=1e-5",
        "--quiet",
        "--no-recording",
    ]);
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("admittance: failure: `nn_compensated`: the hand left its reference"),
        "{err}"
    );
    assert!(
        err.contains("[hand_error]") && err.contains("exit 4"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["health"]["status"], "failure");
    // The same run with the default bound passes.
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/deadzone.toml",
        "--out",
        out_dir.to_str().unwrap(),
        "--variant",
        "nn_compensated",
        "--set",
        "duration=2",
        "--set",
        "evaluation_start=1",
        "--quiet",
        "--no-recording",
    ]);
    assert_eq!(code, 0, "{err}");
}
