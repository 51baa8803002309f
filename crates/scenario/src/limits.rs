//! What a run may cost, checked before it starts (issue: `duration = 1e308` ran forever with
//! growing memory). A run needs `duration * rate_hz` plant steps and keeps
//! `steps / decimation` rows of `5 + 9 n` values per variant; both are refused beyond
//! these limits, with the number the run would need (docs/outputs.md, "Limits").

/// Refusal limits of a run; the defaults fit a 2-core, 24 GiB machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Plant steps per variant (default 2e9: about 10 hours of simulated time at 5 kHz,
    /// some hours of wall time).
    pub max_plant_steps: f64,
    /// Memory for the recorded series of one variant, bytes (default 8 GiB).
    pub max_series_bytes: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_plant_steps: 2e9,
            max_series_bytes: 8.0 * (1u64 << 30) as f64,
        }
    }
}
