//! `admittance excite`: an excitation trajectory for identification (docs/outputs.md,
//! "Excitation data"): a finite Fourier series per joint inside the position, velocity and
//! acceleration limits, optimised for the condition number of the base inertial
//! regressor, written as free-motion data. Its `tau` columns are the torque the nominal
//! arm (the URDF, by RNEA) needs for the motion: a feed-forward reference for the
//! controller that plays it; a recording on the real arm replaces them.

use std::io::Write;
use std::path::{Path, PathBuf};

use admittance_dynamics::{excitation, rnea, Data, Excitation, ExcitationSettings, Model};
use clap::Args;

use crate::train_cmd::positive_number;
use crate::CliError;

/// The last column of every file `excite` writes: the seed on every row. It marks the
/// file as ours, so that `--out` may overwrite it and nothing else.
pub const MARK_COLUMN: &str = "excite_seed";

#[derive(Args)]
pub struct ExciteArgs {
    #[command(flatten)]
    chain: crate::dynamics_cmd::ChainArgs,
    /// Length of the motion (s).
    #[arg(long, value_parser = positive_number, allow_negative_numbers = true)]
    duration: f64,
    /// Period of the series (s), dividing the duration (default: the duration split into
    /// equal periods of at most 10 s).
    #[arg(long, value_parser = positive_number, allow_negative_numbers = true)]
    period: Option<f64>,
    /// Harmonics per joint (at least 2).
    #[arg(long, default_value_t = 5)]
    harmonics: usize,
    /// Sampling rate of the output (Hz).
    #[arg(long, default_value_t = 200.0, value_parser = positive_number, allow_negative_numbers = true)]
    rate: f64,
    /// Acceleration limit of every joint (rad/s^2).
    #[arg(long, default_value_t = 3.0, value_parser = positive_number, allow_negative_numbers = true)]
    acceleration_limit: f64,
    /// Part of each joint's range kept free at either end (0 to 0.5).
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    position_margin: f64,
    /// Seed of the random starts of the optimisation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Condition-number evaluations of the local search.
    #[arg(long, default_value_t = 2000)]
    iterations: usize,
    /// CSV file to write: a new name or a file `excite` wrote.
    #[arg(long)]
    out: PathBuf,
}

impl ExciteArgs {
    fn settings(&self) -> ExcitationSettings {
        let period = self
            .period
            .unwrap_or_else(|| self.duration / (self.duration / 10.0 - 1e-9).ceil().max(1.0));
        ExcitationSettings {
            duration: self.duration,
            period,
            harmonics: self.harmonics,
            rate_hz: self.rate,
            acceleration_limit: self.acceleration_limit,
            position_margin: self.position_margin,
            seed: self.seed,
            iterations: self.iterations,
        }
    }
}

/// A setting's error with the flag's name instead of the setting's.
fn flag_error(e: admittance_dynamics::DynamicsError) -> CliError {
    let mut text = e.to_string();
    for (key, flag) in [
        ("duration", "--duration"),
        ("period", "--period"),
        ("harmonics", "--harmonics"),
        ("rate_hz", "--rate"),
        ("acceleration_limit", "--acceleration-limit"),
        ("position_margin", "--position-margin"),
    ] {
        text = text.replace(&format!("excitation setting {key}:"), &format!("{flag}:"));
    }
    CliError::usage(text)
}

/// `--out` must be a new name or a file this command wrote.
fn check_out(path: &Path) -> Result<(), CliError> {
    if path.is_dir() {
        return Err(CliError::usage(format!(
            "--out {}: is a folder; give a file name",
            path.display()
        )));
    }
    if path.exists() && !is_ours(path) {
        return Err(CliError::usage(format!(
            "--out {}: exists and is not a file `admittance excite` wrote; choose another name",
            path.display()
        )));
    }
    Ok(())
}

fn is_ours(path: &Path) -> bool {
    use std::io::BufRead;
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    let mut header = String::new();
    let read = std::io::BufReader::new(file).read_line(&mut header).is_ok();
    read && header.starts_with("t,q.") && header.trim_end().ends_with(&format!(",{MARK_COLUMN}"))
}

pub fn excite(args: &ExciteArgs) -> Result<(), CliError> {
    check_out(&args.out)?;
    let settings = args.settings();
    settings.validate().map_err(flag_error)?;
    let arm = crate::dynamics_cmd::load(&args.chain)?;
    let started = std::time::Instant::now();
    let e = excitation(&arm, &settings)
        .map_err(|e| CliError::input(format!("excitation of this arm: {e}")))?;
    let seconds = started.elapsed().as_secs_f64();
    write_csv(&args.out, &arm, &e, settings.seed)?;
    crate::write_stdout(&report(&arm, &settings, &e, seconds, &args.out));
    Ok(())
}

/// The free-motion layout plus the mark column, written to a temporary file beside `out`
/// and renamed over it.
fn write_csv(out: &Path, arm: &Model, e: &Excitation, seed: u64) -> Result<(), CliError> {
    let n = arm.nq();
    let names: Vec<&str> = arm.joint_names().collect();
    let mut text = String::from("t");
    for kind in ["q", "qdot", "qddot", "tau"] {
        names.iter().for_each(|j| text += &format!(",{kind}.{j}"));
    }
    text += &format!(",{MARK_COLUMN}\n");
    let mut data = Data::new(arm);
    for k in 0..e.len() {
        let s = k * n..(k + 1) * n;
        let tau = rnea(
            arm,
            &mut data,
            &e.q[s.clone()],
            &e.qdot[s.clone()],
            &e.qddot[s.clone()],
        )
        .map_err(|err| CliError {
            code: 1,
            message: err.to_string(),
        })?;
        text += &format!("{}", e.t[k]);
        for v in e.q[s.clone()]
            .iter()
            .chain(&e.qdot[s.clone()])
            .chain(&e.qddot[s])
            .chain(tau.iter())
        {
            text += &format!(",{v}");
        }
        text += &format!(",{seed}\n");
    }
    let file_name = out
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temp = out.with_file_name(format!(".{file_name}.tmp-{}", std::process::id()));
    let failed = |err: std::io::Error| CliError {
        code: 1,
        message: format!("--out {}: {err}", out.display()),
    };
    let written = std::fs::File::create(&temp)
        .and_then(|mut f| f.write_all(text.as_bytes()).and_then(|_| f.sync_all()));
    if let Err(err) = written.and_then(|_| std::fs::rename(&temp, out)) {
        let _ = std::fs::remove_file(&temp);
        return Err(failed(err));
    }
    Ok(())
}

/// The console summary: conditioning and, per joint, how much of each limit is used.
fn report(
    arm: &Model,
    settings: &ExcitationSettings,
    e: &Excitation,
    seconds: f64,
    out: &Path,
) -> String {
    let mut text = format!(
        "excitation of {} joints: {} s in {} periods of {} s, {} harmonics, {} samples at {} Hz (optimised in {seconds:.1} s)\n\
         condition number of the base inertial regressor ({} base parameters): {:.2} (first random start: {:.2})\n\
         limits used (1 = at the limit; position: max |q - middle| / half the range, margin {}):\n  {:<20} {:>9} {:>9} {:>9}\n",
        arm.nq(),
        settings.duration,
        (settings.duration / settings.period).round(),
        settings.period,
        settings.harmonics,
        e.len(),
        settings.rate_hz,
        e.base_parameters,
        e.condition_number,
        e.initial_condition_number,
        settings.position_margin,
        "joint",
        "position",
        "velocity",
        "accel."
    );
    for (name, u) in arm.joint_names().zip(e.limit_use(arm, settings)) {
        let position = if u.position.is_nan() {
            "-".to_string()
        } else {
            format!("{:.3}", u.position)
        };
        text += &format!(
            "  {name:<20} {position:>9} {:>9.3} {:>9.3}\n",
            u.velocity, u.acceleration
        );
    }
    text += &format!("tau: the torque the nominal arm needs (RNEA of the URDF), a feed-forward reference\nwrote {}\n", out.display());
    if settings.duration > settings.period * (1.0 + 1e-9) {
        // Blocked cross-validation over a periodic recording holds out periods the fit has
        // seen: the validation must be another motion.
        text += &format!(
            "the motion repeats every {} s: record a second excitation (another --seed) and give it to identify and train as --validation\n",
            settings.period
        );
    }
    text
}
