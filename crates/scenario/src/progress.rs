//! Run options that are not part of the scenario file, and progress reports.

use std::sync::Arc;

/// What a long-running stage reports to a progress display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Simulating the closed loop of a variant (`done`/`total` in control steps).
    Simulate,
    /// Simulating free motion to collect an observer's training data (control steps).
    TrainingData,
    /// Training an observer network (`done`/`total` in phases).
    Train,
}

/// One progress report: which variant, which stage, how far.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    /// The variant being run (`"base"` without variants).
    pub variant: &'a str,
    /// The stage.
    pub stage: Stage,
    /// Units done so far.
    pub done: u64,
    /// Units in the stage.
    pub total: u64,
}

/// A progress callback (called at most about a hundred times per stage).
pub type ProgressFn = Arc<dyn Fn(Progress<'_>) + Send + Sync>;

/// Options of a run that are not part of the scenario file.
#[derive(Clone, Default)]
pub struct RunOptions {
    /// Overrides the scenario's seed (sensor noise).
    pub seed: Option<u64>,
    /// Progress display, if any.
    pub progress: Option<ProgressFn>,
    /// Refusal limits checked before a run starts (docs/outputs.md, "Limits").
    pub limits: crate::limits::Limits,
    /// Never train or identify: a network or identification not in the training cache is
    /// an error naming the command that makes it (`admittance deploy`).
    pub cache_only: bool,
}

impl std::fmt::Debug for RunOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunOptions")
            .field("seed", &self.seed)
            .field("progress", &self.progress.is_some())
            .field("limits", &self.limits)
            .field("cache_only", &self.cache_only)
            .finish()
    }
}

impl RunOptions {
    /// Reports progress when a callback is set.
    pub fn report(&self, variant: &str, stage: Stage, done: u64, total: u64) {
        if let Some(p) = &self.progress {
            p(Progress {
                variant,
                stage,
                done,
                total,
            });
        }
    }
}
