//! `admittance excite` writes free-motion data inside the arm's limits that `admittance
//! identify` reads, and identification on it recovers a perturbed arm; it refuses to
//! overwrite what it did not write and names bad flags.

use std::path::{Path, PathBuf};
use std::process::Command;

use admittance_dynamics::{
    excitation, rnea, Data, ExcitationSettings, Identification, JointTerms, Model,
};
use admittance_scenario::FreeMotionData;

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

fn baxter() -> Model {
    Model::from_urdf_file(&root().join("models/baxter_left_arm.urdf"), None, None).unwrap()
}

/// The torque of `model` plus `terms` at every row of `q, qdot, qddot` (row-major).
fn torques(model: &Model, terms: &[JointTerms], q: &[f64], qd: &[f64], qdd: &[f64]) -> Vec<f64> {
    let n = model.nq();
    let mut data = Data::new(model);
    let mut out = Vec::with_capacity(q.len());
    for k in 0..q.len() / n {
        let s = k * n..(k + 1) * n;
        let tau = rnea(
            model,
            &mut data,
            &q[s.clone()],
            &qd[s.clone()],
            &qdd[s.clone()],
        )
        .unwrap();
        out.extend(
            s.clone()
                .map(|c| tau[c - k * n] + terms[c - k * n].torque(q[c], qd[c], qdd[c])),
        );
    }
    out
}

/// `data` with `tau` replaced, in the free-motion layout.
fn write_data(path: &Path, data: &FreeMotionData, tau: &[f64]) {
    let n = data.dof();
    let mut text = String::from("t");
    for kind in ["q", "qdot", "qddot", "tau"] {
        data.joints
            .iter()
            .for_each(|j| text += &format!(",{kind}.{j}"));
    }
    text.push('\n');
    for k in 0..data.len() {
        let s = k * n..(k + 1) * n;
        let row = data.q[s.clone()]
            .iter()
            .chain(&data.qdot[s.clone()])
            .chain(&data.qddot[s.clone()])
            .chain(&tau[s]);
        text += &format!("{}", data.t[k]);
        row.for_each(|v| text += &format!(",{v}"));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn identify_on_an_excitation_recovers_a_perturbed_baxter() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("excitation.csv");
    let urdf = "models/baxter_left_arm.urdf";
    let (code, stdout, stderr) = admittance(&[
        "excite",
        "--urdf",
        urdf,
        "--duration",
        "30",
        "--rate",
        "100",
        // A simulated arm: the URDF's whole limits (the default envelope is for real arms).
        "--range",
        "full",
        "--velocity-fraction",
        "1",
        "--acceleration-fraction",
        "1",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("condition number of the base inertial regressor"),
        "{stdout}"
    );
    assert!(stdout.contains("left_w2"), "{stdout}");
    let arm = baxter();
    let data = FreeMotionData::load(&csv).unwrap();
    assert_eq!(data.len(), 3001);
    assert_eq!(data.joints, arm.joint_names().collect::<Vec<_>>());
    // The tau columns are the URDF's RNEA.
    let none = vec![
        JointTerms {
            coulomb_width: 0.01,
            ..Default::default()
        };
        7
    ];
    let nominal = torques(&arm, &none, &data.q, &data.qdot, &data.qddot);
    assert!(nominal
        .iter()
        .zip(&data.tau)
        .all(|(a, b)| (a - b).abs() < 1e-9));
    // A heavier arm with friction played the excitation.
    let truth = arm
        .with_body_scales(&[1.3, 0.8, 1.2, 1.1, 0.9, 1.25, 1.1])
        .unwrap();
    let terms: Vec<JointTerms> = (0..7)
        .map(|i| JointTerms {
            armature: 0.05,
            viscous: 1.0 + 0.2 * i as f64,
            coulomb: [1.5, 0.3],
            coulomb_width: 0.01,
            offset: 0.2,
            ..Default::default()
        })
        .collect();
    let recorded = dir.path().join("recorded.csv");
    write_data(
        &recorded,
        &data,
        &torques(&truth, &terms, &data.q, &data.qdot, &data.qddot),
    );
    let ident_path = dir.path().join("baxter.ident.json");
    let (code, stdout, stderr) = admittance(&[
        "identify",
        "--data",
        recorded.to_str().unwrap(),
        "--urdf",
        urdf,
        "--no-springs",
        "--out",
        ident_path.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    eprintln!("{stdout}");
    // The excitation repeats its 10 s period and no --validation was given: the user is told
    // that the cross-validated figures are optimistic, and the file records the period.
    assert!(
        stderr.contains("the motion repeats every 10.0") && stderr.contains("--validation"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&ident_path).unwrap();
    assert!(text.contains("\"data_repeats_every_s\""), "{text}");
    // Judged on another seed's excitation.
    let (ident, _) = Identification::load_with_urdf(&ident_path).unwrap();
    let other = excitation(
        &arm,
        &ExcitationSettings {
            seed: 5,
            duration: 10.0,
            rate_hz: 100.0,
            iterations: 0,
            range: vec![f64::INFINITY],
            velocity_fraction: 1.0,
            acceleration_fraction: 1.0,
            ..Default::default()
        },
    )
    .unwrap();
    let want = torques(&truth, &terms, &other.q, &other.qdot, &other.qddot);
    let prior = torques(&arm, &none, &other.q, &other.qdot, &other.qddot);
    let (mut out, mut d) = ([0.0; 7], Data::new(&ident.model));
    let mut pred = Vec::new();
    for k in 0..other.len() {
        let s = k * 7..(k + 1) * 7;
        ident
            .predict(
                &mut d,
                &other.q[s.clone()],
                &other.qdot[s.clone()],
                &other.qddot[s],
                &mut out,
            )
            .unwrap();
        pred.extend_from_slice(&out);
    }
    let rms = |a: &[f64]| {
        (a.iter()
            .zip(&want)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            / want.len() as f64)
            .sqrt()
    };
    let (ours, urdf_rms) = (rms(&pred), rms(&prior));
    eprintln!("other motion: identified {ours:.4} N m rms, URDF {urdf_rms:.3}");
    assert!(
        ours < 0.02 * urdf_rms,
        "identified {ours} vs URDF {urdf_rms}"
    );
}

#[test]
fn out_is_only_a_new_name_or_an_excitation_and_flags_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = "models/franka_panda.urdf";
    let notes = dir.path().join("notes.csv");
    std::fs::write(&notes, "t,q.a\n0,1\n").unwrap();
    let (code, _, stderr) = admittance(&[
        "excite",
        "--urdf",
        urdf,
        "--duration",
        "10",
        "--out",
        notes.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("is not a file `admittance excite` wrote"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "t,q.a\n0,1\n");
    // Its own file it replaces.
    let out = dir.path().join("panda.csv");
    let fast = ["--iterations", "20", "--rate", "50"];
    for seed in ["1", "2"] {
        let mut args = vec![
            "excite",
            "--urdf",
            urdf,
            "--duration",
            "10",
            "--seed",
            seed,
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(fast);
        let (code, stdout, stderr) = admittance(&args);
        assert_eq!(code, 0, "{stderr}");
        assert!(stdout.contains("panda_joint7"), "{stdout}");
    }
    assert!(std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .nth(1)
        .unwrap()
        .ends_with(",2"));
    let leftovers = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(leftovers, 2, "no temporary file is left");
    for (flags, named) in [
        (vec!["--duration", "15", "--period", "10"], "--period"),
        (vec!["--duration", "10", "--harmonics", "1"], "--harmonics"),
        (
            vec!["--duration", "10", "--position-margin", "0.6"],
            "--position-margin",
        ),
        (vec!["--duration", "-3"], "--duration"),
        (vec!["--duration", "10", "--range", "-0.5"], "--range"),
        (vec!["--duration", "10", "--range", "0.5,0.5"], "--range"),
        (vec!["--duration", "10", "--pose", "0,0,0"], "--pose"),
        (
            vec!["--duration", "10", "--pose", "0,0,0,9,0,0,0"],
            "--pose",
        ),
        (
            vec!["--duration", "10", "--velocity-fraction", "1.5"],
            "--velocity-fraction",
        ),
        (
            vec!["--duration", "10", "--acceleration-fraction", "0"],
            "--acceleration-fraction",
        ),
    ] {
        let mut args = vec!["excite", "--urdf", urdf, "--out", out.to_str().unwrap()];
        args.extend(flags);
        let (code, _, stderr) = admittance(&args);
        assert_eq!(code, 2, "{named}: {stderr}");
        assert!(stderr.contains(named), "{named}: {stderr}");
    }
    let (code, _, stderr) = admittance(&[
        "excite",
        "--urdf",
        "models/none.urdf",
        "--duration",
        "10",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{stderr}");
}
