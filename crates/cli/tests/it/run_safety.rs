//! `admittance run` never loses what it did not write, refuses work it cannot finish before
//! it starts, and never reports success for a run that failed (issue 14).

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A short valid scenario (PD on Baxter), with `extra` appended to its `[plant]` table.
fn scenario(extra_plant: &str) -> String {
    let urdf = root()
        .join("models/baxter_left_arm.urdf")
        .canonicalize()
        .unwrap();
    format!(
        r#"name = "tiny"
description = "a short run for tests"
duration = 0.1
evaluation_start = 0.0

[arm]
urdf = "{}"
tip = "left_hand"

[trajectory]
offset = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5]

[plant]

sensors = {{ filter_cutoff_hz = 40.0 }}
{extra_plant}

[controller]
kind = "pd"

[controller.pd]
kp = [240.0, 360.0, 180.0, 120.0, 24.0, 24.0, 2.4]
kd = [20.0, 30.0, 15.0, 10.0, 1.0, 1.0, 0.05]
gravity_compensation = true
"#,
        urdf.display()
    )
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

fn write_scenario(dir: &Path, extra_plant: &str) -> String {
    let file = dir.join("s.toml");
    std::fs::write(&file, scenario(extra_plant)).unwrap();
    file.to_str().unwrap().to_string()
}

fn tempdir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("admittance-run-safety-")
        .tempdir()
        .unwrap()
}

#[test]
fn a_folder_of_the_users_is_refused_and_kept() {
    let tmp = tempdir();
    let s = write_scenario(tmp.path(), "");
    let mine = tmp.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("thesis.tex"), "years of work").unwrap();
    let (code, err) = admittance(&["run", &s, "--out", mine.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("did not write") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(mine.join("thesis.tex")).unwrap(),
        "years of work"
    );
    // A regular file is refused too, and stays.
    let file = tmp.path().join("notes.txt");
    std::fs::write(&file, "keep me").unwrap();
    let (code, err) = admittance(&["run", &s, "--out", file.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    assert!(std::fs::read_dir(tmp.path()).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .contains(".old-")));
    // --force replaces the folder.
    let (code, err) = admittance(&["run", &s, "--out", mine.to_str().unwrap(), "--force"]);
    assert_eq!(code, 0, "{err}");
    assert!(mine.join("summary.json").is_file() && !mine.join("thesis.tex").exists());
}

#[test]
fn the_current_folder_and_the_scenarios_folder_are_refused_before_the_run() {
    let tmp = tempdir();
    let s = write_scenario(tmp.path(), "");
    for out in [".", "/", tmp.path().to_str().unwrap()] {
        let started = std::time::Instant::now();
        let (code, err) = admittance(&["run", &s, "--out", out, "--force"]);
        assert_eq!(code, 2, "--out {out}: {err}");
        assert!(err.contains("nothing was written"), "{err}");
        assert!(started.elapsed().as_secs() < 20);
    }
    assert!(Path::new(&s).is_file());
}

#[test]
fn a_run_folder_is_replaced_and_stale_partials_of_dead_runs_are_removed() {
    let tmp = tempdir();
    let s = write_scenario(tmp.path(), "");
    let out = tmp.path().join("out");
    let (code, err) = admittance(&["run", &s, "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    // A killed run's leftover (its process is gone), and a folder that only looks like one.
    let dead = {
        let mut child = Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        pid
    };
    let stale = tmp.path().join(format!(".out.partial-{dead}"));
    std::fs::create_dir(&stale).unwrap();
    std::fs::write(stale.join(".admittance-partial"), "").unwrap();
    let lookalike = tmp.path().join(format!(".other.partial-{dead}"));
    std::fs::create_dir(&lookalike).unwrap();
    std::fs::write(lookalike.join("data.csv"), "mine").unwrap();
    let (code, err) = admittance(&[
        "run",
        &s,
        "--out",
        out.to_str().unwrap(),
        "--set",
        "duration=0.05",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        !stale.exists(),
        "the stale partial folder of a dead run is removed"
    );
    assert!(
        lookalike.join("data.csv").is_file(),
        "a folder without the marker is kept"
    );
    let toml = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    assert!(
        toml.contains("duration = 0.05") && toml.contains("--set duration=0.05"),
        "{toml}"
    );
}

#[test]
fn work_beyond_the_limits_is_refused_with_the_figure() {
    let tmp = tempdir();
    let s = write_scenario(tmp.path(), "");
    let out = tmp.path().join("out");
    for (set, key) in [
        ("duration=1e308", "duration"),
        ("plant.rate_hz=1e308", "plant.rate_hz"),
    ] {
        let started = std::time::Instant::now();
        let (code, err) = admittance(&["run", &s, "--out", out.to_str().unwrap(), "--set", set]);
        assert_eq!(code, 3, "{set}: {err}");
        assert!(err.contains(key) && err.contains("plant steps"), "{err}");
        assert!(started.elapsed().as_secs() < 20, "refused before the run");
    }
    let (code, err) = admittance(&[
        "run",
        &s,
        "--out",
        out.to_str().unwrap(),
        "--set",
        "duration=30000",
        "--set",
        "output.decimation=1",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("time series") && err.contains("GiB"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_run_that_blows_up_fails_with_exit_1_and_says_where() {
    let tmp = tempdir();
    let s = write_scenario(tmp.path(), "");
    for (extra, what) in [
        (
            "plant.initial_qdot=[100.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
            "velocity",
        ),
        ("plant.gravity=[0.0, 0.0, -1.0e6]", ""),
        ("plant.payload.mass=1.0e6", ""),
        ("plant.sensors.noise_std=1.0e308", "encoder"),
    ] {
        let out = tmp.path().join("out");
        let (code, err) = admittance(&[
            "run",
            &s,
            "--out",
            out.to_str().unwrap(),
            "--set",
            extra,
            "--set",
            "duration=1",
        ]);
        assert_eq!(code, 1, "{extra}: {err}");
        assert!(
            err.contains("diverged") && err.contains(what),
            "{extra}: {err}"
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["variants"]["base"]["diverged"], true, "{extra}");
        assert!(
            summary["variants"]["base"]["diverged_at"].is_number(),
            "{extra}"
        );
    }
}

#[test]
fn an_observer_network_that_cannot_fit_is_refused_before_its_data_are_simulated() {
    let tmp = tempdir();
    let out = tmp.path().join("out");
    let scenario = root().join("scenarios/admittance.toml");
    let started = std::time::Instant::now();
    let (code, err) = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "learned",
        "--set",
        "observer.training.nodes=4294967296",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("observer.training.nodes") && err.contains("4294967296"),
        "{err}"
    );
    assert!(
        started.elapsed().as_secs() < 10,
        "refused before simulating 450 s of data"
    );
    assert!(!out.exists());
}

/// Issue 14: a NaN sensor fault at start-up used to leave the observer's input filter NaN
/// for the whole run (`observer_faults` = every step); it must stop counting when the fault
/// ends. 0.2 s: after 0.5 s without sensors the simulated arm (which has no joint stops)
/// falls beyond its limits by more than the plausibility gates' margin, and the gates then
/// refuse every reading, as a robot's would (issue 34).
#[test]
fn the_observer_recovers_after_a_nan_fault_at_start_up() {
    let tmp = tempdir();
    let out = tmp.path().join("run");
    let scenario = root().join("scenarios/admittance.toml");
    let (code, err) = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "momentum",
        "--set",
        "duration=2",
        "--set",
        "evaluation_start=1",
        "--set",
        r#"plant.sensors.faults=[{kind="nan", t_start=0.0, t_end=0.2}]"#,
        "--out",
        out.to_str().unwrap(),
        "--no-recording",
    ]);
    // The run finishes and writes its folder; 0.2 s without sensors at start-up
    // throws the arm off its reference, which the health rules call a failure (exit 4).
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("[observer_faults]") && err.contains("[hand_error]"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let m = &summary["variants"]["momentum"];
    assert_eq!(m["steps"], 2000, "{m}");
    // 200 control periods of NaN at 1 kHz, and none after.
    assert_eq!(m["observer_faults"], 200, "{m}");
}

/// Issue 14: one joint's encoder frozen for 1 s gave `faults` 0; it is detected, held safe
/// and counted as `stale_measurements`.
#[test]
fn a_frozen_joint_is_detected_and_counted() {
    let tmp = tempdir();
    let out = tmp.path().join("run");
    let scenario = root().join("scenarios/admittance.toml");
    let (code, err) = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "momentum",
        "--set",
        "duration=7",
        "--set",
        "evaluation_start=1",
        "--set",
        r#"plant.sensors.faults=[{kind="stale", joints=["left_s0"], t_start=5.0, t_end=6.0}]"#,
        "--out",
        out.to_str().unwrap(),
        "--no-recording",
    ]);
    // A frozen joint for 1 s is a stale-data warning, and the safe hold it causes throws
    // the arm off its reference: a health failure (exit 4), the folder written.
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("1000 control steps with a stale") && err.contains("[stale_data]"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let m = &summary["variants"]["momentum"];
    // Every one of the 1000 frozen samples is reported (the sample's time stamp is old);
    // the controller holds safe from the 30th repeated value on (s0 moves at 0.45-0.52 rad/s).
    assert_eq!(m["stale_measurements"].as_u64().unwrap(), 1000, "{m}");
    let held = m["faults"].as_u64().unwrap();
    assert!((900..1000).contains(&held), "{m}");
}

/// Issue 14: twenty dropouts of 10 ms gave `faults` 0 and nothing reported; every stale
/// sample is reported now (too short for the controller to hold).
#[test]
fn short_dropouts_are_reported() {
    let tmp = tempdir();
    let out = tmp.path().join("run");
    let scenario = root().join("scenarios/admittance.toml");
    let faults: Vec<String> = (0..20)
        .map(|i| {
            let t = 2.0 + 0.25 * i as f64;
            format!("{{kind=\"stale\", t_start={t:.3}, t_end={:.3}}}", t + 0.01)
        })
        .collect();
    let set = format!("plant.sensors.faults=[{}]", faults.join(", "));
    let (code, err) = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "momentum",
        "--set",
        "duration=8",
        "--set",
        "evaluation_start=1",
        "--set",
        &set,
        "--out",
        out.to_str().unwrap(),
        "--no-recording",
    ]);
    assert_eq!(code, 0, "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let m = &summary["variants"]["momentum"];
    assert_eq!(m["stale_measurements"].as_u64().unwrap(), 200, "{m}");
}

/// Found by the reliability harness: `plant.rate_hz = 1e9` with a short duration passed
/// the step limit (3e8 steps) and ran for minutes. The rate is bounded.
#[test]
fn an_absurd_plant_rate_is_refused_before_the_run() {
    let tmp = tempdir();
    let s = write_scenario(tmp.path(), "rate_hz = 1e9");
    let out = tmp.path().join("run");
    let started = std::time::Instant::now();
    let (code, err) = admittance(&["run", &s, "--out", out.to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("rate_hz") && err.contains("1000000 Hz"),
        "{err}"
    );
    assert!(started.elapsed().as_secs_f64() < 10.0);
    assert!(!out.exists());
}
