//! Replacing a folder in one step: the new one and the old one swap names at once, so that
//! whatever stops the process, the destination holds one complete version or the other.

use std::path::Path;

/// Swaps the entries at `a` and `b` atomically (Linux `renameat2` with `RENAME_EXCHANGE`):
/// `Ok(true)` when they swapped; `Ok(false)` when the system or its file system cannot
/// (other platforms, kernels before 3.15, some network file systems), for the caller to
/// rename in two steps instead; an error otherwise (either missing, no permission).
pub fn exchange(a: &Path, b: &Path) -> std::io::Result<bool> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::ffi::OsStrExt;
        let a = std::ffi::CString::new(a.as_os_str().as_bytes())?;
        let b = std::ffi::CString::new(b.as_os_str().as_bytes())?;
        // SAFETY: both paths are NUL-terminated strings that outlive the call, and the
        // call reads nothing else of this process's memory.
        let swapped = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                a.as_ptr(),
                libc::AT_FDCWD,
                b.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if swapped == 0 {
            return Ok(true);
        }
        let e = std::io::Error::last_os_error();
        match e.raw_os_error() {
            Some(libc::EINVAL | libc::ENOSYS | libc::EOPNOTSUPP) => Ok(false),
            _ => Err(e),
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (a, b);
        Ok(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_folders_swap_names_and_a_missing_one_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::fs::create_dir(&a).unwrap();
        std::fs::create_dir(&b).unwrap();
        std::fs::write(a.join("new.csv"), "new").unwrap();
        std::fs::write(b.join("old.csv"), "old").unwrap();
        match exchange(&a, &b) {
            Ok(true) => {
                assert!(b.join("new.csv").is_file() && a.join("old.csv").is_file());
                assert!(!a.join("new.csv").exists() && !b.join("old.csv").exists());
            }
            // A file system that cannot swap: nothing moved.
            Ok(false) => assert!(a.join("new.csv").is_file() && b.join("old.csv").is_file()),
            Err(e) => panic!("{e}"),
        }
        let missing = dir.path().join("missing");
        let result = exchange(&a, &missing);
        assert!(!matches!(result, Ok(true)), "{result:?}");
        assert!(a.is_dir());
    }
}
