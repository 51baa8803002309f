//! File names inside a run folder (docs/outputs.md, "What a run writes").

/// The metrics of every variant; its presence, with the right `format`, marks a complete
/// run folder ([`crate::summary`]).
pub const SUMMARY: &str = "summary.json";
/// The scenario as run: the file with every `--set` override and `--seed` folded in.
pub const SCENARIO: &str = "scenario.toml";
/// Every variant's settings as the run applied them ([`crate::settings`]).
pub const SETTINGS: &str = "settings.json";
/// The report as Markdown.
pub const REPORT_MD: &str = "report.md";
/// The report as one self-contained HTML page.
pub const REPORT_HTML: &str = "report.html";
/// The figures folder (PNG and SVG).
pub const FIGURES: &str = "figures";
/// The MCAP recording for Foxglove.
pub const RECORDING: &str = "recording.mcap";

/// The time series of a variant: `VARIANT.csv`.
pub fn series(variant: &str) -> String {
    format!("{variant}.csv")
}

/// The free-motion recording of a variant: `free_motion.csv` when the run has one
/// variant, `free_motion_VARIANT.csv` otherwise.
pub fn free_motion(variant: &str, variants_in_run: usize) -> String {
    if variants_in_run == 1 {
        "free_motion.csv".to_string()
    } else {
        format!("free_motion_{variant}.csv")
    }
}

/// Whether a file name is a free-motion recording.
pub fn is_free_motion(name: &str) -> bool {
    name.starts_with("free_motion") && name.ends_with(".csv")
}

/// A learned observer's network on its validation data: `validation_VARIANT.csv`.
pub fn observer_validation(variant: &str) -> String {
    format!("validation_{variant}.csv")
}

/// The contact floor a variant detected with (`[contact]`): `contact_floor_VARIANT.json`,
/// a contact-floor file (`admittance calibrate-contact`'s format).
pub fn contact_floor(variant: &str) -> String {
    format!("contact_floor_{variant}.json")
}

/// The f network's per-node weight norms (dynamic nodes): `weights_VARIANT.csv`.
pub fn node_weights(variant: &str) -> String {
    format!("weights_{variant}.csv")
}
