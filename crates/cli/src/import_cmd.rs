//! `admittance import`: free-motion training data from a rosbag2 bag (the work is in the
//! `admittance-bag` crate; docs/import.md).

use std::path::PathBuf;

use admittance_bag::{import_to_csv, ImportOptions, Profile};
use clap::Args;

use crate::CliError;

#[derive(Args)]
pub struct ImportArgs {
    /// The bag: a rosbag2 MCAP folder, its metadata.yaml, or one .mcap file (a sqlite3
    /// bag is refused with the command that converts it).
    bag: PathBuf,
    /// Which topics and fields are q, qdot, tau and the label: a built-in profile
    /// (franka, ur, lbr) or a TOML file of the same form (crates/bag/profiles/).
    #[arg(long)]
    profile: String,
    /// The free-motion CSV to write: a new name, or a CSV an earlier import wrote (anything
    /// else is refused).
    #[arg(long)]
    out: PathBuf,
    /// Output rate (Hz); default: the median rate of the q topic.
    #[arg(long, value_name = "HZ", value_parser = positive_hz, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// Skip damaged MCAP chunks and keep the messages before the end of a truncated file
    /// (a recorder that was killed) instead of failing; the loss is reported and counted.
    #[arg(long)]
    accept_damaged: bool,
    /// Import a recording whose rate (or a --rate) is under 200 Hz, the least the loop
    /// needs, with a warning instead of refusing it.
    #[arg(long)]
    accept_low_rate: bool,
}

fn positive_hz(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1e9 => Ok(v),
        Ok(_) => Err("the rate must be a finite number of Hz > 0 (at most 1e9)".into()),
        Err(_) => Err("not a number".into()),
    }
}

fn bag_error(e: admittance_bag::BagError) -> CliError {
    CliError {
        code: e.exit_code(),
        message: e.to_string(),
    }
}

pub fn import(args: &ImportArgs) -> Result<(), CliError> {
    let profile = Profile::resolve(&args.profile).map_err(bag_error)?;
    let options = ImportOptions {
        rate_hz: args.rate,
        accept_damage: args.accept_damaged,
        accept_low_rate: args.accept_low_rate,
    };
    let report = import_to_csv(&args.bag, &profile, &options, &args.out).map_err(bag_error)?;
    crate::write_stdout(&format!(
        "profile: {} ({})\n{report}\nwrote {}\n",
        profile.name,
        profile.description,
        args.out.display()
    ));
    for warning in report.notes.iter().filter(|n| n.starts_with("WARNING")) {
        eprintln!("admittance: {warning}");
    }
    if report.skipped() > 0 || !report.damage.is_empty() {
        eprintln!(
            "admittance: warning: {} message(s) skipped{}; see the list above",
            report.skipped(),
            if report.damage.is_empty() {
                String::new()
            } else {
                format!(
                    ", {} damaged chunk(s) skipped and damaged data accepted",
                    report.skipped_chunks
                )
            }
        );
    }
    Ok(())
}
