//! `admittance identify --payload DATA --identification FILE --out NEW`: the payload at the
//! tip fitted on top of an identification, written as a new identification file carrying it
//! (the payload recorded in its data); bad combinations of flags are named.

use std::path::{Path, PathBuf};
use std::process::Command;

use admittance_dynamics::{
    excitation, rnea, Data, ExcitationSettings, Identification, Model, Payload,
};
use nalgebra::{Matrix3, Vector3};

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

/// Free-motion CSV of `model` playing an excitation (seed `seed`), tau by RNEA.
fn recording(path: &Path, model: &Model, seed: u64) {
    let e = excitation(
        model,
        &ExcitationSettings {
            duration: 20.0,
            period: 20.0,
            rate_hz: 100.0,
            iterations: 50,
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    let n = model.nq();
    let mut text = String::from("t");
    for kind in ["q", "qdot", "qddot", "tau"] {
        model
            .joint_names()
            .for_each(|j| text += &format!(",{kind}.{j}"));
    }
    text.push('\n');
    let mut data = Data::new(model);
    for k in 0..e.len() {
        let s = k * n..(k + 1) * n;
        let tau = rnea(
            model,
            &mut data,
            &e.q[s.clone()],
            &e.qdot[s.clone()],
            &e.qddot[s.clone()],
        )
        .unwrap()
        .clone();
        text += &format!("{}", e.t[k]);
        for v in e.q[s.clone()]
            .iter()
            .chain(&e.qdot[s.clone()])
            .chain(&e.qddot[s])
            .chain(tau.iter())
        {
            text += &format!(",{v:.17e}");
        }
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn a_payload_on_top_of_an_identification_is_written_into_a_new_file() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = "models/baxter_left_arm.urdf";
    let arm = Model::from_urdf_file(&root().join(urdf), None, None).unwrap();
    let truth = Payload {
        mass: 2.0,
        com: Vector3::new(0.02, -0.01, 0.07),
        inertia: Matrix3::from_diagonal(&Vector3::new(0.004, 0.003, 0.002)),
    };
    let (plain, tool) = (dir.path().join("plain.csv"), dir.path().join("tool.csv"));
    recording(&plain, &arm, 1);
    recording(&tool, &arm.with_payload(&truth).unwrap(), 2);
    let base = dir.path().join("arm.ident.json");
    let (code, _, stderr) = admittance(&[
        "identify",
        "--data",
        plain.to_str().unwrap(),
        "--urdf",
        urdf,
        "--no-friction",
        "--out",
        base.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let out = dir.path().join("arm_tool.ident.json");
    let (code, stdout, stderr) = admittance(&[
        "identify",
        "--payload",
        tool.to_str().unwrap(),
        "--identification",
        base.to_str().unwrap(),
        "--urdf",
        urdf,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    eprintln!("{stdout}");
    assert!(
        stdout.contains("payload at left_hand") && stdout.contains("with payload"),
        "{stdout}"
    );
    // The new file carries the payload: every consumer loading it predicts the arm with it.
    let (carried, _) = Identification::load_with_urdf(&out).unwrap();
    let (ident, _) = Identification::load_with_urdf(&base).unwrap();
    let added = carried.model.total_moving_mass() - ident.model.total_moving_mass();
    assert!((added - truth.mass).abs() < 0.02 * truth.mass, "{added}");
    let text = std::fs::read_to_string(&out).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let record = &v["payload"]["data"]["payload"];
    let mass = record["mass_kg"].as_f64().unwrap();
    assert!((mass - truth.mass).abs() < 0.02 * truth.mass, "{record}");
    let com: Vec<f64> = serde_json::from_value(record["com_m"].clone()).unwrap();
    let off = (Vector3::from_vec(com) - truth.com).norm();
    assert!(off < 0.005, "{record}");
    // What the identification without the payload was made from is kept.
    assert!(v["payload"]["data"]["data"]
        .as_str()
        .unwrap()
        .ends_with("plain.csv"));
    // --payload without --identification, and --out over a file that is not ours.
    let (code, _, stderr) = admittance(&[
        "identify",
        "--payload",
        tool.to_str().unwrap(),
        "--urdf",
        urdf,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--identification"), "{stderr}");
    let (code, _, stderr) = admittance(&[
        "identify",
        "--payload",
        tool.to_str().unwrap(),
        "--identification",
        base.to_str().unwrap(),
        "--urdf",
        urdf,
        "--out",
        tool.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    let (code, _, stderr) =
        admittance(&["identify", "--urdf", urdf, "--out", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--data"), "{stderr}");
}
