//! `admittance-ros2`: the `admittance ros2` subcommands as their own binary (the same
//! arguments), for a build without the `admittance` command's other dependencies.

use std::process::ExitCode;

use admittance_ros2::cli::{run, Ros2Args};
use clap::Parser;

/// ROS 2 without ROS: the observer on a robot's JointState topic.
#[derive(Parser)]
#[command(name = "admittance-ros2", version, about)]
struct Cli {
    #[command(flatten)]
    args: Ros2Args,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    match run(&cli.args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("admittance-ros2: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}
