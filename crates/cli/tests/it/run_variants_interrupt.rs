//! `admittance run` with `--variant` given more than once runs those variants, in that order,
//! each once; Ctrl-C (SIGINT) ends a run with one line on stderr and exit code 130, leaving
//! no folder at `--out` and no partial one (issue 25).

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn admittance() -> Command {
    Command::new(env!("CARGO_BIN_EXE_admittance"))
}

#[test]
fn variant_can_be_repeated() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("two");
    let scenario = root().join("scenarios/deadzone.toml");
    let output = admittance()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args([
            "--variant",
            "pd",
            "--variant",
            "nn_uncompensated",
            "--variant",
            "pd",
        ])
        .args(["--set", "duration=0.5", "--set", "evaluation_start=0.1"])
        // Half a second is the start-up transient: the hand-error rule is not the point here.
        .args(["--set", "health.max_hand_error=inf"])
        .args(["--no-recording", "--quiet"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["variant_order"],
        serde_json::json!(["pd", "nn_uncompensated"]),
        "{summary}"
    );
    let variants = summary["variants"].as_object().unwrap();
    assert_eq!(variants.len(), 2, "{summary}");
    assert!(out.join("pd.csv").is_file() && out.join("nn_uncompensated.csv").is_file());
}

#[test]
fn an_unknown_repeated_variant_is_refused_before_any_run() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bad");
    let scenario = root().join("scenarios/deadzone.toml");
    let output = admittance()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--variant", "pd", "--variant", "no_such_variant", "--quiet"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_ne!(output.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("no_such_variant"), "{stderr}");
    assert!(!out.exists());
}

#[cfg(unix)]
#[test]
fn ctrl_c_prints_one_line_and_exits_130() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("interrupted");
    let scenario = root().join("scenarios/deadzone.toml");
    let mut child = admittance()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--variant", "pd", "--set", "duration=600", "--no-recording"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    std::thread::sleep(Duration::from_millis(1500));
    let status = Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let started = Instant::now();
    let output = loop {
        if child.try_wait().unwrap().is_some() {
            break child.wait_with_output().unwrap();
        }
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "still running 10 s after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with("admittance: interrupted (Ctrl-C); ")
            && lines[0].contains(&format!(".interrupted.partial-{pid}")),
        "{stderr}"
    );
    assert!(!out.exists(), "an interrupted run left {}", out.display());
}

/// Ctrl-C while the finished run writes its folder (CSV files, figures, report): the
/// unfinished `.DIR.partial-PID` folder is removed before the process exits, and an older
/// run folder at `--out` is left as it was.
#[cfg(unix)]
#[test]
fn ctrl_c_while_writing_removes_the_partial_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("late");
    let scenario = root().join("scenarios/deadzone.toml");
    // An older run folder at --out, which must survive.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(
        out.join("summary.json"),
        r#"{"format": "admittance-run", "format_version": 1}"#,
    )
    .unwrap();
    let mut child = admittance()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--variant", "pd", "--set", "duration=25", "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let partial = tmp.path().join(format!(".late.partial-{pid}"));
    let started = Instant::now();
    while !partial.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before its partial folder was seen"
        );
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no partial folder"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let status = Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("interrupted (Ctrl-C)") && stderr.contains("was removed"),
        "{stderr}"
    );
    assert!(!partial.exists(), "{} was left", partial.display());
    let left: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["late"], "only the older run folder remains");
    assert_eq!(
        std::fs::read_to_string(out.join("summary.json")).unwrap(),
        r#"{"format": "admittance-run", "format_version": 1}"#
    );
}
