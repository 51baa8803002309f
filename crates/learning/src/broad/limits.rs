//! The limits a fit or a growth must stay within ([`Budget`], checked by
//! `check_budget`), and how byte counts are written in messages.

use serde::{Deserialize, Serialize};

/// Default memory limit: 8 GB (8 x 10^9 bytes), below the free memory of a 16 GB
/// workstation and a third of the CI machine; about 18,000 nodes.
pub const DEFAULT_MAX_MEMORY_BYTES: u64 = 8_000_000_000;

/// Default work limit: 10^14 floating-point operations, about three hours at the 9 to
/// 13 GFLOP/s that fits reach on the two cores of the test machine (the paper's fit of
/// 1000 nodes on 450,000 rows needs about 5 x 10^11).
pub const DEFAULT_MAX_FLOP: f64 = 1e14;

/// Limits a fit or a growth must stay within (`check_budget`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Budget {
    /// Largest estimated peak memory, bytes.
    pub max_memory_bytes: u64,
    /// Largest estimated work, floating-point operations.
    pub max_flop: f64,
}

impl Default for Budget {
    fn default() -> Self {
        Self {
            max_memory_bytes: DEFAULT_MAX_MEMORY_BYTES,
            max_flop: DEFAULT_MAX_FLOP,
        }
    }
}

impl Budget {
    /// No memory or work limit (the structural checks of `check_budget` still apply).
    pub fn unlimited() -> Self {
        Self {
            max_memory_bytes: u64::MAX,
            max_flop: f64::INFINITY,
        }
    }
}

/// `12.3 GB` (10^9 bytes), `450 MB`; `None` (a count beyond 64 bits): `more than 18 EB`.
pub fn format_bytes(bytes: Option<u64>) -> String {
    let Some(b) = bytes else {
        return "more than 18 EB (the count overflows 64 bits)".into();
    };
    let b = b as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.0} MB", b / 1e6)
    } else {
        format!("{:.0} kB", (b / 1e3).max(1.0))
    }
}
