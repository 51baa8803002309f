//! The contract of a run folder, the one place that defines it: what `admittance run`
//! writes (the `scenario` crate) and what `admittance report` reads (the `report` crate).
//!
//! * [`files`]: the file names of a run folder;
//! * [`columns`]: the time-series columns of `VARIANT.csv` and the other CSV files;
//! * [`metrics`]: every metric of `summary.json` with its unit, whether it is per joint
//!   and the window it is computed over;
//! * [`summary`]: the format marker and version of `summary.json`, and [`summary::is_run_folder`],
//!   which tells a folder this tool wrote from anything else (a user's folder is never
//!   replaced by `run --out`);
//! * [`health`]: the rules a run is judged by, their thresholds and the verdicts recorded in
//!   `summary.json`;
//! * [`settings`]: `settings.json`, every variant's settings as the run applied them (the
//!   deadzone, environment windows, evaluation window, saturation bounds, kinds);
//! * [`write_atomic`]: files are written through an exclusively created temporary sibling
//!   with an unpredictable name and a rename (`admittance_files`);
//!   [`writer`]: a whole run folder through a hidden partial sibling and a rename, and its
//!   CSV time series.
//!
//! docs/outputs.md describes the same contract for users.

#![warn(missing_docs)]

pub mod columns;
pub mod files;
pub mod health;
pub mod metrics;
pub mod settings;
pub mod summary;
pub mod writer;

mod atomic;

pub use atomic::{commit_guard, write_atomic};
