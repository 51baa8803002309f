//! Scenarios: TOML files in `scenarios/`, one per experiment, with named variants; the
//! closed-loop runner; and the run folder it writes.

pub mod output;
pub mod runner;
pub mod source;
pub mod spec;
pub mod training;

pub use output::{run_scenario, RunSummary};
pub use runner::{run_variant, Progress, ProgressFn, RunOptions, Stage, TimeSeries, VariantRun};
pub use source::{Invalid, ScenarioError, ScenarioSource};
pub use spec::Scenario;
