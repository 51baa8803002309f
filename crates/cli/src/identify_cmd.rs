//! `admittance identify`: the arm's inertial parameters and joint terms from free motion
//! (docs/method.md section 1; docs/outputs.md, "Identification files"). Settings are
//! chosen and the expected false torque measured on motion the fit did not see: the
//! `--validation` recording, or contiguous stretches of the data held out in turn.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use admittance_dynamics::{Identification, IdentificationSettings, JointTerms, Model, Samples};
use admittance_scenario::FreeMotionData;
use clap::Args;
use serde_json::json;

use crate::train_cmd::{non_negative_hz, positive_number};
use crate::CliError;

mod payload;

#[derive(Args)]
pub struct IdentifyArgs {
    /// Free-motion data (CSV: t, q.J, qdot.J, qddot.J, tau.J, qdot and qddot optional;
    /// docs/outputs.md). Required unless --payload.
    #[arg(long, default_value = "", hide_default_value = true, value_parser = payload::any_path)]
    data: PathBuf,
    #[command(flatten)]
    chain: crate::dynamics_cmd::ChainArgs,
    /// Another recording of other motion: settings are chosen and the expected error
    /// measured on it (default: blocked cross-validation over contiguous stretches of --data).
    #[arg(long)]
    validation: Option<PathBuf>,
    /// Use only the rows of --data with t < UNTIL (s): the rest is left for evaluation.
    #[arg(long, value_parser = positive_number)]
    until: Option<f64>,
    /// Low-pass (Hz) on q and tau before differentiating, as the observers condition their
    /// inputs at run time (`input_filter_hz`); 0: the columns as recorded. Default: chosen on
    /// held-out motion among 4, 6 and 10 Hz and the columns as recorded (the identification
    /// file records it, and every consumer conditions its inputs the same way).
    #[arg(long, value_parser = non_negative_hz, allow_negative_numbers = true)]
    input_filter_hz: Option<f64>,
    /// Fit the rigid-body parameters only (no rotor inertia, friction, offset or springs).
    #[arg(long)]
    no_friction: bool,
    /// Do not offer spring terms.
    #[arg(long)]
    no_springs: bool,
    /// Width of the Coulomb friction's narrower smooth sign tanh(qdot / w) (rad/s). Default:
    /// chosen on held-out motion among 0.01, 0.003 and 0.005.
    #[arg(long, value_parser = positive_number)]
    coulomb_width: Option<f64>,
    /// Contiguous stretches for cross-validation (without --validation).
    #[arg(long, default_value_t = 5)]
    folds: usize,
    /// Each link's mass at most R times the URDF's (plus a twentieth of the arm's) and
    /// within twice its size (docs/method.md section 8); `none`: no bound.
    #[arg(long, value_name = "R|none", default_value = "2", value_parser = mass_ratio)]
    max_mass_ratio: MassRatio,
    /// Identification file to write (JSON): a new name or an identification file.
    #[arg(long)]
    out: PathBuf,
    /// Free-motion data with a tool or payload attached at the tip (CSV as --data; 20 s
    /// is enough): fits the payload on top of --identification and writes the
    /// identification carrying it to --out.
    #[arg(long, value_name = "DATA", requires = "identification", conflicts_with_all = ["validation"])]
    payload: Option<PathBuf>,
    /// With --payload: the identification of the arm without the payload.
    #[arg(long, value_name = "FILE", requires = "payload")]
    identification: Option<PathBuf>,
    /// No progress output on stderr.
    #[arg(long)]
    quiet: bool,
}

/// `--max-mass-ratio`: a ratio of at least 1, or no bound.
#[derive(Clone, Copy, Debug)]
struct MassRatio(Option<f64>);

fn mass_ratio(text: &str) -> Result<MassRatio, String> {
    if text.eq_ignore_ascii_case("none") {
        return Ok(MassRatio(None));
    }
    match text.parse::<f64>() {
        Ok(r) if r.is_finite() && r >= 1.0 => Ok(MassRatio(Some(r))),
        _ => Err(format!(
            "{text}: a ratio of at least 1 (times the URDF's mass), or none for no bound"
        )),
    }
}

/// The data's rows as identification samples, conditioned as at run time.
pub struct Conditioned {
    pub q: Vec<f64>,
    pub qdot: Vec<f64>,
    pub qddot: Vec<f64>,
    pub tau: Vec<f64>,
    pub dof: usize,
}

impl Conditioned {
    pub fn new(path: &Path, data: &FreeMotionData, input_filter_hz: f64) -> Result<Self, CliError> {
        let n = data.dof();
        let (x, tau) = admittance_scenario::observer_training_arrays(data, input_filter_hz)
            .map_err(|e| {
                CliError::usage(format!(
                    "--input-filter-hz {input_filter_hz} with the data of {}: {e}",
                    path.display()
                ))
            })?;
        let (mut q, mut qdot, mut qddot) = (Vec::new(), Vec::new(), Vec::new());
        for row in x.chunks_exact(3 * n) {
            q.extend_from_slice(&row[..n]);
            qdot.extend_from_slice(&row[n..2 * n]);
            qddot.extend_from_slice(&row[2 * n..]);
        }
        Ok(Conditioned {
            q,
            qdot,
            qddot,
            tau,
            dof: n,
        })
    }

    pub fn samples(&self) -> Samples<'_> {
        Samples {
            q: &self.q,
            qdot: &self.qdot,
            qddot: &self.qddot,
            tau: &self.tau,
            dof: self.dof,
        }
    }
}

/// Rows with `t < until` (all without `until`); an error when that leaves too few.
pub fn rows_until(
    path: &Path,
    data: &FreeMotionData,
    until: Option<f64>,
) -> Result<usize, CliError> {
    let Some(until) = until else {
        return Ok(data.len());
    };
    let rows = data.t.iter().take_while(|t| **t < until).count();
    if rows < 20 {
        return Err(CliError::usage(format!(
            "--until {until}: only {rows} rows of {} are before it (its time runs from {} to {} s; \
             --until is a time of that column)",
            path.display(),
            data.t.first().copied().unwrap_or(f64::NAN),
            data.t.last().copied().unwrap_or(f64::NAN)
        )));
    }
    Ok(rows)
}

/// `--out` must be a new name or an identification file.
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
    if path.exists() && Identification::load_with_urdf(path).is_err() && !is_identification(path) {
        return Err(CliError::usage(format!(
            "--out {}: exists and is not an identification file; choose another name",
            path.display()
        )));
    }
    Ok(())
}

fn is_identification(path: &Path) -> bool {
    admittance_files::read_regular_text(path, admittance_files::TEXT_LIMIT)
        .is_ok_and(|t| t.contains("\"format\": \"admittance-identification\""))
}

pub fn identify_cmd(args: &IdentifyArgs) -> Result<(), CliError> {
    if let Some(tool) = &args.payload {
        return payload::payload_cmd(args, tool);
    }
    if args.data.as_os_str().is_empty() {
        return Err(CliError::usage(
            "--data is required (or --payload DATA --identification FILE)",
        ));
    }
    check_out(&args.out)?;
    if !(2..=50).contains(&args.folds) {
        return Err(CliError::usage(format!(
            "--folds {}: must be 2 to 50",
            args.folds
        )));
    }
    let arm = crate::dynamics_cmd::load(&args.chain)?;
    let joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let data = crate::train_cmd::load_data(&args.data, Some(&joints))?;
    let rows = rows_until(&args.data, &data, args.until)?;
    let repeats_every_s = match args.validation {
        None => crate::train_cmd::warn_if_repeating(&args.data, &data, rows, args.folds),
        Some(_) => None,
    };
    let validation = match &args.validation {
        Some(p) => Some(crate::train_cmd::load_data(p, Some(&joints))?),
        None => None,
    };
    let settings = IdentificationSettings {
        friction: !args.no_friction,
        springs: !args.no_friction && !args.no_springs,
        coulomb_width: args.coulomb_width,
        folds: args.folds,
        max_mass_ratio: args.max_mass_ratio.0,
        ..Default::default()
    };
    for (path, recording) in [
        (Some(&args.data), Some(&data)),
        (args.validation.as_ref(), validation.as_ref()),
    ] {
        if let (Some(path), Some((_, found))) = (
            path,
            recording.and_then(admittance_scenario::evenly_sampled),
        ) {
            eprintln!(
                "admittance: warning: {}: {}",
                path.display(),
                found.describe()
            );
        }
    }
    let started = std::time::Instant::now();
    let spinner = crate::progress::Spinner::start(
        crate::progress::wanted(args.quiet),
        format!("identifying {} joints from {rows} samples", arm.nq()),
    );
    let (ident, tried) = admittance_scenario::identify_recording(
        &arm,
        &data,
        rows,
        validation.as_ref(),
        &settings,
        args.input_filter_hz,
    )
    .map_err(|e| CliError::input(format!("{}: {e}", args.data.display())))?;
    drop(spinner);
    let mut provenance = BTreeMap::new();
    provenance.insert("data".into(), json!(args.data.display().to_string()));
    provenance.insert("rows".into(), json!(rows));
    provenance.insert("until_s".into(), json!(args.until));
    provenance.insert(
        "validation".into(),
        json!(args.validation.as_ref().map(|p| p.display().to_string())),
    );
    provenance.insert(
        "input_filter_hz".into(),
        json!(ident.summary.input_filter_hz),
    );
    provenance.insert(
        "input_filters_tried".into(),
        json!(tried
            .iter()
            .map(|t| json!({"input_filter_hz": t.input_filter_hz, "expected_false_torque_rms": t.expected_false_torque_rms}))
            .collect::<Vec<_>>()),
    );
    if let Some(period) = repeats_every_s {
        provenance.insert("data_repeats_every_s".into(), json!(period));
    }
    ident
        .save(&args.out, &arm, provenance)
        .map_err(|e| CliError {
            code: 1,
            message: e.to_string(),
        })?;
    let mut text = String::new();
    if tried.len() > 1 {
        text += "input filter chosen on held-out motion (expected false torque, rms N m):";
        for t in &tried {
            text += &format!(
                " {}: {:.3};",
                filter_name(t.input_filter_hz),
                t.expected_false_torque_rms
            );
        }
        text += "\n";
    }
    text += &report(&arm, &ident, started.elapsed().as_secs_f64(), &args.out);
    crate::write_stdout(&text);
    for warning in admittance_scenario::identification_warnings(&arm, &ident) {
        eprintln!("admittance: warning: {warning}");
    }
    Ok(())
}

/// The springs column: how a kept spring continues beyond the positions trained on.
fn spring_kind(kept: bool, terms: &JointTerms) -> &'static str {
    match (kept, terms.spring_range) {
        (false, _) => "-",
        (true, Some(_)) => "linear",
        (true, None) => "periodic",
    }
}

fn filter_name(hz: f64) -> String {
    if hz > 0.0 {
        format!("{hz} Hz")
    } else {
        "as recorded".into()
    }
}

/// The torque's delay behind the motion: one value when every joint has the same (as
/// `identify` chooses), else per joint.
fn delay_text(delay_s: &[f64]) -> String {
    let ms: Vec<f64> = delay_s.iter().map(|d| (1e4 * d).round() / 10.0).collect();
    match ms.first() {
        None => "0 ms".into(),
        Some(first) if ms.iter().all(|d| d == first) => format!("{first} ms"),
        Some(_) => format!("per joint {ms:?} ms"),
    }
}

/// The console table: per joint the URDF's and the identification's rms on held-out motion.
fn report(arm: &Model, ident: &Identification, seconds: f64, out: &Path) -> String {
    let s = &ident.summary;
    let mut text = format!(
        "identified {} joints from {} samples in {seconds:.1} s; held out: {}\n\
         ridge {:.1e}, Coulomb width {} rad/s{}, {} base parameters, condition number {:.1}, bodies a free fit would make impossible: {:?}\n\
         expected false torque on motion not trained on (rms, N m):\n  {:<16} {:>10} {:>12} {:>8} {:>12}  {}\n",
        arm.nq(), s.training_samples, s.held_out, s.ridge,
        ident.joint_terms.first().map_or(f64::NAN, |t| t.coulomb_width),
        if s.settings.coulomb_width.is_none() { " (chosen)" } else { "" },
        s.base_parameters, s.condition_number,
        s.projected_bodies, "joint", "URDF", "identified", "springs", "top speed", "positions trained on"
    );
    if !s.bodies_at_extent.is_empty() {
        let names: Vec<&str> = s
            .bodies_at_extent
            .iter()
            .filter_map(|&b| arm.joints.get(b).map(|j| j.child_link.as_str()))
            .collect();
        text = format!(
            "bodies held at the arm's size (at most {} times the URDF's mass, within twice its \
             size): {names:?}: the data wanted them heavier or farther out, a torque the model \
             lacks (a spring, cables) or URDF masses that are off\n{text}",
            s.settings.max_mass_ratio.unwrap_or(f64::NAN)
        );
    }
    if s.prior_scale != 1.0 {
        text = format!(
            "the torque is {:.3} times what the URDF's arm needs (a torque constant, gear ratio, unit or \
             masses off?): the bodies were pulled toward the URDF scaled by it\n{text}",
            s.prior_scale
        );
    }
    text = format!(
        "signals: input filter {}, torque delay {}, acceleration gain {}{}, estimate's 90 % step response {:.0} ms\n{text}",
        filter_name(s.input_filter_hz),
        delay_text(&s.delay_s),
        s.acceleration_gain,
        if s.fit_acceleration_hz > 0.0 {
            format!(" (fitted on q'' low-passed at {} Hz, zero phase)", s.fit_acceleration_hz)
        } else {
            String::new()
        },
        1e3 * s.step_response_s
    );
    let total = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    for (i, name) in arm.joint_names().enumerate() {
        let range = s
            .training_range
            .get(i)
            .map_or("-".to_string(), |[low, high]| {
                format!("{low:.2} to {high:.2}")
            });
        let speed = s
            .training_speed
            .get(i)
            .map_or("-".to_string(), |v| format!("{v:.2}"));
        text += &format!(
            "  {name:<16} {:>10.3} {:>12.3} {:>8} {speed:>12}  {range}\n",
            s.prior_false_torque_rms.get(i).copied().unwrap_or(f64::NAN),
            s.expected_false_torque_rms[i],
            spring_kind(s.springs[i], &ident.joint_terms[i])
        );
    }
    text += &format!(
        "  {:<16} {:>10.3} {:>12.3}\n",
        "all joints",
        total(&s.prior_false_torque_rms),
        total(&s.expected_false_torque_rms),
    );
    if !s.training_range.is_empty() {
        text += "beyond the positions trained on the model extrapolates (its offsets, gravity and \
                 springs: `linear` along their tangent, `periodic` as fitted over half a turn or \
                 more): `admittance evaluate` lists data that go there, the run-time loop flags \
                 each such step (outside_training_range)\n";
    }
    if !s.training_speed.is_empty() {
        text += "beyond the top speed trained at (rad/s or m/s, conditioned) its friction \
                 extrapolates: `admittance evaluate` lists data over half again as fast, the \
                 run-time loop flags each such step (faster_than_training)\n";
    }
    text += &format!("wrote {}\n", out.display());
    text
}
