//! Scenarios of `admittance`: the TOML files in `scenarios/` (one per experiment, with
//! named variants), the runner that steps an `admittance_loop::ClosedLoop` against the
//! simulated plant and gathers the metrics, the training of the learned observers (with a
//! cache), and the run folder it writes.
//!
//! * [`ScenarioSource`]: a scenario file parsed once, every key with its position; a
//!   variant resolves to a typed [`Scenario`], and every error ([`ScenarioError`]) names the
//!   file, the line and the key.
//! * [`Scenario::loop_config`]: the scenario's `[controller]`, `[admittance]`,
//!   `[task_admittance]` and `[observer]` tables, an `admittance_loop::LoopConfig` from
//!   which a variant's loop is built (`ClosedLoop::from_config`).
//! * [`run_variant`], [`run_scenario`]: run a variant / every variant into a run folder
//!   (`admittance_runfolder` defines its files, columns and metrics).
//! * [`FreeMotionData`]: the free-motion data format and its validating loader.
//!
//! ```no_run
//! use admittance_scenario::{run_variant, RunOptions, ScenarioSource};
//! let path = std::path::Path::new("scenarios/deadzone.toml");
//! let mut source = ScenarioSource::load(path).unwrap();
//! source.set("duration=2").unwrap();
//! let run = run_variant(&source, path, Some("nn_compensated"), &RunOptions::default()).unwrap();
//! println!("{:?}", run.metrics.tracking_rmse);
//! ```

#![warn(missing_docs)]
// Scenario errors carry the file, line, key and hint by value; they are the cold path,
// returned once per bad file, so their size is not worth a box on every signature.
#![allow(clippy::result_large_err)]
// Bounds are written `!(x <= bound)` on purpose: a NaN fails them.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod assemble;
mod budget;
mod contact;
mod contact_run;
mod contact_score;
mod context;
mod error;
mod even_sampling;
mod external;
mod free_motion;
mod gate_stage;
mod gather;
mod hand;
mod hand_paths;
mod identification_warnings;
mod identify_recording;
mod limits;
mod metrics;
mod node_events;
mod progress;
mod recorder;
mod robot;
mod run_folder;
mod runner;
mod series;
mod settings;
mod source;
mod spec;
mod step_gather;
mod training;
mod trajectory;

pub use admittance_loop::Divergence;
pub use assemble::gain_warnings;
pub use contact::{
    calibrate_contact_on, calibrate_contact_on_all, count_false_alarms, detect, floor_of_estimates,
    momentum_estimates, FalseAlarms, FreeMotionEstimates, CONTACT_WARM_UP_S,
};
pub use contact_score::ContactMetrics;
pub use error::ScenarioError;
pub use even_sampling::{evenly_sampled, Resampling};
pub use external::{ExternalVariant, PlantStep};
pub use free_motion::{observer_training_arrays, FreeMotionData, FreeMotionError, DERIVED_NOTE};
pub use identification_warnings::identification_warnings;
pub use identify_recording::{
    conditioning_step_response_s, identify_recording, sample_rate_hz, ConditionedSamples,
    CutoffTrial, CUTOFF_CANDIDATES_HZ,
};
pub use limits::Limits;
pub use metrics::{DynamicNodeMetrics, HandMetrics, ObserverTrainingMetrics, VariantMetrics};
pub use progress::{Progress, ProgressFn, RunOptions, Stage};
pub use robot::{deployable, Deployable};
pub use run_folder::{
    check_out_dir, remove_stale_partials, run_scenario, run_scenario_variants,
    write_external_run_folder, write_series_csv, RunError, RunSummary, STOPPING_RULES,
};
pub use runner::{run_variant, VariantRun};
pub use series::{TimeSeries, NODE_WEIGHT_INTERVAL};
pub use source::ScenarioSource;
pub use spec::{
    mid_range, ArmSpec, ContactSpec, DynamicNodesSpec, OutputSpec, RecordSpec, Scenario, SineSpec,
    TrainingSpec, TrajectorySpec,
};
pub use step_gather::Desired;
pub use training::{TrainedNetwork, VALIDATION_DECIMATION};
pub use trajectory::Trajectory;
