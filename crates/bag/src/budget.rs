//! The import's memory budget, which the streaming, the resampling and the import check.

/// The memory budget: the values decoded from the bag (checked while it is streamed) and
/// the table's rows x columns (t, the four joint blocks, the label columns and the stamp,
/// checked before the resampling allocates anything) at most this many each (50 million
/// f64 = 400 MB).
pub const MAX_TABLE_VALUES: u128 = 50_000_000;
