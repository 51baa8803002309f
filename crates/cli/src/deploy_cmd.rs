//! `admittance deploy (SCENARIO | RUN_DIR) --out DIR`: the folder a robot's loop reads
//! (`adm_create`, `admittance ros2 bridge`, Python's `RobotLoop.load`; docs/your_robot.md):
//! `loop.toml` in the loop's own vocabulary, the arm's URDF, the identification and the
//! network the observer runs on, a contact floor when given, and `manifest.json` with each
//! file's size and checksum and what made them. It never trains: a network or
//! identification that the training cache does not hold is an error naming the command
//! that makes it.

use std::path::{Path, PathBuf};

use admittance_learning::broad::fnv1a64;
use admittance_loop::{RobotConfig, RobotLoop, LOOP_FILE, LOOP_FILE_FORMAT, LOOP_FILE_VERSION};
use admittance_scenario::{deployable, Deployable, RunOptions, ScenarioSource};
use serde_json::json;

use crate::CliError;

/// `admittance deploy`.
#[derive(clap::Args, Debug)]
pub struct DeployArgs {
    /// A scenario file, or a run folder (its scenario.toml is deployed).
    source: PathBuf,
    /// The variant to deploy (default: the file's base).
    #[arg(long)]
    variant: Option<String>,
    /// Override a scenario value: --set section.key=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// A contact floor (`admittance calibrate-contact`) for the loop's contact flags.
    #[arg(long, value_name = "FILE")]
    contact_floor: Option<PathBuf>,
    /// The folder to write (missing, empty, or a deployment folder it replaces).
    #[arg(long)]
    out: PathBuf,
}

fn read(path: &Path) -> Result<Vec<u8>, CliError> {
    admittance_files::read_regular(path, admittance_files::DATA_LIMIT)
        .map_err(|e| CliError::input(format!("{}: cannot be read: {e}", path.display())))
}

/// Runs the command.
pub fn deploy(args: &DeployArgs) -> Result<(), CliError> {
    let scenario_path = if args.source.is_dir() {
        args.source.join(admittance_runfolder::files::SCENARIO)
    } else {
        args.source.clone()
    };
    let mut source =
        ScenarioSource::load(&scenario_path).map_err(|e| CliError::input(e.to_string()))?;
    // A run folder's scenario.toml keeps the file's relative paths: they are relative to
    // the scenario file the run was made from, which summary.json names.
    let scenario_path = if args.source.is_dir() {
        run_scenario_file(&args.source).unwrap_or(scenario_path)
    } else {
        scenario_path
    };
    for s in &args.set {
        source.set(s).map_err(|e| CliError::input(e.to_string()))?;
    }
    let parts = deployable(
        &source,
        &scenario_path,
        args.variant.as_deref(),
        &RunOptions::default(),
    )
    .map_err(|e| CliError::input(e.to_string()))?;
    let (files, made_by) = folder_files(args, &scenario_path, &parts)?;
    admittance_loop::write_deployment(&args.out, &files, made_by)
        .map_err(|e| CliError::input(e.text()))?;
    // What was written loads as a robot will load it.
    let check = RobotLoop::load(&args.out, &[]).map_err(|e| CliError {
        code: 1,
        message: format!("the folder written does not load: {}", e.text()),
    })?;
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    crate::write_stdout(&format!(
        "admittance deploy: {} ({} joints, {:?} observer, {:.0} Hz) -> {} ({}, manifest.json)\n",
        scenario_path.display(),
        check.dof(),
        parts.loop_config.observer.kind,
        parts.loop_config.control_rate_hz,
        args.out.display(),
        names.join(", ")
    ));
    Ok(())
}

/// The folder's files and the manifest's `made_by`.
fn folder_files(
    args: &DeployArgs,
    scenario_path: &Path,
    parts: &Deployable,
) -> Result<(Vec<(String, Vec<u8>)>, serde_json::Value), CliError> {
    let bad = |e: String| CliError::input(format!("{}: {e}", scenario_path.display()));
    let urdf = read(&parts.urdf)?;
    let mut files = vec![("arm.urdf".to_string(), urdf.clone())];
    let mut made_by = json!({
        "tool": "admittance deploy",
        "version": env!("CARGO_PKG_VERSION"),
        "scenario": scenario_path.display().to_string(),
        "variant": args.variant,
        "set": args.set,
        "urdf": {"path": parts.urdf.display().to_string(), "fnv1a64": format!("{:016x}", fnv1a64(&urdf))},
    });
    // The loop's settings, as the scenario resolved them, without what the loop does not
    // read (the training table) and with the file names of this folder.
    let mut table: toml::Table = toml::Table::try_from(&parts.loop_config)
        .map_err(|e| bad(format!("the loop settings do not serialise: {e}")))?;
    let observer = table
        .entry("observer")
        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        .as_table_mut()
        .ok_or_else(|| bad("observer is not a table".into()))?;
    observer.remove("training");
    observer.remove("identification");
    observer.remove("network");
    let c = &parts.loop_config.observer;
    if let Some(ident) = &c.identification {
        let bytes = read(ident)?;
        if let Some(fitted) = fitted_filter_hz(&bytes) {
            if fitted.to_bits() != c.input_filter_hz.to_bits() {
                return Err(bad(format!(
                    "observer.input_filter_hz is {} Hz, but {} was fitted on signals conditioned at {fitted} Hz: \
                     the robot's observer would run it on other signals; set observer.input_filter_hz = {fitted}",
                    c.input_filter_hz,
                    ident.display()
                )));
            }
        }
        files.push(("identification.json".into(), bytes));
        observer.insert("identification".into(), "identification.json".into());
        made_by["identification"] = json!(ident.display().to_string());
    }
    let network = match (&parts.network, &c.network) {
        (Some(model), _) => Some((
            model.to_bytes(),
            "the scenario's training cache".to_string(),
        )),
        (None, Some(file)) => Some((read(file)?, file.display().to_string())),
        (None, None) => None,
    };
    if let Some((bytes, from)) = network {
        files.push(("observer.broad".into(), bytes));
        observer.insert("network".into(), "observer.broad".into());
        made_by["network"] = json!(from);
    }
    let arm = &parts.scenario.arm;
    let mut arm_table = toml::Table::new();
    arm_table.insert("urdf".into(), "arm.urdf".into());
    if let Some(b) = &arm.base {
        arm_table.insert("base".into(), b.clone().into());
    }
    if let Some(t) = &arm.tip {
        arm_table.insert("tip".into(), t.clone().into());
    }
    arm_table.insert("strict".into(), arm.strict.into());
    if !arm.lock.is_empty() {
        let lock: toml::Table = arm
            .lock
            .iter()
            .map(|(j, v)| (j.clone(), (*v).into()))
            .collect();
        arm_table.insert("lock".into(), lock.into());
    }
    if !arm.drop.is_empty() {
        arm_table.insert(
            "drop".into(),
            toml::Value::try_from(&arm.drop).map_err(|e| bad(e.to_string()))?,
        );
    }
    table.insert("format".into(), LOOP_FILE_FORMAT.into());
    table.insert("version".into(), (LOOP_FILE_VERSION as i64).into());
    table.insert("arm".into(), arm_table.into());
    let mut signals = toml::Table::new();
    signals.insert(
        "filter_cutoff_hz".into(),
        parts.scenario.plant.sensors.filter_cutoff_hz.into(),
    );
    table.insert("signals".into(), signals.into());
    if let Some(floor) = contact_floor_file(args, &scenario_path, &parts.scenario)? {
        files.push(("contact_floor.json".into(), read(&floor)?));
        let mut contact = toml::Table::new();
        contact.insert("floor".into(), "contact_floor.json".into());
        let deadband = parts.scenario.contact.as_ref().is_some_and(|c| c.deadband);
        contact.insert("deadband".into(), deadband.into());
        table.insert("contact".into(), contact.into());
        made_by["contact_floor"] = json!(floor.display().to_string());
    }
    let text = toml::to_string(&table).map_err(|e| bad(e.to_string()))?;
    // Checked here as the robot's side will read it.
    RobotConfig::from_toml(&text, Path::new(LOOP_FILE)).map_err(|e| bad(e.text()))?;
    let header = format!(
        "# The robot's loop (admittance deploy, docs/your_robot.md), from {}{}.\n# Paths are relative to this folder; manifest.json holds every file's checksum.\n",
        scenario_path.display(),
        args.variant.as_deref().map(|v| format!(", variant {v}")).unwrap_or_default()
    );
    files.insert(0, (LOOP_FILE.to_string(), (header + &text).into_bytes()));
    Ok((files, made_by))
}

/// The contact floor to deploy: `--contact-floor`, else the scenario's `[contact] floor`,
/// else, for a run folder, the floor its variant detected with. A scenario that calibrates
/// its floor at run time is deployed from its run folder (deploy never calibrates).
fn contact_floor_file(
    args: &DeployArgs,
    scenario_path: &Path,
    scenario: &admittance_scenario::Scenario,
) -> Result<Option<PathBuf>, CliError> {
    if let Some(f) = &args.contact_floor {
        return Ok(Some(f.clone()));
    }
    let Some(spec) = &scenario.contact else {
        return Ok(None);
    };
    if let Some(f) = &spec.floor {
        let dir = scenario_path.parent().unwrap_or(Path::new("."));
        return Ok(Some(if f.is_absolute() {
            f.clone()
        } else {
            dir.join(f)
        }));
    }
    let variant = args.variant.as_deref().unwrap_or("base");
    let in_run = args
        .source
        .join(admittance_runfolder::files::contact_floor(variant));
    if args.source.is_dir() && in_run.is_file() {
        return Ok(Some(in_run));
    }
    Err(CliError::input(format!(
        "{}: [contact] calibrates its floor when the scenario runs, and deploy never calibrates: \
         run it (admittance run {} --out RUN_DIR) and deploy RUN_DIR, or give --contact-floor FILE",
        scenario_path.display(),
        scenario_path.display()
    )))
}

/// The input cut-off an identification file was fitted at: its summary's, else the one
/// `admittance identify` or a scenario's training recorded beside it; `None` when unknown.
fn fitted_filter_hz(bytes: &[u8]) -> Option<f64> {
    let v: serde_json::Value = serde_json::from_slice(bytes).ok()?;
    let summary = v.pointer("/payload/summary/input_filter_hz")?.as_f64()?;
    if summary > 0.0 {
        return Some(summary);
    }
    v.pointer("/payload/data/input_filter_hz")?.as_f64()
}

/// The scenario file a run folder was made from (`summary.json`'s `scenario_file`), when it
/// names one that exists.
fn run_scenario_file(run_dir: &Path) -> Option<PathBuf> {
    let summary = run_dir.join(admittance_runfolder::files::SUMMARY);
    let bytes = admittance_files::read_regular(&summary, admittance_files::TEXT_LIMIT).ok()?;
    let v: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    let file = PathBuf::from(
        v.get(admittance_runfolder::summary::KEY_SCENARIO_FILE)?
            .as_str()?,
    );
    file.is_file().then_some(file)
}
