//! Deployment folders for the tests, written with `admittance_loop::write_deployment` as
//! `admittance deploy` writes them (the arm of scenarios/admittance.toml: Baxter's left
//! arm, PD with gravity compensation, joint admittance on s0), and the inputs of a slow
//! motion with consistent torques.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use admittance_dynamics::{rnea, Data, Model};
use admittance_learning::broad::{fit, ArmIdentity, BroadConfig, Dataset};

pub const URDF: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../models/baxter_left_arm.urdf"
);

/// Baxter's pose of experiment B.
pub const POSE: [f64; 7] = [0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5];

pub fn model() -> Model {
    Model::from_urdf_file(URDF.as_ref(), Some("base"), Some("left_hand")).unwrap()
}

/// The loop file of an observer `kind` ("momentum", "learned", "hybrid", "none").
pub fn loop_toml(kind: &str) -> String {
    let network = if kind == "learned" || kind == "hybrid" {
        "network = \"observer.broad\"\n"
    } else {
        ""
    };
    format!(
        r#"format = "admittance-loop"
version = 1
control_rate_hz = 1000.0

[arm]
urdf = "arm.urdf"
base = "base"
tip = "left_hand"

[signals]
filter_cutoff_hz = 40.0

[controller]
kind = "pd"
pd = {{ kp = [100.0, 150.0, 50.0, 50.0, 10.0, 10.0, 2.0], kd = [10.0, 15.0, 4.0, 4.0, 0.5, 0.5, 0.1], gravity_compensation = true }}

[admittance]
damping = [3.0, 1e4, 1e4, 1e4, 1e4, 1e4, 1e4]
stiffness = [5.0, 1e4, 1e4, 1e4, 1e4, 1e4, 1e4]

[admittance.saturation]
rho = 0.95
centre = 0.0
half_range = [1.1, inf, inf, inf, inf, inf, inf]

[observer]
kind = "{kind}"
input_filter_hz = 10.0
cutoff_hz = 5.0
warmup = 0.5
momentum = {{ gain = 50.0 }}
{network}"#
    )
}

/// A small network on this arm (inputs `[q, q', q'']`, outputs its 7 torques), fitted on
/// the inverse dynamics of random states: any network of the right sizes serves the tests.
pub fn network_bytes() -> Vec<u8> {
    let model = model();
    let mut data = Data::new(&model);
    let rows = 400;
    let mut inputs = Vec::with_capacity(rows * 21);
    let mut targets = Vec::with_capacity(rows * 7);
    let mut state = 11u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for _ in 0..rows {
        let q: Vec<f64> = POSE.iter().map(|p| p + 0.4 * next()).collect();
        let v: Vec<f64> = (0..7).map(|_| next()).collect();
        let a: Vec<f64> = (0..7).map(|_| 2.0 * next()).collect();
        let tau = rnea(&model, &mut data, &q, &v, &a).unwrap();
        inputs.extend(q.iter().chain(&v).chain(&a));
        targets.extend(tau.iter());
    }
    let set = Dataset::new(&inputs, &targets, 21, 7).unwrap();
    let config = BroadConfig {
        nodes: 60,
        centre_subsample: 400,
        lambda_grid: vec![1e-6],
        threads: 1,
        ..BroadConfig::for_arm(7)
    };
    let (mut network, _) = fit(&set, None, &config).unwrap();
    network
        .set_arm(ArmIdentity::new(model.joint_names(), model.fingerprint()))
        .unwrap();
    network.to_bytes()
}

/// Writes the deployment folder of observer `kind` into `dir` (its network fitted here).
pub fn deploy_into(dir: &Path, kind: &str) {
    let mut files = vec![
        ("loop.toml".to_string(), loop_toml(kind).into_bytes()),
        ("arm.urdf".to_string(), std::fs::read(URDF).unwrap()),
    ];
    if kind == "learned" || kind == "hybrid" {
        files.push(("observer.broad".to_string(), network_bytes()));
    }
    admittance_loop::write_deployment(
        dir,
        &files,
        serde_json::json!({"tool": "crates/ffi/tests/common", "observer": kind}),
    )
    .unwrap();
}

/// A fresh deployment folder of observer `kind` (removed with the returned guard).
pub fn deploy(kind: &str) -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join(format!("deploy_{kind}"));
    deploy_into(&dir, kind);
    (tmp, dir)
}

/// Period `k` of a slow motion around [`POSE`] and its inverse-dynamics torque (what an
/// arm moving so in free space measures), at 1 kHz.
pub fn motion(model: &Model, data: &mut Data, k: usize) -> ([f64; 7], [f64; 7]) {
    let t = k as f64 * 1e-3;
    let (mut q, mut v, mut a) = ([0.0; 7], [0.0; 7], [0.0; 7]);
    for i in 0..7 {
        let w = 1.0 + 0.3 * i as f64;
        q[i] = POSE[i] + 0.1 * (w * t).sin();
        v[i] = 0.1 * w * (w * t).cos();
        a[i] = -0.1 * w * w * (w * t).sin();
    }
    let tau = rnea(model, data, &q, &v, &a).unwrap();
    let mut t7 = [0.0; 7];
    t7.copy_from_slice(tau.as_slice());
    (q, t7)
}
