//! `admittance report DIR`: regenerates the figures, report.md, report.html and
//! recording.mcap of an existing run folder from its files.

use std::path::PathBuf;

use admittance_report::ReportError;
use clap::Args;

use crate::progress::{self, Spinner};
use crate::CliError;

#[derive(Args)]
pub struct ReportArgs {
    /// A run folder written by `admittance run`.
    dir: PathBuf,
    /// Folder of the original scenario file, to find its URDF (for Fig 7); default: the run
    /// folder, then ./scenarios.
    #[arg(long)]
    scenario_dir: Option<PathBuf>,
    /// Skip the MCAP recording.
    #[arg(long)]
    no_recording: bool,
    /// No progress or summary output.
    #[arg(long)]
    quiet: bool,
}

pub fn report(args: &ReportArgs) -> Result<(), CliError> {
    let started = std::time::Instant::now();
    crate::interrupt::set_message(&crate::interrupt::report_message(&args.dir));
    // The temporary files and folder the report writes are removed on Ctrl-C by
    // `admittance_files::remove_pending` (their names are unpredictable).
    let spinner = Spinner::start(
        progress::wanted(args.quiet),
        "writing figures, report and recording",
    );
    let outcome = admittance_report::generate(
        &args.dir,
        &admittance_report::Options {
            scenario_dir: args.scenario_dir.clone(),
            recording: !args.no_recording,
            ..admittance_report::Options::default()
        },
    )
    .map_err(|e| match e {
        ReportError::Input { .. } => CliError::input(e.to_string()),
        other => CliError {
            code: 1,
            message: other.to_string(),
        },
    })?;
    drop(spinner);
    if !args.quiet {
        eprintln!(
            "wrote {} ({} figures, {} not available; {:.1} s)",
            args.dir.join("report.html").display(),
            outcome.figures.len(),
            outcome.unavailable.len(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
