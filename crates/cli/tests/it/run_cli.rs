//! `admittance run` on bad scenario files: one line naming the file, the line and the key,
//! with a hint; exit code 3; no output folder, complete-looking or not.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A small valid scenario: PD on Baxter for 0.2 s, with an admittance model.
fn scenario() -> String {
    let urdf = root()
        .join("models/baxter_left_arm.urdf")
        .canonicalize()
        .unwrap();
    format!(
        r#"name = "tiny"
description = "a short run for tests"
duration = 0.2
evaluation_start = 0.0

[arm]
urdf = "{}"
tip = "left_hand"

[trajectory]
offset = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5]

[[trajectory.sines]]
joint = "left_s0"
amplitude = 0.2
period = 2.0

[plant]
integrator = "semi_implicit_euler"
sensors = {{ filter_cutoff_hz = 40.0 }}

[controller]
kind = "pd"

[controller.pd]
# Per joint (the wrist's inertia is small: with a
# uniform kd = 10, or kd = 0.2 on w2 without friction, the loop through the 40 Hz velocity
# filter is unstable, and the run reports it as diverged).
kp = [240.0, 360.0, 180.0, 120.0, 24.0, 24.0, 2.4]
kd = [20.0, 30.0, 15.0, 10.0, 1.0, 1.0, 0.05]
gravity_compensation = true

[controller.neural]
k2 = 6.0

[admittance]
damping = 3.0
stiffness = 5.0
# Inside every joint's limits (a wider interval is refused: q_r could leave them).
saturation = {{ rho = 0.95, centre = [0.0, -0.55, 0.0, 1.284, 0.0, 0.262, 0.0], half_range = [1.5, 1.5, 1.5, 1.3, 1.5, 1.5, 1.5] }}
"#,
        urdf.display()
    )
}

fn run(dir: &Path, text: &str) -> (i32, String, String) {
    let file = dir.join("s.toml");
    std::fs::write(&file, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args([
            "run",
            file.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// A fresh folder under the system's temporary directory, removed with everything in it
/// when the returned guard drops (also when the test fails).
fn tempdir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("admittance-run-cli-{tag}-"))
        .tempdir()
        .unwrap()
}

#[test]
fn a_valid_scenario_writes_a_complete_folder() {
    let tmp = tempdir("ok");
    let dir = tmp.path();
    let (code, _, stderr) = run(dir, &scenario());
    assert_eq!(code, 0, "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["scenario"], "tiny");
    let base = &summary["variants"]["base"];
    assert_eq!(base["tracking_rmse"].as_array().unwrap().len(), 7);
    assert_eq!(base["torque_limit_violations"], 0);
    let csv = std::fs::read_to_string(dir.join("out/base.csv")).unwrap();
    assert!(csv.lines().next().unwrap().starts_with("t,q_d.left_s0"));
    assert!(csv.lines().count() > 10);
    assert!(dir.join("out/report.md").exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(
        leftovers.is_empty(),
        "temporary folders left: {leftovers:?}"
    );
}

#[test]
fn bad_scenarios_name_file_line_and_key_with_a_hint() {
    let good = scenario();
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown key",
            good.replace(
                "gravity_compensation = true",
                "gravity_compensation = true\nki = 1.0",
            ),
            "controller.pd",
        ),
        (
            "wrong type",
            good.replace("duration = 0.2", "duration = \"long\""),
            "duration",
        ),
        (
            "negative gain",
            good.replace("kd = [20.0", "kd = [-20.0"),
            "controller.pd.kd",
        ),
        (
            "rho outside (0, 1)",
            good.replace("rho = 0.95", "rho = 1.5"),
            "admittance.saturation",
        ),
        (
            "unknown joint",
            good.replace("joint = \"left_s0\"", "joint = \"left_s9\""),
            "trajectory.sines.0.joint",
        ),
        (
            "zero period",
            good.replace("period = 2.0", "period = 0.0"),
            "trajectory.sines.0.period",
        ),
        (
            "offset length",
            good.replace("-0.67, 1.03, -0.5]", "-0.67]"),
            "trajectory.offset",
        ),
        (
            "pose outside the arm's limits",
            good.replace("1.94, -0.67", "4.0, -0.67"),
            "trajectory.offset",
        ),
        (
            "faster than the velocity limit",
            good.replace("period = 2.0", "period = 0.5"),
            "trajectory.sines.0.amplitude",
        ),
        ("bad TOML", good.replace("[plant]", "[plant"), ""),
    ];
    for (what, text, key) in cases {
        let tmp = tempdir(&what.replace(' ', "_").replace(['(', ')', ','], ""));
        let dir = tmp.path();
        let (code, stdout, stderr) = run(dir, &text);
        assert_eq!(code, 3, "{what}: exit {code}, stderr {stderr}");
        assert!(stdout.is_empty(), "{what}: {stdout}");
        let line = stderr.trim_end();
        assert_eq!(line.lines().count(), 1, "{what}: {stderr}");
        assert!(line.contains("s.toml:"), "{what}: no file:line in {line}");
        let after = line.split("s.toml:").nth(1).unwrap();
        assert!(
            after.chars().next().is_some_and(|c| c.is_ascii_digit()),
            "{what}: no line number in {line}"
        );
        assert!(line.contains(key), "{what}: key {key} missing in {line}");
        assert!(line.contains("hint:"), "{what}: no hint in {line}");
        assert!(
            !dir.join("out").exists(),
            "{what}: an output folder was left"
        );
        let leftovers = std::fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
            .count();
        assert_eq!(leftovers, 0, "{what}: temporary folder left");
    }
}
