//! A fixed-capacity message buffer: the real-time path records its errors without
//! allocating (formatting integers and `&str` into it does not allocate).

use std::fmt;

/// Capacity of a handle's error message (bytes); longer messages are cut at a character
/// boundary.
pub(crate) const ERROR_CAPACITY: usize = 1024;

/// A message of at most [`ERROR_CAPACITY`] bytes of UTF-8.
pub(crate) struct ErrorBuf {
    bytes: [u8; ERROR_CAPACITY],
    len: usize,
}

impl ErrorBuf {
    /// Empty.
    pub fn new() -> Self {
        Self {
            bytes: [0; ERROR_CAPACITY],
            len: 0,
        }
    }

    /// Forgets the message.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// The message.
    pub fn as_str(&self) -> &str {
        // Only whole characters are ever appended (see `write_str`).
        std::str::from_utf8(&self.bytes[..self.len]).unwrap_or("")
    }

    /// Replaces the message (cut to the capacity).
    pub fn set(&mut self, args: fmt::Arguments<'_>) {
        self.clear();
        let _ = fmt::Write::write_fmt(self, args);
    }
}

impl fmt::Write for ErrorBuf {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let room = ERROR_CAPACITY - self.len;
        let mut k = s.len().min(room);
        while !s.is_char_boundary(k) {
            k -= 1;
        }
        self.bytes[self.len..self.len + k].copy_from_slice(&s.as_bytes()[..k]);
        self.len += k;
        Ok(())
    }
}

/// Copies `msg` into a C buffer of `len` bytes, NUL-terminated and cut at a character
/// boundary when it does not fit; returns the length of the whole message (bytes, without
/// the NUL), as `snprintf` does.
///
/// # Safety
/// `buf` is null or valid for `len` bytes of writes.
pub(crate) unsafe fn copy_to_c(msg: &str, buf: *mut std::os::raw::c_char, len: usize) -> usize {
    if !buf.is_null() && len > 0 {
        let mut k = msg.len().min(len - 1);
        while !msg.is_char_boundary(k) {
            k -= 1;
        }
        // SAFETY: the caller guarantees `buf` is valid for `len` bytes; `k + 1 <= len`, and
        // `msg` (Rust memory) cannot overlap a buffer the caller owns for writing.
        unsafe {
            std::ptr::copy_nonoverlapping(msg.as_ptr(), buf.cast::<u8>(), k);
            *buf.add(k) = 0;
        }
    }
    msg.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuts_at_character_boundaries() {
        let mut e = ErrorBuf::new();
        let long = "é".repeat(ERROR_CAPACITY); // 2 bytes each
        e.set(format_args!("x{long}"));
        assert_eq!(e.as_str().len(), ERROR_CAPACITY - 1);
        let mut buf = [0 as std::os::raw::c_char; 4];
        // SAFETY: `buf` is 4 bytes.
        let n = unsafe { copy_to_c("aéb", buf.as_mut_ptr(), buf.len()) };
        assert_eq!(n, 4);
        assert_eq!(buf.map(|c| c as u8), [b'a', 0xc3, 0xa9, 0]);
        // SAFETY: `buf` is 4 bytes; 2 are offered.
        unsafe { copy_to_c("aéb", buf.as_mut_ptr(), 2) };
        assert_eq!(
            buf[..2].iter().map(|&c| c as u8).collect::<Vec<_>>(),
            [b'a', 0]
        );
    }
}
