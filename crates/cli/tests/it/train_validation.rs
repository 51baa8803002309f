//! `admittance train` validates on motion it did not train on (issue #22): blocked
//! cross-validation by default, `--validation FILE` for a separate recording,
//! `--validation-fraction` kept; `--nominal IDENT.json` trains the residual of an
//! identification, recorded by its checksum and required again by `grow`.

use std::path::{Path, PathBuf};
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

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const ARM: [&str; 6] = [
    "--urdf",
    "models/baxter_left_arm.urdf",
    "--base",
    "base",
    "--tip",
    "left_hand",
];

/// `seconds` of simulated free motion (1000 rows a second) in `dir/name`.
fn free_motion(dir: &Path, name: &str, seconds: f64, seed: u64) -> PathBuf {
    let run = dir.join(name);
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/free_motion.toml",
        "--out",
        s(&run),
        "--quiet",
        "--set",
        &format!("duration={seconds}"),
        "--set",
        &format!("seed={seed}"),
    ]);
    assert_eq!(code, 0, "{err}");
    run.join("free_motion.csv")
}

fn train(data: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["train", "--data", s(data), "--out", s(out), "--nodes", "20"];
    args.extend_from_slice(&ARM);
    args.extend_from_slice(extra);
    admittance(&args)
}

fn header(model: &Path) -> serde_json::Value {
    let bytes = std::fs::read(model).unwrap();
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[16..16 + h_len]).unwrap()
}

fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

#[test]
fn validation_flags_choose_the_rows_and_are_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path(), "a", 2.0, 1);
    let other = free_motion(dir.path(), "b", 1.0, 2);
    let model = dir.path().join("m.broad");
    let (code, out, err) = train(&data, &model, &["--folds", "4"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("samples: 2000"), "{out}");
    assert!(out.contains("cross-validation over 4 stretches"), "{out}");
    let h = header(&model);
    assert_eq!(h["data"]["validation"]["kind"], "blocked_cross_validation");
    assert_eq!(h["data"]["validation"]["folds"], 4);
    assert!(h["coverage_threshold"].as_f64().unwrap() > 0.0);
    let (code, out, err) = train(&data, &model, &["--validation", s(&other)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("validation samples: 1000"), "{out}");
    assert_eq!(
        header(&model)["data"]["validation"]["kind"],
        "separate_data"
    );
    let (code, out, err) = train(&data, &model, &["--validation-fraction", "0.25"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("samples: 1500") && out.contains("validation samples: 500"));
    assert_eq!(header(&model)["data"]["validation"]["fraction"], 0.25);
    for bad in [
        &["--validation", s(&other), "--validation-fraction", "0.2"][..],
        &["--validation", s(&other), "--folds", "3"],
        &["--folds", "1"],
    ] {
        let (code, _, err) = train(&data, &model, bad);
        assert_eq!(code, 2, "{bad:?}: {err}");
    }
}

#[test]
fn nominal_trains_the_identified_residual_and_grow_needs_it() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path(), "a", 2.0, 1);
    let ident = dir.path().join("ident.json");
    let mut args = vec!["identify", "--data", s(&data), "--out", s(&ident)];
    args.extend_from_slice(&ARM);
    let (code, _, err) = admittance(&args);
    assert_eq!(code, 0, "{err}");
    let model = dir.path().join("r.broad");
    let (code, _, err) = train(&data, &model, &["--nominal", s(&ident)]);
    assert_eq!(code, 0, "{err}");
    let h = header(&model);
    assert_eq!(h["data"]["target"]["kind"], "identified_residual");
    let checksum = format!("{:016x}", fnv1a64(&std::fs::read(&ident).unwrap()));
    assert_eq!(h["data"]["target"]["checksum"], checksum.as_str());

    let grown = dir.path().join("g.broad");
    let grow = |extra: &[&str]| {
        let mut args = vec![
            "grow",
            "--model",
            s(&model),
            "--data",
            s(&data),
            "--out",
            s(&grown),
            "--nodes",
            "5",
        ];
        args.extend_from_slice(extra);
        admittance(&args)
    };
    let (code, _, err) = grow(&ARM);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--nominal"), "{err}");
    let mut with = ARM.to_vec();
    with.extend_from_slice(&["--nominal", s(&ident)]);
    let (code, out, err) = grow(&with);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("nodes: 25 (+5)"), "{out}");
    // Another identification file (here: the same with a byte more) is refused.
    let changed = dir.path().join("ident2.json");
    let mut bytes = std::fs::read(&ident).unwrap();
    bytes.push(b'\n');
    std::fs::write(&changed, bytes).unwrap();
    let mut with = ARM.to_vec();
    with.extend_from_slice(&["--nominal", s(&changed)]);
    let (code, _, err) = grow(&with);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("checksum"), "{err}");
}
