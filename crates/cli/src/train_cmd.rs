//! `admittance train` and `admittance grow`: the flat RBF network of the learned observer
//! (docs/method.md section 5) from free-motion data (docs/outputs.md, "Free-motion data").
//!
//! Inputs `[q, qdot, qddot]`, targets `tau` (or, with `--nominal FILE`, what an
//! identification file explains not: `tau - ident.predict(q, qdot, qddot)`). The ridge
//! parameter is chosen, and the printed validation error measured, on motion the fit did
//! not see (issue #22): a separate recording (`--validation FILE`), else blocked
//! cross-validation over `--folds` contiguous stretches of the rows (default 5); the
//! network is then fitted on every row. `--validation-fraction F` (the last rows, the tail
//! of the same motion) is kept for compatibility only. The model file records the arm (joint
//! names, the URDF model's fingerprint) and every setting (docs/outputs.md, "Model
//! files"); `grow` takes the settings from it and refuses another arm or data that are
//! not the training data. Before any work: the arguments, `--out`, and the memory and work
//! the fit needs (`--max-memory-gb`, `--max-tflop`) are checked.

mod args;
mod data;
mod recorded;

pub use args::{non_negative_hz, positive_number};
pub use data::{load as load_data, warn_if_repeating};
pub use recorded::{
    check_network, input_filter_hz, network_filter_hz, IdentificationFile, Learned,
};

use std::path::PathBuf;
use std::time::Instant;

use admittance_learning::broad::{
    check_budget, fit, ArmCheck, BroadConfig, BroadError, BroadModel, DataSettings, FitSize,
    FrictionFeatures, GrowthSpec, TrainingTarget, ValidationSplit,
};
use clap::Args;

use crate::progress::{self, Spinner};
use crate::CliError;
use args::{
    arm_identity, check_out, fold_count, learn_error, open_fraction, positive_count, BudgetArgs,
    OptionalArmArgs,
};

#[derive(Args)]
pub struct TrainArgs {
    /// Free-motion data (CSV: t, q.J, qdot.J, qddot.J, tau.J; any column order, extra
    /// columns ignored; qdot and qddot left out are taken by differences).
    #[arg(long)]
    data: PathBuf,
    /// The arm (`--urdf`, `--base`, `--tip`): the data must hold its joints' columns; the
    /// model file records its joint names and model fingerprint.
    #[command(flatten)]
    chain: crate::dynamics_cmd::ChainArgs,
    /// Enhancement (Gaussian) nodes L (at most the training rows).
    #[arg(long, default_value_t = admittance_learning::broad::DEFAULT_NODES, value_parser = positive_count, allow_negative_numbers = true)]
    nodes: usize,
    /// Add friction-shaped inputs tanh(qdot / v) (docs/method.md section 7).
    #[arg(long)]
    friction_features: bool,
    /// Second low-pass (Hz) on q and tau before differentiating again, the observer input
    /// conditioning of the scenarios (`observer.input_filter_hz`); 0: the columns as recorded.
    /// The observer must be fed the same conditioning at run time (`admittance_loop::InputConditioner`).
    /// Default: with --nominal, the identification's (another value is an error); else 0.
    #[arg(long, value_parser = non_negative_hz, allow_negative_numbers = true)]
    input_filter_hz: Option<f64>,
    /// A separate free-motion recording (another motion, same columns) that chooses the
    /// ridge parameter and measures the validation error; every row of --data trains.
    #[arg(long, conflicts_with_all = ["validation_fraction", "folds"])]
    validation: Option<PathBuf>,
    /// Without --validation: contiguous stretches of the rows for blocked
    /// cross-validation (each scored by a fit on the others; at least 2).
    #[arg(long, default_value_t = 5, value_parser = fold_count)]
    folds: usize,
    /// Hold out the last fraction of the rows instead (the tail of the same motion: it
    /// underestimates the error on new motion; kept for compatibility).
    #[arg(long, value_parser = open_fraction, allow_negative_numbers = true, conflicts_with = "folds")]
    validation_fraction: Option<f64>,
    /// An identification file (`admittance identify`) of this arm: the network learns what
    /// it does not explain, `tau - ident.predict(q, qdot, qddot)` (the hybrid observer's
    /// residual network).
    #[arg(long)]
    nominal: Option<PathBuf>,
    /// Seed of the centre placement.
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Model file to write: a new name or a model file (anything else is refused).
    #[arg(long)]
    out: PathBuf,
    /// No progress output on stderr.
    #[arg(long)]
    quiet: bool,
}

#[derive(Args)]
pub struct GrowArgs {
    /// A model written by `admittance train`.
    #[arg(long)]
    model: PathBuf,
    /// Nodes to add.
    #[arg(long, value_parser = positive_count, allow_negative_numbers = true)]
    nodes: usize,
    /// The free-motion data the model was trained on.
    #[arg(long)]
    data: PathBuf,
    /// The validation fraction `train` used (default: the one recorded in the model file;
    /// a different value is an error).
    #[arg(long, value_parser = open_fraction, allow_negative_numbers = true)]
    validation_fraction: Option<f64>,
    /// The input filter `train` used (default: the one recorded in the model file; a
    /// different value is an error).
    #[arg(long, value_parser = non_negative_hz, allow_negative_numbers = true)]
    input_filter_hz: Option<f64>,
    #[command(flatten)]
    arm: OptionalArmArgs,
    /// The identification file `train --nominal` used (needed when the model learned an
    /// identified model's residual; checked against the checksum the model records).
    #[arg(long)]
    nominal: Option<PathBuf>,
    /// Seed of the new centres.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Model file to write: a new name or a model file (the input model too).
    #[arg(long)]
    out: PathBuf,
    /// No progress output on stderr.
    #[arg(long)]
    quiet: bool,
}

fn fmt_list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.4}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Runs `work` with a spinner (or one line on stderr when that is not a terminal).
fn with_progress<T>(quiet: bool, what: String, work: impl FnOnce() -> T) -> (T, f64) {
    let show = progress::wanted(quiet);
    if !quiet && !show {
        eprintln!("{what} ...");
    }
    let started = Instant::now();
    let spinner = Spinner::start(show, what);
    let out = work();
    drop(spinner);
    (out, started.elapsed().as_secs_f64())
}

/// How the ridge parameter is validated, from the flags.
fn validation_split(args: &TrainArgs) -> ValidationSplit {
    match (&args.validation, args.validation_fraction) {
        (Some(_), _) => ValidationSplit::SeparateData,
        (None, Some(fraction)) => ValidationSplit::TrailingFraction { fraction },
        (None, None) => ValidationSplit::BlockedCrossValidation { folds: args.folds },
    }
}

/// Inputs and targets of `path` for `joints` (conditioned, minus the identified model on
/// the torque paired as the identification was fitted: its delay).
fn target_arrays(
    path: &std::path::Path,
    joints: &[String],
    filter_hz: f64,
    ident: Option<&IdentificationFile>,
) -> Result<(admittance_scenario::FreeMotionData, Vec<f64>, Vec<f64>), CliError> {
    let data = data::load(path, Some(joints))?;
    let (x, y) = match ident {
        Some(id) => {
            let (x, mut y) = recorded::network_arrays(&id.paired(path, &data, filter_hz)?);
            data::subtract_identified(&id.ident, &x, &mut y)?;
            (x, y)
        }
        None => data::arrays(path, &data, filter_hz, None)?,
    };
    Ok((data, x, y))
}

pub fn train(args: &TrainArgs) -> Result<(), CliError> {
    check_out(&args.out)?;
    let arm = crate::dynamics_cmd::load(&args.chain)?;
    let joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let ident = match &args.nominal {
        Some(p) => Some(IdentificationFile::load(p, &arm)?),
        None => None,
    };
    // The residual is of the identification on the signals it was fitted on.
    let recorded: Vec<(String, f64)> = ident
        .iter()
        .map(|i| (i.path.display().to_string(), i.input_filter_hz))
        .collect();
    let filter = input_filter_hz(args.input_filter_hz, &recorded)?;
    let id = ident.as_ref();
    let (data, x, y) = target_arrays(&args.data, &joints, filter, id)?;
    let n = data.dof();
    let train_rows = data::training_rows(&args.data, &data, args.validation_fraction)?;
    if args.validation.is_none() {
        data::warn_if_repeating(&args.data, &data, data.t.len(), args.folds);
    }
    let separate = match &args.validation {
        Some(p) => Some((p, target_arrays(p, &joints, filter, id)?)),
        None => None,
    };
    let mut config = BroadConfig {
        nodes: args.nodes,
        friction: FrictionFeatures::for_observer(n, args.friction_features, None),
        cv_folds: args.folds,
        budget: args.budget.budget(),
        // A residual on an identification keeps the identification alone where it does
        // not pay on unseen motion; without a recording of other motion nothing shows that
        // it pays (issue 30): every output is zero.
        zero_unhelpful_outputs: ident.is_some(),
        zero_all_outputs: ident.is_some() && args.validation.is_none(),
        ..BroadConfig::default()
    };
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    let held_out = match &separate {
        Some((_, (v, _, _))) => v.len(),
        None => data.len() - train_rows,
    };
    let size = FitSize::fit(train_rows, held_out, 3 * n, n, &config);
    let estimate = check_budget(&size, &config.budget).map_err(learn_error)?;
    let (train, mut validation) = data::datasets(&args.data, &data, (&x, &y), train_rows, filter)?;
    if let Some((p, (v, xv, yv))) = &separate {
        validation = Some(data::datasets(p, v, (xv, yv), v.len(), filter)?.0);
    }
    let split = validation_split(args);
    let what = format!(
        "training on {train_rows} rows (validation on {split}), {} nodes: {}",
        args.nodes, estimate
    );
    let (result, seconds) = with_progress(args.quiet, what, || {
        fit(&train, validation.as_ref(), &config)
    });
    let (mut net, report) = result.map_err(learn_error)?;
    net.set_arm(arm_identity(&arm)).map_err(learn_error)?;
    net.set_data_settings(DataSettings {
        input_filter_hz: filter,
        validation: split,
        target: match &ident {
            Some(i) => TrainingTarget::IdentifiedResidual {
                checksum: i.checksum,
            },
            None => TrainingTarget::FreeMotionTorque,
        },
    })
    .map_err(learn_error)?;
    net.save(&args.out).map_err(learn_error)?;
    crate::write_stdout(&format!(
        "samples: {}\nvalidation: {split}{}\nvalidation samples: {}\nnodes: {}\nlambda: {:.3e} (relative {:.1e})\ntime: {:.3} s\nvalidation nrmse: [{}]\nexpected false torque on unseen motion (rms, N m): [{}]\n{}coverage threshold: {}\nwrote {}\n",
        report.samples,
        if report.cv_folds > 0 {
            " (every row scored by a fit on the other stretches)"
        } else {
            ""
        },
        report.validation_samples,
        report.nodes,
        report.lambda,
        report.lambda_rel,
        seconds,
        fmt_list(&report.validation_nrmse),
        fmt_list(&report.validation_rmse),
        if config.zero_all_outputs {
            no_evidence_line()
        } else {
            zeroed_line(&report.zeroed_outputs, &joints)
        },
        net.coverage_threshold().map_or("none".into(), |t| format!("{t:.4}")),
        args.out.display()
    ));
    Ok(())
}

/// Why a residual without `--validation` is all zeros.
fn no_evidence_line() -> String {
    "zeroed (every output): no --validation recording of other motion, and cross-validation over \
     one recording is not evidence that a residual pays on new motion; the hybrid observer is the \
     momentum observer on the identification (give another recording as --validation to fit one)\n"
        .into()
}

/// The outputs a residual fit set to zero, by joint name (empty when none).
fn zeroed_line(zeroed: &[usize], joints: &[String]) -> String {
    if zeroed.is_empty() {
        return String::new();
    }
    let names: Vec<&str> = zeroed.iter().map(|&o| joints[o].as_str()).collect();
    format!(
        "zeroed (the residual did not beat the identification alone on unseen motion): [{}]\n",
        names.join(", ")
    )
}

/// The data settings of a growth: the model file's, which explicit flags must agree with;
/// a model that records none (format version 1) takes the flags or their defaults, with a
/// warning.
fn grow_settings(args: &GrowArgs, net: &BroadModel) -> Result<DataSettings, CliError> {
    let model = args.model.display();
    let Some(recorded) = net.provenance().data else {
        let settings = DataSettings {
            input_filter_hz: args.input_filter_hz.unwrap_or(0.0),
            validation: ValidationSplit::TrailingFraction {
                fraction: args.validation_fraction.unwrap_or(0.2),
            },
            target: TrainingTarget::FreeMotionTorque,
        };
        eprintln!(
            "admittance: warning: {model} records no training settings (format version 1): \
             using --input-filter-hz {} and --validation-fraction {}; pass the values `train` used",
            settings.input_filter_hz,
            args.validation_fraction.unwrap_or(0.2)
        );
        return Ok(settings);
    };
    let mut differ = Vec::new();
    if let Some(hz) = args.input_filter_hz {
        if hz.to_bits() != recorded.input_filter_hz.to_bits() {
            differ.push(format!(
                "--input-filter-hz {hz}, but {model} was trained with --input-filter-hz {}",
                recorded.input_filter_hz
            ));
        }
    }
    if let Some(f) = args.validation_fraction {
        if (ValidationSplit::TrailingFraction { fraction: f }) != recorded.validation {
            differ.push(format!(
                "--validation-fraction {f}, but {model} was validated on {}",
                recorded.validation
            ));
        }
    }
    if differ.is_empty() {
        Ok(recorded)
    } else {
        Err(CliError::usage(format!(
            "{}: drop the flag to use the model's setting",
            differ.join("; ")
        )))
    }
}

/// The identification whose residual the model learned (`--nominal`, checked against the
/// recorded checksum), or `None` for another target (where `--nominal` is an error).
fn grow_identification(
    args: &GrowArgs,
    settings: &DataSettings,
    urdf: Option<&admittance_dynamics::Model>,
) -> Result<Option<IdentificationFile>, CliError> {
    let model = args.model.display();
    let TrainingTarget::IdentifiedResidual { checksum } = settings.target else {
        return match &args.nominal {
            Some(_) => Err(CliError::usage(format!(
                "--nominal: {model} learned {}, not an identified model's residual",
                settings.target
            ))),
            None => Ok(None),
        };
    };
    let (Some(path), Some(arm)) = (&args.nominal, urdf) else {
        return Err(CliError::usage(format!(
            "{model} learned an identified model's residual: give its identification file with --nominal and the arm with --urdf"
        )));
    };
    let ident = IdentificationFile::load(path, arm)?;
    let found = ident.checksum;
    if found != checksum {
        return Err(CliError::input(format!(
            "{}: checksum {found:016x}, but {model} learned the residual of the identification with checksum {checksum:016x}",
            path.display()
        )));
    }
    Ok(Some(ident))
}

/// The model's arm checked against `--urdf` (when given) and the joints to read from the
/// data: the recorded ones, else the URDF's, else the file's `q.*` order.
fn grow_joints(
    args: &GrowArgs,
    net: &BroadModel,
    urdf: Option<&admittance_dynamics::Model>,
) -> Result<Option<Vec<String>>, CliError> {
    let model = args.model.display();
    if let Some(arm) = urdf {
        match net.check_arm(&arm_identity(arm)) {
            Ok(ArmCheck::Matches) => {}
            Ok(ArmCheck::Unrecorded) => eprintln!(
                "admittance: warning: {model} records no arm (format version 1): not checked against --urdf"
            ),
            Err(e) => return Err(CliError::input(format!("{model}: {e}"))),
        }
    }
    Ok(match (net.arm(), urdf) {
        (Some(recorded), _) => Some(recorded.joints.clone()),
        (None, Some(arm)) => Some(arm.joint_names().map(String::from).collect()),
        (None, None) => None,
    })
}

pub fn grow(args: &GrowArgs) -> Result<(), CliError> {
    check_out(&args.out)?;
    let mut net = BroadModel::load(&args.model).map_err(|e| CliError::input(e.to_string()))?;
    let settings = grow_settings(args, &net)?;
    let urdf = args.arm.load()?;
    let joints = grow_joints(args, &net, urdf.as_ref())?;
    let data = data::load(&args.data, joints.as_deref())?;
    if let Err(e) = net.check_joints(&data.joints) {
        return Err(CliError::input(format!(
            "{} and {}: {e}",
            args.model.display(),
            args.data.display()
        )));
    }
    let n = data.dof();
    if net.d_in() != 3 * n || net.d_out() != n {
        return Err(CliError::input(format!(
            "{}: the model has {} inputs and {} outputs, the data {} joints",
            args.model.display(),
            net.d_in(),
            net.d_out(),
            n
        )));
    }
    let ident = grow_identification(args, &settings, urdf.as_ref())?;
    let nominal = match settings.target {
        TrainingTarget::FreeMotionTorque | TrainingTarget::IdentifiedResidual { .. } => None,
        TrainingTarget::NominalResidual {
            nominal_inertia_scale,
        } => {
            let Some(arm) = &urdf else {
                return Err(CliError::usage(format!(
                    "{} learned the nominal model's residual (inertia scale {nominal_inertia_scale}): give the arm with --urdf (and --base, --tip)",
                    args.model.display()
                )));
            };
            Some(
                arm.with_scaled_inertias(nominal_inertia_scale)
                    .map_err(|e| CliError::input(e.to_string()))?,
            )
        }
    };
    let fraction = match settings.validation {
        ValidationSplit::TrailingFraction { fraction } => Some(fraction),
        ValidationSplit::SeparateData
        | ValidationSplit::NoValidation
        | ValidationSplit::BlockedCrossValidation { .. } => None,
    };
    let train_rows = data::training_rows(&args.data, &data, fraction)?;
    let mut config = BroadConfig {
        friction: net.friction().clone(),
        budget: args.budget.budget(),
        ..BroadConfig::default()
    };
    if let Some(centres) = net
        .provenance()
        .fit
        .as_ref()
        .and_then(|f| f.centres.as_ref())
    {
        config.centre_subsample = centres.centre_subsample;
        config.widths = centres.widths.clone();
    }
    let size = FitSize::growth(
        &net,
        train_rows,
        data.len() - train_rows,
        args.nodes,
        &config,
    );
    let estimate = check_budget(&size, &config.budget).map_err(learn_error)?;
    let (x, y) = match &ident {
        // The identification's residual on the torque paired as it was fitted (as `train`).
        Some(id) => {
            let (x, mut y) = recorded::network_arrays(&id.paired(
                &args.data,
                &data,
                settings.input_filter_hz,
            )?);
            data::subtract_identified(&id.ident, &x, &mut y)?;
            (x, y)
        }
        None => data::arrays(
            &args.data,
            &data,
            settings.input_filter_hz,
            nominal.as_ref(),
        )?,
    };
    let (train, validation) = data::datasets(
        &args.data,
        &data,
        (&x, &y),
        train_rows,
        settings.input_filter_hz,
    )?;
    let what = format!(
        "growing by {} nodes on {train_rows} rows: {}",
        args.nodes, estimate
    );
    let spec = GrowthSpec::KMeansPlusPlus {
        count: args.nodes,
        seed: args.seed,
    };
    let (result, seconds) = with_progress(args.quiet, what, || net.grow(&train, &spec, &config));
    let report = result.map_err(|e| match e {
        BroadError::GrowthDataMismatch(_) => CliError::input(format!(
            "{} and {}: {e} (grow needs the rows the model was trained on, with its input filter and validation split)",
            args.data.display(),
            args.model.display()
        )),
        other => learn_error(other),
    })?;
    let nrmse = match &validation {
        Some(v) => net.evaluate(v, 0).map_err(learn_error)?,
        None => Vec::new(),
    };
    if let Some(bad) = nrmse.iter().find(|e| !e.is_finite()) {
        return Err(CliError {
            code: 1,
            message: format!("the grown network's validation NRMSE is {bad}; nothing written"),
        });
    }
    net.save(&args.out).map_err(learn_error)?;
    crate::write_stdout(&format!(
        "samples: {}\nnodes: {} (+{})\nlambda: {:.3e}\ntime: {:.3} s\nvalidation nrmse: [{}]\nwrote {}\n",
        train_rows,
        report.nodes,
        report.nodes_added,
        net.lambda(),
        seconds,
        fmt_list(&nrmse),
        args.out.display()
    ));
    Ok(())
}
