//! Model files: versioned, checksummed, atomically written; every bad file is an error
//! naming the file, never a panic.

use crate::broad_common;
use admittance_learning::broad::{
    fit, fnv1a64, BroadError, BroadModel, Dataset, FrictionFeatures, GrowthSpec, FORMAT_NAME,
};
use broad_common::{data, small_config};
use std::path::{Path, PathBuf};

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("broad-io-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn model() -> (BroadModel, Vec<f64>, Vec<f64>) {
    let (x, y) = data(800, 51, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(25);
    cfg.lambda_grid = vec![1e-6];
    cfg.friction = FrictionFeatures {
        columns: vec![1],
        scales: vec![0.02, 0.3],
    };
    (fit(&train, None, &cfg).unwrap().0, x, y)
}

fn assert_same_predictions(a: &BroadModel, b: &BroadModel, x: &[f64]) {
    let (mut oa, mut ob) = ([0.0; 2], [0.0; 2]);
    let (mut wa, mut wb) = (a.workspace(), b.workspace());
    for r in x.chunks(3).take(100) {
        a.predict_into(r, &mut oa, &mut wa).unwrap();
        b.predict_into(r, &mut ob, &mut wb).unwrap();
        assert_eq!(oa, ob);
    }
}

#[test]
fn save_load_round_trip_is_exact_and_keeps_growth_state() {
    let dir = tmpdir("roundtrip");
    let path = dir.join("observer.brbf");
    let (m, x, y) = model();
    m.save(&path).unwrap();
    let l = BroadModel::load(&path).unwrap();
    assert_eq!(l.weights(), m.weights());
    assert_eq!(l.nodes(), m.nodes());
    assert_eq!(l.standardiser(), m.standardiser());
    assert_eq!(l.friction(), m.friction());
    assert_eq!((l.lambda(), l.lambda_rel()), (m.lambda(), m.lambda_rel()));
    assert!(l.has_growth_state());
    assert_eq!(l.training_samples(), Some(800));
    assert_same_predictions(&m, &l, &x);
    // Growth after loading equals growth before saving.
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(25);
    cfg.lambda_grid = vec![1e-6];
    let spec = GrowthSpec::KMeansPlusPlus { count: 5, seed: 4 };
    let (mut g1, mut g2) = (m.clone(), l);
    g1.grow(&train, &spec, &cfg).unwrap();
    g2.grow(&train, &spec, &cfg).unwrap();
    assert_eq!(g1.weights(), g2.weights());
    // Overwrite in place with the grown model; no temporary files remain.
    g1.save(&path).unwrap();
    assert_eq!(BroadModel::load(&path).unwrap().n_nodes(), 30);
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("observer.brbf")]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn stripped_model_round_trip() {
    let (mut m, x, _) = model();
    m.strip_growth_state();
    let bytes = m.to_bytes();
    let l = BroadModel::from_bytes(&bytes, "mem").unwrap();
    assert!(!l.has_growth_state());
    assert_same_predictions(&m, &l, &x);
    // Much smaller without the Gram.
    let (full, _, _) = model();
    assert!(bytes.len() * 3 < full.to_bytes().len());
}

#[test]
fn file_header_names_format_and_version() {
    let (m, _, _) = model();
    let bytes = m.to_bytes();
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + h_len]).unwrap();
    assert_eq!(header["format"], FORMAT_NAME);
    assert_eq!(header["format_version"], 2);
    assert!(header["written_by"]
        .as_str()
        .unwrap()
        .starts_with("admittance-learning "));
    // What the fit recorded; what only the caller knows is null until set.
    assert_eq!(header["fit"]["nodes"], 25);
    assert_eq!(header["fit"]["training_rows"], 800);
    assert_eq!(header["fit"]["centres"]["seed"], 11);
    assert!(header["arm"].is_null() && header["data"].is_null());
    assert_eq!(header["d_in"], 3);
    assert_eq!(header["nodes"], 25);
    let n = bytes.len();
    assert_eq!(
        u64::from_le_bytes(bytes[n - 8..].try_into().unwrap()),
        fnv1a64(&bytes[..n - 8])
    );
}

fn expect_format_error(r: Result<BroadModel, BroadError>, path: &Path, needle: &str) {
    match r {
        Err(e @ BroadError::Format { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains(&path.display().to_string()), "{msg}");
            assert!(msg.contains(needle), "expected {needle:?} in {msg:?}");
        }
        other => panic!("expected a format error containing {needle:?}, got {other:?}"),
    }
}

#[test]
fn corrupted_file_is_a_checksum_error() {
    let dir = tmpdir("corrupt");
    let path = dir.join("m.brbf");
    let (m, _, _) = model();
    m.save(&path).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x10;
    std::fs::write(&path, &bytes).unwrap();
    match BroadModel::load(&path) {
        Err(e @ BroadError::Checksum { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("m.brbf") && msg.contains("checksum"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn truncated_files_are_errors() {
    let (m, _, _) = model();
    let bytes = m.to_bytes();
    let p = Path::new("/models/truncated.brbf");
    for len in [
        0,
        3,
        8,
        12,
        16,
        40,
        bytes.len() / 2,
        bytes.len() - 9,
        bytes.len() - 1,
    ] {
        expect_format_error(BroadModel::from_bytes(&bytes[..len], p), p, "truncated");
    }
    let mut longer = bytes.clone();
    longer.extend_from_slice(&[0u8; 5]);
    expect_format_error(BroadModel::from_bytes(&longer, p), p, "trailing");
}

#[test]
fn wrong_version_format_or_magic() {
    let (m, _, _) = model();
    let bytes = m.to_bytes();
    let p = Path::new("future.brbf");
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let text = String::from_utf8_lossy(&bytes[16..16 + h_len]).to_string();
    assert!(text.contains("\"format_version\":2"), "{text}");
    let replace = |from: &str, to: &str| -> Vec<u8> {
        assert_eq!(from.len(), to.len());
        let mut b = bytes.clone();
        let pos = b
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap();
        b[pos..pos + to.len()].copy_from_slice(to.as_bytes());
        b
    };
    match BroadModel::from_bytes(&replace("\"format_version\":2", "\"format_version\":7"), p) {
        Err(
            e @ BroadError::UnsupportedVersion {
                found: 7,
                supported: 2,
                ..
            },
        ) => {
            assert!(e.to_string().contains("future.brbf"));
            assert!(e.to_string().contains("reads versions 1 to 2"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    expect_format_error(
        BroadModel::from_bytes(&replace("admittance-broad-rbf", "admittance-other-rbf"), p),
        p,
        "format is",
    );
    let mut b = bytes.clone();
    b[0] = b'X';
    expect_format_error(BroadModel::from_bytes(&b, p), p, "bad magic");
    // Broken JSON header.
    let mut b = bytes.clone();
    b[16] = b'[';
    expect_format_error(BroadModel::from_bytes(&b, p), p, "corrupted header");
    // Header length pointing past the end.
    let mut b = bytes.clone();
    b[8..16].copy_from_slice(&u64::MAX.to_le_bytes());
    expect_format_error(BroadModel::from_bytes(&b, p), p, "truncated");
}

#[test]
fn missing_file_and_bad_directory_are_io_errors() {
    let p = Path::new("/nonexistent-dir-broad/model.brbf");
    match BroadModel::load(p) {
        Err(e @ BroadError::Io { .. }) => assert!(e.to_string().contains("model.brbf")),
        other => panic!("{other:?}"),
    }
    let (m, _, _) = model();
    match m.save(p) {
        Err(e @ BroadError::Destination { .. }) => {
            assert!(e.to_string().contains("nonexistent-dir-broad"), "{e}")
        }
        other => panic!("{other:?}"),
    }
}

/// Flipping any byte never panics and never loads silently.
#[test]
fn random_byte_flips_never_panic() {
    let (mut m, _, _) = model();
    m.strip_growth_state();
    let bytes = m.to_bytes();
    let p = Path::new("flip.brbf");
    let step = (bytes.len() / 400).max(1);
    for pos in (0..bytes.len()).step_by(step) {
        for mask in [0x01u8, 0x80] {
            let mut b = bytes.clone();
            b[pos] ^= mask;
            assert!(
                BroadModel::from_bytes(&b, p).is_err(),
                "flip at {pos} loaded"
            );
        }
    }
}
