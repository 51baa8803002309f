//! A link planted where the tool writes never makes it write through that link.

use admittance_files::{write_atomic, write_atomic_with};
use std::os::unix::fs::symlink;

#[test]
fn a_link_planted_at_the_old_predictable_temporary_name_is_not_followed() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let out = dir.path().join("ident.json");
    // The names the tool used to write through: `.NAME.tmp-PID` and `.NAME.tmpPID`.
    let pid = std::process::id();
    for name in [
        format!(".ident.json.tmp-{pid}"),
        format!(".ident.json.tmp{pid}"),
    ] {
        symlink(&victim, dir.path().join(name)).unwrap();
    }
    write_atomic(&out, b"new").unwrap();
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    assert!(!std::fs::symlink_metadata(&out)
        .unwrap()
        .file_type()
        .is_symlink());
}

#[test]
fn a_link_at_the_destination_is_refused_and_its_target_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let out = dir.path().join("report.md");
    symlink(&victim, &out).unwrap();
    let e = write_atomic(&out, b"new").unwrap_err();
    assert!(e.to_string().contains("symbolic link"), "{e}");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert!(std::fs::symlink_metadata(&out)
        .unwrap()
        .file_type()
        .is_symlink());
    // A dangling link is refused too (the tool would otherwise create its target).
    let dangling = dir.path().join("dangling.csv");
    symlink(dir.path().join("nowhere"), &dangling).unwrap();
    assert!(write_atomic(&dangling, b"x").is_err());
    assert!(!dir.path().join("nowhere").exists());
}

#[test]
fn a_regular_file_is_replaced_and_no_temporary_file_is_left() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.csv");
    std::fs::write(&out, "old").unwrap();
    write_atomic(&out, b"new").unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    let failed = write_atomic_with(&out, |w| {
        use std::io::Write;
        w.write_all(b"half")?;
        Err::<(), _>(std::io::Error::other("stopped"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("a.csv")]);
}

#[test]
fn a_folder_or_fifo_at_the_destination_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    assert!(write_atomic(&sub, b"x")
        .unwrap_err()
        .to_string()
        .contains("a folder"));
    let fifo = dir.path().join("pipe");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    assert!(write_atomic(&fifo, b"x")
        .unwrap_err()
        .to_string()
        .contains("FIFO"));
}
