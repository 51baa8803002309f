//! `admittance calibrate-contact`: the contact floor (per-joint contact and collision
//! thresholds for a stated false-alarm rate) from free motion the identification did not
//! fit (issue 31; docs/method.md section 5, "Contact"; docs/outputs.md, "Contact floors").

use std::path::{Path, PathBuf};

use admittance_control::{ContactCalibrationConfig, JointValues, MomentumObserverConfig};
use admittance_dynamics::{Identification, Model};
use admittance_scenario::FreeMotionData;
use clap::Args;
use serde_json::json;

use crate::train_cmd::{positive_number, IdentificationFile};
use crate::CliError;

/// A time in seconds, finite and >= 0.
pub fn seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err("the value must be a time >= 0 s".into()),
    }
}

#[derive(Args)]
pub struct CalibrateContactArgs {
    /// Free motion that the identification did not fit (CSV, docs/outputs.md): a second
    /// recording, or the held-out stretch of one (--from); several files are pooled, each
    /// after its own warm-up (motion at several speeds and poses holds more than one file).
    #[arg(required = true, num_args = 1..)]
    data: Vec<PathBuf>,
    /// The identification file (`admittance identify`); the URDF it names is loaded.
    #[arg(long)]
    identification: PathBuf,
    /// Contact-floor file to write (JSON): a new name or a contact-floor file.
    #[arg(long)]
    out: PathBuf,
    /// False contact events per hour the floor allows, all joints together.
    #[arg(long, default_value_t = 1.0, value_parser = positive_number)]
    false_alarms_per_hour: f64,
    /// Use the rows with t >= FROM (s) only (e.g. the stretch identify's --until left out;
    /// of every file).
    #[arg(long, default_value_t = 0.0, value_parser = seconds)]
    from: f64,
    /// Use the rows with t < UNTIL (s) only.
    #[arg(long, value_parser = positive_number)]
    until: Option<f64>,
    /// Momentum observer gain K_O (1/s): the observer the floor is for.
    #[arg(long, default_value_t = 50.0, value_parser = positive_number)]
    gain: f64,
    /// Constant levels (no growth with speed and acceleration).
    #[arg(long)]
    constant: bool,
}

/// The identification file with its arm, the cut-off it was made with in its summary.
pub fn load_identification(path: &Path) -> Result<(Identification, Model), CliError> {
    let (_, arm) =
        Identification::load_with_urdf(path).map_err(|e| CliError::input(e.to_string()))?;
    let file = IdentificationFile::load(path, &arm)?;
    let mut ident = file.ident;
    ident.summary.input_filter_hz = file.input_filter_hz;
    Ok((ident, arm))
}

/// The rows of `data` with `from <= t < until`, at least `min_rows` of them.
pub fn rows_between(
    path: &Path,
    data: FreeMotionData,
    from: f64,
    until: Option<f64>,
    min_rows: usize,
) -> Result<FreeMotionData, CliError> {
    let until = until.unwrap_or(f64::INFINITY);
    let first = data.t.iter().take_while(|t| **t < from).count();
    let end = data.t.iter().take_while(|t| **t < until).count().max(first);
    if end - first < min_rows {
        return Err(CliError::usage(format!(
            "{}: only {} rows lie in [{from}, {until}) s; need at least {min_rows}",
            path.display(),
            end - first
        )));
    }
    let n = data.dof();
    let cut = |v: &[f64]| v[first * n..end * n].to_vec();
    Ok(FreeMotionData {
        t: data.t[first..end].to_vec(),
        q: cut(&data.q),
        qdot: cut(&data.qdot),
        qddot: cut(&data.qddot),
        tau: cut(&data.tau),
        joints: data.joints,
        derived: data.derived,
        unwrapped: data.unwrapped,
    })
}

pub fn calibrate_contact(args: &CalibrateContactArgs) -> Result<(), CliError> {
    if args.out.is_dir() {
        return Err(CliError::usage(format!(
            "--out {}: is a folder; give a file name",
            args.out.display()
        )));
    }
    let (ident, arm) = load_identification(&args.identification)?;
    let joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let mut recordings = Vec::with_capacity(args.data.len());
    for path in &args.data {
        let data = crate::train_cmd::load_data(path, Some(&joints))?;
        let data = rows_between(path, data, args.from, args.until, 100)?;
        // A floor calibrated where the model extrapolates holds its error, not the noise.
        let conditioned =
            admittance_scenario::ConditionedSamples::new(&data, ident.summary.input_filter_hz)
                .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        for line in crate::training_range::lines(&ident, &arm, &conditioned.q) {
            eprintln!(
                "admittance: warning: {}: outside the identification's training range, where its model \
                 extrapolates and the floor takes its error: {line}",
                path.display()
            );
        }
        for line in crate::training_speed::lines(&ident, &arm, &conditioned.qdot) {
            eprintln!(
                "admittance: warning: {}: faster than the identification's training speeds, where its \
                 friction extrapolates and the floor takes its error: {line}",
                path.display()
            );
        }
        recordings.push(data);
    }
    let observer = MomentumObserverConfig {
        gain: JointValues::Uniform(args.gain),
    };
    let config = ContactCalibrationConfig {
        false_alarms_per_hour: args.false_alarms_per_hour,
        grow_with_motion: !args.constant,
        ..Default::default()
    };
    let names: Vec<String> = args.data.iter().map(|p| p.display().to_string()).collect();
    let mut floor =
        admittance_scenario::calibrate_contact_on_all(&recordings, &ident, &observer, &config)
            .map_err(|e| CliError::input(format!("{}: {e}", names.join(", "))))?;
    let data = match names.as_slice() {
        [one] => json!(one),
        many => json!(many),
    };
    floor.source.insert("data".into(), data);
    floor.source.insert("from_s".into(), json!(args.from));
    floor.source.insert("until_s".into(), json!(args.until));
    floor.source.insert(
        "identification".into(),
        json!(args.identification.display().to_string()),
    );
    floor.created_by = format!("admittance calibrate-contact {}", env!("CARGO_PKG_VERSION"));
    floor
        .save(&args.out)
        .map_err(|e| CliError::input(e.to_string()))?;
    crate::write_stdout(&format!(
        "{}\nwrote {}\n",
        floor.describe(),
        args.out.display()
    ));
    Ok(())
}
