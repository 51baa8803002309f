//! The deployment folder the bridge tests run: the Panda of scenarios/panda_admittance.toml,
//! variant `momentum` (PD with gravity compensation, joint admittance on joint 1, the
//! momentum observer on a nominal model with 80 % of the inertias), written as
//! `admittance deploy` writes it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub const LOOP_TOML: &str = r#"format = "admittance-loop"
version = 1
control_rate_hz = 1000.0

[arm]
urdf = "arm.urdf"
base = "panda_link0"
tip = "panda_hand_tcp"

[signals]
filter_cutoff_hz = 40.0

[controller]
kind = "pd"
pd = { kp = [100.0, 200.0, 100.0, 100.0, 10.0, 10.0, 3.0], kd = [10.0, 20.0, 10.0, 10.0, 0.5, 0.5, 0.1], gravity_compensation = true }

[admittance]
damping = [3.0, 1e4, 1e4, 1e4, 1e4, 1e4, 1e4]
stiffness = [5.0, 1e4, 1e4, 1e4, 1e4, 1e4, 1e4]

[admittance.saturation]
rho = 0.95
centre = 0.0
half_range = [1.1, inf, inf, inf, inf, inf, inf]

[observer]
kind = "momentum"
nominal_inertia_scale = 0.8
input_filter_hz = 10.0
cutoff_hz = 5.0
warmup = 0.5
momentum = { gain = 50.0 }
"#;

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Writes the folder into `dir`.
pub fn deploy_into(dir: &Path) {
    let urdf = std::fs::read(root().join("models/franka_panda.urdf")).unwrap();
    admittance_loop::write_deployment(
        dir,
        &[
            ("loop.toml".into(), LOOP_TOML.as_bytes().to_vec()),
            ("arm.urdf".into(), urdf),
        ],
        serde_json::json!({"tool": "crates/ros2/tests/common"}),
    )
    .unwrap();
}

/// A fresh folder (removed with the returned guard).
pub fn deploy() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("deploy_panda_momentum");
    deploy_into(&dir);
    (tmp, dir)
}
