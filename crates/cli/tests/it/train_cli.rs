//! `admittance train` / `admittance grow` end to end: record a short free-motion file with
//! `admittance run scenarios/free_motion.toml`, train a small network on it, grow it, and
//! reject a corrupted data file with its line number.

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

#[test]
fn train_and_grow_on_recorded_free_motion() {
    let dir = std::env::temp_dir().join(format!("admittance-train-cli-{}", std::process::id()));
    let run = dir.join("run");
    let run_s = run.to_str().unwrap();
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/free_motion.toml",
        "--out",
        run_s,
        "--quiet",
        "--set",
        "duration=4.0",
    ]);
    assert_eq!(code, 0, "{err}");
    let data = run.join("free_motion.csv");
    let data_s = data.to_str().unwrap();
    let model = dir.join("m1.broad");
    let model_s = model.to_str().unwrap();
    let (code, out, err) = admittance(&[
        "train",
        "--data",
        data_s,
        "--urdf",
        "models/baxter_left_arm.urdf",
        "--tip",
        "left_hand",
        "--base",
        "base",
        "--nodes",
        "40",
        "--out",
        model_s,
    ]);
    assert_eq!(code, 0, "{err}");
    for key in [
        "samples: 4000",
        "validation: blocked cross-validation over 5 stretches",
        "validation samples: 0",
        "expected false torque on unseen motion (rms, N m): [",
        "coverage threshold: 0.",
        "nodes: 40",
        "lambda:",
        "time:",
        "validation nrmse: [",
    ] {
        assert!(out.contains(key), "`{key}` missing in:\n{out}");
    }
    assert!(model.exists());
    let grown = dir.join("m2.broad");
    let (code, out, err) = admittance(&[
        "grow",
        "--model",
        model_s,
        "--nodes",
        "10",
        "--data",
        data_s,
        "--out",
        grown.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("nodes: 50 (+10)"), "{out}");

    // A corrupted row: exit code 3, the file and the line named.
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[5] = lines[5].replacen(',', ",x", 1);
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let (code, _, err) = admittance(&[
        "train",
        "--data",
        bad.to_str().unwrap(),
        "--urdf",
        "models/baxter_left_arm.urdf",
        "--nodes",
        "10",
        "--out",
        model_s,
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("bad.csv:6:") && err.contains("is not a number"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
