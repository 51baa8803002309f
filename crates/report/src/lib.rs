//! The report of a run folder: the paper's figures (Figs 7-26, and hand-contact figures
//! for task-space runs) as PNG and SVG, `report.md`, a self-contained `report.html` and
//! `recording.mcap` (for Foxglove), all made from the files of the folder as the contract
//! of `admittance_runfolder` defines them, so that they can be regenerated at any time
//! with `admittance report DIR`.
//!
//! The report opens with the experiment's claim, this run's headline numbers beside the
//! paper's, and any warning (divergence, limits, saturation, faults, non-finite metrics,
//! samples the figures could not draw); docs/report.md says which figure is drawn from
//! which columns.
//!
//! ```no_run
//! let outcome = admittance_report::generate(
//!     std::path::Path::new("runs/deadzone"),
//!     &admittance_report::Options::default(),
//! )?;
//! println!("{} figures", outcome.figures.len());
//! # Ok::<(), admittance_report::ReportError>(())
//! ```

#![warn(missing_docs)]

mod arm;
mod document;
mod experiment;
mod figures;
mod folder;
mod generate;
mod number;
mod plot;
mod recording;
mod scenario_file;
mod table;
mod values;

pub use arm::load_arm;
pub use experiment::Experiment;
pub use figures::{PaperFigure, PAPER_FIGURES};
pub use folder::{RunFolder, Variant};
pub use generate::{generate, Options, Outcome};
pub use recording::RECORDING_FORMAT_VERSION;
pub use table::Table;

/// A failure to make the report.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file of the run folder is missing or malformed.
    #[error("{path}: {message}")]
    Input {
        /// The file.
        path: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// Writing an output failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The error.
        source: std::io::Error,
    },
    /// Drawing a figure or writing the recording failed.
    #[error("{0}")]
    Output(String),
}
