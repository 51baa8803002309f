//! What training and loading refuse (issue 34, items 7, 8 and 9): zero nodes, a recording
//! without motion, a model file stating absurd sizes, a FIFO or a device as a model file.

use crate::broad_common;
use admittance_learning::broad::{fit, BroadError, BroadModel, Dataset};
use broad_common::{data, small_config};

#[test]
fn zero_nodes_are_refused_naming_the_setting() {
    let (x, y) = data(200, 3, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let e = fit(&train, None, &small_config(0)).unwrap_err();
    assert!(matches!(e, BroadError::Config(_)), "{e}");
    assert!(e.to_string().contains("nodes"), "{e}");
}

#[test]
fn a_recording_without_motion_is_refused_instead_of_scoring_zero() {
    let rows = 300;
    let x: Vec<f64> = (0..rows).flat_map(|_| [0.3, 0.0, -1.2]).collect();
    let y: Vec<f64> = (0..rows).flat_map(|_| [2.0, -0.5]).collect();
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let e = fit(&train, None, &small_config(10)).unwrap_err();
    assert!(matches!(e, BroadError::NoMotion { .. }), "{e}");
    assert!(e.to_string().contains("no motion"), "{e}");
    // One joint moving is motion.
    let x: Vec<f64> = (0..rows)
        .flat_map(|k| [0.3 + 0.01 * (k as f64).sin(), 0.0, -1.2])
        .collect();
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    assert!(!matches!(
        fit(&train, None, &small_config(10)),
        Err(BroadError::NoMotion { .. })
    ));
}

#[test]
fn a_model_file_stating_absurd_sizes_is_refused() {
    let (x, y) = data(400, 5, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let (model, _) = fit(&train, None, &small_config(12)).unwrap();
    let bytes = model.to_bytes();
    let len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let header = std::str::from_utf8(&bytes[16..16 + len]).unwrap();
    assert!(header.contains("\"nodes\":12"), "{header}");
    let edited = header.replace("\"nodes\":12", "\"nodes\":1000000000000");
    let mut out = bytes[..8].to_vec();
    out.extend_from_slice(&(edited.len() as u64).to_le_bytes());
    out.extend_from_slice(edited.as_bytes());
    out.extend_from_slice(&bytes[16 + len..]);
    let e = BroadModel::from_bytes(&out, "edited.bin")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("edited.bin") && e.contains("nodes = 1000000000000"),
        "{e}"
    );
}

#[test]
fn a_fifo_or_a_device_is_refused_as_a_model_file_without_blocking() {
    let dir = std::env::temp_dir().join(format!("broad-refusals-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("net.bin");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let e = BroadModel::load(&fifo).unwrap_err().to_string();
    assert!(e.contains("net.bin") && e.contains("FIFO"), "{e}");
    let e = BroadModel::load("/dev/zero").unwrap_err().to_string();
    assert!(e.contains("/dev/zero") && e.contains("device"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
