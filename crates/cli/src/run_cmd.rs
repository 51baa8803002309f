//! `admittance run`: one scenario file, every variant (or one), into a run folder with its
//! report (figures, report.md, report.html, recording.mcap; see docs/outputs.md).

use std::path::PathBuf;

use admittance_runfolder::health;
use admittance_scenario::{run_scenario_variants, RunError, RunOptions};
use clap::Args;

use crate::progress::{self, RunProgress, Spinner};
use crate::CliError;

/// Exit code of a run that finished and wrote its folder but broke a health rule of
/// severity failure (hand error, effort saturation, estimate beyond the effort limit, ...).
pub const EXIT_HEALTH_FAILURE: u8 = 4;

#[derive(Args)]
pub struct RunArgs {
    /// Scenario file (TOML), e.g. scenarios/deadzone.toml.
    scenario: PathBuf,
    /// Output folder: a new folder, an empty one, or one an earlier `admittance run` wrote
    /// (replaced atomically when the run completes). Anything else is refused.
    #[arg(long)]
    out: PathBuf,
    /// Replace --out even when it is a folder this tool did not write.
    #[arg(long)]
    force: bool,
    /// Refuse a variant that needs more plant steps than this (duration x plant.rate_hz).
    #[arg(long, value_name = "STEPS", default_value_t = admittance_scenario::Limits::default().max_plant_steps)]
    max_plant_steps: f64,
    /// Refuse a variant whose recorded time series would take more memory than this (GiB).
    #[arg(long, value_name = "GIB", default_value_t = admittance_scenario::Limits::default().max_series_bytes / (1u64 << 30) as f64)]
    max_series_gb: f64,
    /// Run only this variant (repeatable: --variant a --variant b runs both, in that order).
    #[arg(long, value_name = "NAME")]
    variant: Vec<String>,
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
    /// Skip the MCAP recording (figures and reports are still written).
    #[arg(long)]
    no_recording: bool,
}

// The finish hook returns the runner's `RunError`, whatever its size.
#[allow(clippy::result_large_err)]
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let show = progress::wanted(args.quiet);
    let bar = show.then(RunProgress::new);
    for (flag, v) in [
        ("--max-plant-steps", args.max_plant_steps),
        ("--max-series-gb", args.max_series_gb),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(CliError::usage(format!(
                "{flag} {v}: must be a finite number > 0"
            )));
        }
    }
    let options = RunOptions {
        seed: args.seed,
        progress: bar.as_ref().map(RunProgress::callback),
        limits: admittance_scenario::Limits {
            max_plant_steps: args.max_plant_steps,
            max_series_bytes: args.max_series_gb * (1u64 << 30) as f64,
        },
        cache_only: false,
    };
    let started = std::time::Instant::now();
    let report_options = admittance_report::Options {
        scenario_dir: args.scenario.parent().map(|p| {
            if p.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                p.to_path_buf()
            }
        }),
        recording: !args.no_recording,
        ..admittance_report::Options::default()
    };
    crate::interrupt::set_message(&crate::interrupt::run_message(&args.out));
    crate::interrupt::remove_on_interrupt(
        crate::interrupt::run_partial(&args.out),
        Some(crate::interrupt::PARTIAL_MARKER),
    );
    let result = run_scenario_variants(
        &args.scenario,
        &args.out,
        &args.variant,
        &args.set,
        &options,
        args.force,
        |_, k, total| {
            if let Some(b) = &bar {
                b.variant_started(k, total);
            }
        },
        |partial| {
            if let Some(b) = &bar {
                b.finish();
            }
            let _spinner = Spinner::start(show, "writing figures, report and recording");
            admittance_report::generate(partial, &report_options)
                .map(|_| ())
                .map_err(|e| RunError::Finish(format!("writing the report: {e}")))
        },
    );
    if let Some(b) = &bar {
        b.finish();
    }
    let summary = result.map_err(|e| match e {
        RunError::Scenario(s) => CliError::input(s.to_string()),
        RunError::Refused(message) => CliError::usage(message),
        RunError::Finish(message) => CliError { code: 1, message },
        io @ RunError::Io { .. } => CliError {
            code: 1,
            message: io.to_string(),
        },
    })?;
    if let Some(warnings) = summary.json.get("warnings").and_then(|w| w.as_array()) {
        for w in warnings.iter().filter_map(|w| w.as_str()) {
            eprintln!("admittance: warning: {w}");
        }
    }
    // The health verdicts of every variant (docs/outputs.md, "Health"), worst first.
    let mut healthy = 0;
    for (variant, h) in &summary.health {
        if h.verdicts.is_empty() {
            healthy += 1;
        }
        for v in &h.verdicts {
            eprintln!("admittance: {}", health::console_line(variant, v));
        }
    }
    if !args.quiet && healthy == summary.health.len() {
        eprintln!(
            "health: every variant passed every rule ({} checked; thresholds in summary.json)",
            healthy
        );
    }
    if !summary.failures.is_empty() {
        if args.json {
            crate::write_stdout(&format!(
                "{}\n",
                serde_json::to_string_pretty(&summary.json).unwrap_or_default()
            ));
        }
        return Err(CliError {
            code: 1,
            message: format!(
                "the run failed: {}; the run folder {} holds what ran (report.md says where it stopped)",
                summary.failures.join("; "),
                summary.out_dir.display()
            ),
        });
    }
    if args.json {
        crate::write_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&summary.json).unwrap_or_default()
        ));
    }
    if !summary.health_failures.is_empty() {
        return Err(CliError {
            code: EXIT_HEALTH_FAILURE,
            message: format!(
                "the run finished but broke {} health rule(s) of severity failure (the `failure:` lines above; exit {EXIT_HEALTH_FAILURE}); the run folder {} holds everything (summary.json's `health`, report.md)",
                summary.health_failures.len(),
                summary.out_dir.display()
            ),
        });
    }
    if !args.json && !args.quiet {
        eprintln!(
            "wrote {} ({:.1} s): open {} in a browser",
            summary.out_dir.display(),
            started.elapsed().as_secs_f64(),
            summary.out_dir.join("report.html").display()
        );
    }
    Ok(())
}
