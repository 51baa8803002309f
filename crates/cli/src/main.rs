//! The `admittance` command: run the paper's experiments (`run`, `list`, `report`),
//! train the learned observer (`train`, `grow`) on free-motion data (recorded on a real arm:
//! `import` from a rosbag2 bag), identify the arm (`excite`, `identify`, `evaluate`), query an
//! arm's dynamics (`dynamics`, `model`), a starting set of its gains (`gains`), and run the
//! observer on a ROS 2 robot's topics (`ros2`, built with the `ros2` feature: crates/ros2,
//! docs/ros2.md).
//!
//! Exit codes:
//!
//! | code | meaning |
//! |---|---|
//! | 0 | success |
//! | 1 | a run failed (a variant diverged or a metric is not finite, writing outputs, a numerical failure in training, the report) |
//! | 2 | bad command-line arguments (usage) |
//! | 3 | a bad input file: URDF, scenario, free-motion data, model, run folder, bag, profile |
//! | 4 | `run`: the run finished and wrote its folder, but a variant broke a health rule of severity failure (docs/outputs.md, "Health") |
//! | 130 | interrupted (Ctrl-C): one line says so; nothing of the user's was changed |
//!
//! Every failure prints one or two lines on stderr naming the file, line, key or value,
//! and how to fix it.

mod calibrate_cmd;
mod deploy_cmd;
mod dynamics_cmd;
mod evaluate_cmd;
mod evaluate_contact;
mod excite_cmd;
mod gains_cmd;
mod identify_cmd;
mod import_cmd;
mod interrupt;
mod list_cmd;
mod progress;
mod report_cmd;
mod run_cmd;
mod train_cmd;
mod training_range;
mod training_speed;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Force-sensorless, learning-based admittance control of robot arms.
#[derive(Parser)]
#[command(name = "admittance", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate the rigid-body dynamics of a URDF chain at one state and print JSON.
    Dynamics(dynamics_cmd::DynamicsArgs),
    /// Print a readable summary of a URDF chain: joints, limits, masses.
    Model(dynamics_cmd::ModelArgs),
    /// Print a starting set of controller and admittance gains for an arm, from its model (TOML).
    Gains(gains_cmd::GainsArgs),
    /// Run a scenario (every variant) and write its run folder: summary.json, CSVs, figures,
    /// report.md, report.html, recording.mcap.
    Run(run_cmd::RunArgs),
    /// List the scenario files (name and description of each).
    List(list_cmd::ListArgs),
    /// Regenerate the figures, reports and recording of an existing run folder.
    Report(report_cmd::ReportArgs),
    /// Train the learned observer's flat RBF network on free-motion data and save it.
    Train(train_cmd::TrainArgs),
    /// Add nodes to a trained network (incremental growth) and save the result.
    Grow(train_cmd::GrowArgs),
    /// Write an excitation trajectory for identification (free-motion CSV; tau from the URDF).
    Excite(excite_cmd::ExciteArgs),
    /// Identify the arm's inertial parameters and joint friction from free motion.
    Identify(identify_cmd::IdentifyArgs),
    /// Run every estimator the given files allow over a free-motion recording and print its false torque.
    Evaluate(evaluate_cmd::EvaluateArgs),
    /// Contact and collision thresholds for a stated false-alarm rate, from free motion the
    /// identification did not fit (a contact-floor file).
    CalibrateContact(calibrate_cmd::CalibrateContactArgs),
    /// Free-motion training data (CSV) from a rosbag2 MCAP bag recorded on a real arm.
    Import(import_cmd::ImportArgs),
    /// Write the folder a robot's loop reads (adm_create, ros2 bridge, Python RobotLoop.load): loop.toml, URDF, identification, network, manifest. Never trains.
    Deploy(deploy_cmd::DeployArgs),
    /// ROS 2 without ROS: the observer on a robot's JointState topic, the estimate published
    /// (docs/ros2.md).
    #[cfg(feature = "ros2")]
    Ros2(admittance_ros2::cli::Ros2Args),
    /// ROS 2 without ROS (docs/ros2.md): not in this build (`--features ros2`).
    #[cfg(not(feature = "ros2"))]
    #[command(disable_help_flag = true)]
    Ros2 {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true, hide = true)]
        args: Vec<String>,
    },
}

/// A failure with its exit code and a short message.
pub struct CliError {
    pub code: u8,
    pub message: String,
}

impl CliError {
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            code: 2,
            message: message.into(),
        }
    }
    pub fn input(message: impl Into<String>) -> Self {
        Self {
            code: 3,
            message: message.into(),
        }
    }
}

/// Writes to stdout; a closed pipe (`| head`) is not an error worth a panic.
pub fn write_stdout(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

fn main() -> ExitCode {
    interrupt::install();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // One line: clap's first line (with the next one when it ends in a colon, as
            // in "required arguments were not provided:"), plus where to look for usage.
            let rendered = e.render().to_string();
            let mut lines = rendered.lines().map(str::trim).filter(|l| !l.is_empty());
            let mut first = lines
                .next()
                .unwrap_or("invalid arguments")
                .trim_start_matches("error: ")
                .to_string();
            if first.ends_with(':') {
                if let Some(next) = lines.next() {
                    first = format!("{first} {next}");
                }
            }
            eprintln!("admittance: {first} (see `admittance --help`)");
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Dynamics(args) => dynamics_cmd::dynamics(&args),
        Command::Model(args) => dynamics_cmd::model(&args),
        Command::Gains(args) => gains_cmd::gains(&args),
        Command::Run(args) => run_cmd::run(&args),
        Command::List(args) => list_cmd::list(&args),
        Command::Report(args) => report_cmd::report(&args),
        Command::Train(args) => train_cmd::train(&args),
        Command::Grow(args) => train_cmd::grow(&args),
        Command::Excite(args) => excite_cmd::excite(&args),
        Command::Identify(args) => identify_cmd::identify_cmd(&args),
        Command::Evaluate(args) => evaluate_cmd::evaluate(&args),
        Command::CalibrateContact(args) => calibrate_cmd::calibrate_contact(&args),
        Command::Import(args) => import_cmd::import(&args),
        Command::Deploy(args) => deploy_cmd::deploy(&args),
        #[cfg(feature = "ros2")]
        Command::Ros2(args) => admittance_ros2::cli::run(&args).map_err(|f| CliError {
            code: f.code,
            message: f.message,
        }),
        #[cfg(not(feature = "ros2"))]
        Command::Ros2 { .. } => Err(CliError::usage(
            "this admittance was built without ROS 2: build it with `cargo build --release -p admittance-cli --features ros2`, or use `cargo build --release -p admittance-ros2` (target/release/admittance-ros2 takes the same arguments); docs/ros2.md",
        )),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("admittance: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
