//! Only regular files are read, and never more than the stated bound.

use admittance_files::{read_regular, read_regular_text, TEXT_LIMIT};
use std::time::{Duration, Instant};

#[test]
fn a_fifo_is_refused_at_once_instead_of_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("robot.urdf");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let start = Instant::now();
    let e = read_regular_text(&fifo, TEXT_LIMIT).unwrap_err();
    assert!(start.elapsed() < Duration::from_secs(5));
    assert!(
        e.to_string()
            .contains("FIFO (named pipe), not a regular file"),
        "{e}"
    );
}

#[test]
fn a_device_is_refused() {
    let e = read_regular(std::path::Path::new("/dev/zero"), TEXT_LIMIT).unwrap_err();
    assert!(e.to_string().contains("a device"), "{e}");
}

#[test]
fn a_file_over_the_bound_is_refused_with_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.csv");
    std::fs::write(&big, vec![b'1'; 3000]).unwrap();
    let e = read_regular(&big, 1024).unwrap_err();
    assert!(e.to_string().contains("more than the 1024 bytes"), "{e}");
    assert_eq!(read_regular(&big, 4096).unwrap().len(), 3000);
}

#[test]
fn a_link_to_a_regular_file_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a.toml");
    std::fs::write(&file, "x = 1\n").unwrap();
    let link = dir.path().join("b.toml");
    std::os::unix::fs::symlink(&file, &link).unwrap();
    assert_eq!(read_regular_text(&link, TEXT_LIMIT).unwrap(), "x = 1\n");
}
