//! `admittance deploy` (issue 32): a scenario variant becomes the folder a robot's loop
//! reads; the folder loads as `RobotLoop` and holds no simulated part; a learned variant
//! whose network is not cached is refused with the command that trains it (never trained
//! here); `oracle` is refused; a folder that is not a deployment is never overwritten.

use std::path::PathBuf;
use std::process::Command;

use admittance_loop::{Deployment, RobotLoop};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn admittance(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .current_dir(root())
        // An empty cache: nothing trained elsewhere is found.
        .env(
            "ADMITTANCE_CACHE_DIR",
            std::env::temp_dir().join("admittance-deploy-test-empty-cache"),
        )
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn a_scenario_variant_deploys_and_loads() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("deploy");
    let out_s = out.to_str().unwrap();
    let (code, stdout, stderr) = admittance(&[
        "deploy",
        "scenarios/admittance.toml",
        "--variant",
        "momentum",
        "--out",
        out_s,
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("loop.toml") && stdout.contains("manifest.json"),
        "{stdout}"
    );
    let d = Deployment::load(&out).unwrap();
    assert_eq!(
        d.file_names().collect::<Vec<_>>(),
        ["arm.urdf", "loop.toml"]
    );
    // The scenario's rate and sensor filter, in the loop's vocabulary; nothing simulated.
    assert_eq!(d.config.control_rate_hz, 1000.0);
    assert_eq!(d.config.signals.filter_cutoff_hz, 40.0);
    let text = std::fs::read_to_string(out.join("loop.toml")).unwrap();
    for absent in ["[plant", "[trajectory", "training", "friction"] {
        assert!(!text.contains(absent), "loop.toml holds {absent}");
    }
    assert_eq!(d.made_by["variant"], "momentum");
    let l = RobotLoop::load(&out, &[]).unwrap();
    assert_eq!(l.dof(), 7);
    // Deploying again replaces the folder's files.
    let (code, _, stderr) = admittance(&[
        "deploy",
        "scenarios/admittance.toml",
        "--variant",
        "momentum",
        "--out",
        out_s,
    ]);
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn what_cannot_be_deployed_is_refused_naming_why() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("deploy");
    let out_s = out.to_str().unwrap();
    let (code, _, stderr) = admittance(&[
        "deploy",
        "scenarios/admittance.toml",
        "--variant",
        "learned",
        "--out",
        out_s,
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(
        stderr.contains("observer.training")
            && stderr.contains("not in the training cache")
            && stderr.contains("admittance run"),
        "{stderr}"
    );
    assert!(!out.exists(), "a refused deploy wrote {out_s}");
    let (code, _, stderr) = admittance(&[
        "deploy",
        "scenarios/admittance.toml",
        "--variant",
        "oracle",
        "--out",
        out_s,
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("oracle"), "{stderr}");
    // A folder of someone else's is not written into.
    let mine = tmp.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let (code, _, stderr) = admittance(&[
        "deploy",
        "scenarios/admittance.toml",
        "--variant",
        "momentum",
        "--out",
        mine.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("not a deployment folder"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(mine.join("notes.txt")).unwrap(),
        "keep"
    );
}

/// A run folder anywhere deploys: its scenario.toml's relative paths are taken from the
/// scenario file the run was made from (summary.json's `scenario_file`).
#[test]
fn a_run_folder_outside_the_project_deploys() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let run_s = run.to_str().unwrap();
    let (code, _, stderr) = admittance(&[
        "run",
        "scenarios/admittance.toml",
        "--variant",
        "momentum",
        "--set",
        "duration=0.2",
        "--set",
        "evaluation_start=0.1",
        "--out",
        run_s,
        "--no-recording",
    ]);
    assert!(code == 0 || code == 4, "{stderr}");
    let out = tmp.path().join("deploy");
    let (code, _, stderr) = admittance(&[
        "deploy",
        run_s,
        "--variant",
        "momentum",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let d = Deployment::load(&out).unwrap();
    assert!(d.made_by["scenario"]
        .as_str()
        .unwrap()
        .ends_with("scenarios/admittance.toml"));
    assert_eq!(RobotLoop::load(&out, &[]).unwrap().dof(), 7);
}
