//! Writing model files: only to a new name or over a model file, atomically; anything else
//! (a folder, a FIFO, a device behind a link, a user's other file) is refused and left as
//! it was. Before, `save` renamed its temporary file over whatever was at the path.

use crate::broad_common;
use admittance_learning::broad::{check_model_destination, fit, BroadError, BroadModel, Dataset};
use broad_common::{data, small_config};
use std::path::{Path, PathBuf};

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("broad-dest-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn model() -> BroadModel {
    let (x, y) = data(300, 8, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(10);
    cfg.lambda_grid = vec![1e-6];
    fit(&train, None, &cfg).unwrap().0
}

fn expect_refused(m: &BroadModel, path: &Path, needle: &str) {
    for result in [check_model_destination(path).map(|_| ()), m.save(path)] {
        match result {
            Err(e @ BroadError::Destination { .. }) => {
                let msg = e.to_string();
                assert!(msg.contains(&path.display().to_string()), "{msg}");
                assert!(msg.contains(needle), "expected {needle:?} in {msg:?}");
            }
            other => panic!("{}: expected a refusal, got {other:?}", path.display()),
        }
    }
}

/// Files in `dir` (temporary files would show up here).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn new_names_and_model_files_are_written() {
    let dir = tmpdir("ok");
    let m = model();
    let path = dir.join("m.broad");
    assert_eq!(check_model_destination(&path).unwrap(), path);
    m.save(&path).unwrap();
    // Over a model file (even one corrupted after its magic bytes).
    let mut bytes = std::fs::read(&path).unwrap();
    bytes.truncate(40);
    std::fs::write(&path, &bytes).unwrap();
    m.save(&path).unwrap();
    assert!(BroadModel::load(&path).is_ok());
    assert_eq!(names(&dir), ["m.broad"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_users_file_or_a_folder_is_never_replaced() {
    let dir = tmpdir("user");
    let m = model();
    let csv = dir.join("free_motion.csv");
    std::fs::write(&csv, "t,q.a\n0,1\n").unwrap();
    expect_refused(&m, &csv, "is not a model file; refusing to replace it");
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), "t,q.a\n0,1\n");
    let empty = dir.join("empty.broad");
    std::fs::write(&empty, "").unwrap();
    expect_refused(&m, &empty, "not a model file");
    let sub = dir.join("models");
    std::fs::create_dir(&sub).unwrap();
    std::fs::write(sub.join("keep.txt"), "mine").unwrap();
    expect_refused(&m, &sub, "is a folder");
    assert_eq!(
        std::fs::read_to_string(sub.join("keep.txt")).unwrap(),
        "mine"
    );
    let trailing = PathBuf::from(format!("{}/", dir.join("new").display()));
    expect_refused(&m, &trailing, "names a folder");
    expect_refused(&m, &dir.join("missing/m.broad"), "its folder");
    assert_eq!(names(&dir), ["empty.broad", "free_motion.csv", "models"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(unix)]
#[test]
fn links_fifos_and_devices() {
    use std::os::unix::fs::{symlink, FileTypeExt};
    let dir = tmpdir("special");
    let m = model();
    // A link to a model file: the file it points to is replaced, the link stays.
    let real = dir.join("real.broad");
    m.save(&real).unwrap();
    let before = std::fs::read(&real).unwrap();
    let link = dir.join("link.broad");
    symlink(&real, &link).unwrap();
    let mut grown = m.clone();
    grown.strip_growth_state();
    grown.save(&link).unwrap();
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_ne!(std::fs::read(&real).unwrap(), before);
    assert!(!BroadModel::load(&real).unwrap().has_growth_state());
    // A link to a device: refused, the link and the device untouched.
    let dev = dir.join("dev.broad");
    symlink("/dev/null", &dev).unwrap();
    expect_refused(&m, &dev, "is a device (a link to /dev/null)");
    assert!(std::fs::symlink_metadata(&dev)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    // A dangling link.
    let dangling = dir.join("dangling.broad");
    symlink(dir.join("nowhere"), &dangling).unwrap();
    expect_refused(&m, &dangling, "symbolic link that cannot be followed");
    // A FIFO (a reader would block on it forever; a rename would hide it).
    let fifo = dir.join("pipe.broad");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        expect_refused(&m, &fifo, "is a FIFO");
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
    }
    let left = names(&dir);
    assert!(left.iter().all(|n| !n.contains(".tmp-")), "{left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
