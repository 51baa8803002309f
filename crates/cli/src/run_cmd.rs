//! `admittance run`: one scenario file, every variant (or one), into a run folder.

use std::path::PathBuf;

use admittance_sim::scenario::{output::RunError, run_scenario, RunOptions};
use clap::Args;

use crate::CliError;

#[derive(Args)]
pub struct RunArgs {
    /// Scenario file (TOML), e.g. scenarios/deadzone.toml.
    scenario: PathBuf,
    /// Output folder (replaced atomically when the run completes).
    #[arg(long)]
    out: PathBuf,
    /// Run only this variant.
    #[arg(long)]
    variant: Option<String>,
    /// Override a scenario value: --set section.key=value (repeatable; same validation as the file).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Seed of the sensor noise (overrides the scenario's).
    #[arg(long)]
    seed: Option<u64>,
    /// Print the summary JSON on stdout.
    #[arg(long)]
    json: bool,
    /// No progress output.
    #[arg(long)]
    quiet: bool,
}

pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let options = RunOptions {
        seed: args.seed,
        progress: None,
    };
    let quiet = args.quiet;
    let started = std::time::Instant::now();
    let summary = run_scenario(
        &args.scenario,
        &args.out,
        args.variant.as_deref(),
        &args.set,
        &options,
        |name, k, total| {
            if !quiet {
                eprintln!(
                    "[{}/{}] variant {name} ({:.1} s elapsed)",
                    k + 1,
                    total,
                    started.elapsed().as_secs_f64()
                );
            }
        },
        |_| Ok(()),
    )
    .map_err(|e| match e {
        RunError::Scenario(s) => CliError::input(s.to_string()),
        RunError::Finish(message) => CliError { code: 1, message },
        io @ RunError::Io { .. } => CliError {
            code: 1,
            message: io.to_string(),
        },
    })?;
    if args.json {
        crate::write_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&summary.json).unwrap_or_default()
        ));
    } else if !quiet {
        eprintln!(
            "wrote {} ({:.1} s)",
            summary.out_dir.display(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
