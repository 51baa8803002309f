//! `admittance excite`: an excitation trajectory for identification (docs/outputs.md,
//! "Excitation data"): a finite Fourier series per joint inside the position, velocity and
//! acceleration limits, optimised for the condition number of the base inertial
//! regressor, written as free-motion data. Its `tau` columns are the torque the nominal
//! arm (the URDF, by RNEA) needs for the motion: a feed-forward reference for the
//! controller that plays it; a recording on the real arm replaces them.

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
    /// Centre of the envelope: one position per joint, comma-separated (rad or m; default:
    /// the middle of each joint's limits). Give the pose the robot is at, away from obstacles.
    #[arg(long, value_name = "Q1,Q2,...", allow_hyphen_values = true)]
    pose: Option<String>,
    /// Half-width of each joint's range around the pose (rad or m): one number for every
    /// joint or one per joint, comma-separated; `full`: the URDF's whole range.
    #[arg(
        long,
        value_name = "R or R1,R2,...",
        default_value = "0.5",
        allow_hyphen_values = true
    )]
    range: String,
    /// Fraction (0 to 1] of each joint's URDF velocity limit the motion may reach.
    #[arg(long, default_value_t = admittance_dynamics::DEFAULT_LIMIT_FRACTION, allow_negative_numbers = true)]
    velocity_fraction: f64,
    /// Fraction (0 to 1] of --acceleration-limit the motion may reach.
    #[arg(long, default_value_t = admittance_dynamics::DEFAULT_LIMIT_FRACTION, allow_negative_numbers = true)]
    acceleration_fraction: f64,
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
            ..Default::default()
        }
    }

    /// The settings with the envelope for `arm`: `--pose`, `--range` and the fractions.
    fn settings_for(&self, arm: &Model) -> Result<ExcitationSettings, CliError> {
        let n = arm.nq();
        let pose = match &self.pose {
            Some(text) => {
                crate::dynamics_cmd::parse_list("pose", text, n, "one position per joint")?
            }
            None => Vec::new(),
        };
        Ok(ExcitationSettings {
            pose,
            range: parse_range(&self.range, n)?,
            velocity_fraction: self.velocity_fraction,
            acceleration_fraction: self.acceleration_fraction,
            ..self.settings()
        })
    }
}

/// `--range`: `full`, one half-width, or one per joint.
fn parse_range(text: &str, n: usize) -> Result<Vec<f64>, CliError> {
    if text.trim() == "full" {
        return Ok(vec![f64::INFINITY]);
    }
    let count = text.split(',').count();
    let expected = if count == 1 { 1 } else { n };
    crate::dynamics_cmd::parse_list(
        "range",
        text,
        expected,
        "one half-width, one per joint, or `full`",
    )
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
        ("pose", "--pose"),
        ("range", "--range"),
        ("velocity_fraction", "--velocity-fraction"),
        ("acceleration_fraction", "--acceleration-fraction"),
    ] {
        text = text.replace(&format!("excitation setting {key}:"), &format!("{flag}:"));
    }
    CliError::usage(text)
}

/// `--out` must be a new name or a file this command wrote.
fn check_out(path: &Path) -> Result<(), CliError> {
    // Checked before any work; the write refuses it again (`admittance_files`).
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(CliError::usage(format!(
            "--out {}: is a symbolic link; the file is written only to a new name or over a regular file (remove the link or give another name)",
            path.display()
        )));
    }
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
    // Only a regular file is opened (a FIFO would block): its size does not matter here.
    let Ok(file) = admittance_files::open_regular(path, u64::MAX) else {
        return false;
    };
    let mut header = String::new();
    let head = std::io::Read::take(file, 1 << 20);
    let read = std::io::BufReader::new(head).read_line(&mut header).is_ok();
    read && header.starts_with("t,q.") && header.trim_end().ends_with(&format!(",{MARK_COLUMN}"))
}

pub fn excite(args: &ExciteArgs) -> Result<(), CliError> {
    check_out(&args.out)?;
    let settings = args.settings();
    settings.validate().map_err(flag_error)?;
    let arm = crate::dynamics_cmd::load(&args.chain)?;
    let settings = args.settings_for(&arm)?;
    settings.validate_for(&arm).map_err(flag_error)?;
    let started = std::time::Instant::now();
    let e = excitation(&arm, &settings)
        .map_err(|e| CliError::input(format!("excitation of this arm: {e}")))?;
    let seconds = started.elapsed().as_secs_f64();
    write_csv(&args.out, &arm, &e, settings.seed)?;
    crate::write_stdout(&report(&arm, &settings, &e, seconds, &args.out));
    Ok(())
}

/// The free-motion layout plus the mark column, written atomically and exclusively
/// (`admittance_files::write_atomic`: never through a link planted beside `out` or at it).
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
    admittance_files::write_atomic(out, text.as_bytes()).map_err(|err| CliError {
        code: 1,
        message: format!("--out {}: {err}", out.display()),
    })
}

fn range_text(range: &[f64]) -> String {
    match range {
        [r] if r.is_infinite() => "the whole range".into(),
        [r] => format!("+-{r}"),
        many => format!("+-{many:?}"),
    }
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
         envelope: {} around {}, {} % of the velocity limits, {} % of {} rad/s^2, limits less a margin of {}\n\
         envelope used (1 = at its edge; position: max |q - centre| / half-width):\n  {:<20} {:>9} {:>9} {:>9}\n",
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
        range_text(&settings.range),
        if settings.pose.is_empty() { "the middle of the limits".to_string() } else { format!("{:?}", settings.pose) },
        100.0 * settings.velocity_fraction,
        100.0 * settings.acceleration_fraction,
        settings.acceleration_limit,
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
    let start: Vec<String> = e.q[..arm.nq()].iter().map(|q| format!("{q:.4}")).collect();
    text += &format!(
        "starts and ends at rest at q = [{}]: bring the arm there slowly first (docs/your_robot.md)\n",
        start.join(", ")
    );
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
