//! `admittance ros2`: with the `ros2` feature the bridge's arguments and its refusals
//! (before any network), without it the message saying how to build it.

use std::process::Command;

fn admittance(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[cfg(feature = "ros2")]
#[test]
fn ros2_bridge_arguments_and_refusals() {
    let (code, out, _) = admittance(&["ros2", "bridge", "--help"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("--profile") && out.contains("--distro"),
        "{out}"
    );
    // KUKA's LBRState topic cannot be subscribed to: a bad input, named.
    let dir = tempfile::tempdir().unwrap();
    let deployed = dir.path().join("deployed");
    let deployed = deployed.to_str().unwrap();
    let (code, _, err) = admittance(&[
        "deploy",
        "scenarios/panda_admittance.toml",
        "--variant",
        "momentum",
        "--out",
        deployed,
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = admittance(&["ros2", "bridge", deployed, "--profile", "lbr"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("/lbr/state") && err.contains("/lbr/joint_states"),
        "{err}"
    );
    let (code, _, err) = admittance(&["ros2", "bridge", "no/such.toml", "--distro", "foxy"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--distro `foxy`"), "{err}");
    let (code, _, err) = admittance(&["ros2", "bridge", "no/such"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("no/such") && err.contains("admittance deploy"),
        "{err}"
    );
}

#[cfg(not(feature = "ros2"))]
#[test]
fn ros2_without_the_feature_says_how_to_build_it() {
    let (code, _, err) = admittance(&["ros2", "bridge", "scenarios/panda_admittance.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--features ros2") && err.contains("docs/ros2.md"),
        "{err}"
    );
}
