//! `admittance train` and `admittance grow`: the flat RBF network of the learned observer
//! (METHOD.md section 5) from free-motion data (docs/outputs.md, "Free-motion data").
//!
//! Inputs `[q, qdot, qddot]`, targets `tau`. The last `--validation-fraction` of the rows
//! (by time, default 20%) is held out: lambda is chosen on it (the broad module's grid) and
//! the printed validation NRMSE is measured on it. `grow` needs the same data the model was
//! trained on (the growth state is the factorisation of that data's Gram matrix).

use std::path::{Path, PathBuf};
use std::time::Instant;

use admittance_learning::broad::{
    fit, BroadConfig, BroadModel, Dataset, FrictionFeatures, GrowthSpec,
};
use admittance_scenario::FreeMotionData;
use clap::Args;

use crate::progress::{self, Spinner};
use crate::CliError;

#[derive(Args)]
pub struct TrainArgs {
    /// Free-motion data (CSV: t, q.J, qdot.J, qddot.J, tau.J).
    #[arg(long)]
    data: PathBuf,
    /// The arm (`--urdf`, `--base`, `--tip`): the data's joints must be its joints, in chain order.
    #[command(flatten)]
    chain: crate::dynamics_cmd::ChainArgs,
    /// Enhancement (Gaussian) nodes L.
    #[arg(long, default_value_t = 1000)]
    nodes: usize,
    /// Add friction-shaped inputs tanh(qdot / v) (METHOD.md section 7).
    #[arg(long)]
    friction_features: bool,
    /// Second low-pass (Hz) on q and tau before differentiating again, the observer input
    /// conditioning of the scenarios (`observer.input_filter_hz`); 0: the columns as recorded.
    /// The observer must be fed the same conditioning at run time (`admittance_sim::InputConditioner`).
    #[arg(long, default_value_t = 0.0)]
    input_filter_hz: f64,
    /// Fraction of the rows, at the end, held out for validation.
    #[arg(long, default_value_t = 0.2)]
    validation_fraction: f64,
    /// Seed of the centre placement.
    #[arg(long)]
    seed: Option<u64>,
    /// Model file to write.
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
    #[arg(long)]
    nodes: usize,
    /// The free-motion data the model was trained on.
    #[arg(long)]
    data: PathBuf,
    /// The validation fraction used by `train`.
    #[arg(long, default_value_t = 0.2)]
    validation_fraction: f64,
    /// The input filter used by `train`.
    #[arg(long, default_value_t = 0.0)]
    input_filter_hz: f64,
    /// Seed of the new centres.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Model file to write.
    #[arg(long)]
    out: PathBuf,
    /// No progress output on stderr.
    #[arg(long)]
    quiet: bool,
}

fn load_split(
    path: &Path,
    fraction: f64,
    input_filter_hz: f64,
) -> Result<(FreeMotionData, Vec<f64>, Vec<f64>, usize), CliError> {
    if !(fraction > 0.0 && fraction < 1.0) {
        return Err(CliError::usage(format!(
            "--validation-fraction is {fraction}, must be in (0, 1)"
        )));
    }
    let data = FreeMotionData::load(path).map_err(|e| CliError::input(e.to_string()))?;
    let train_rows = ((data.len() as f64) * (1.0 - fraction)).floor() as usize;
    if train_rows < 2 || train_rows >= data.len() {
        return Err(CliError::input(format!(
            "{}: {} rows are too few to split for validation",
            path.display(),
            data.len()
        )));
    }
    // `[q, qdot, qddot]` and `tau`, row-major, conditioned as at run time.
    let (x, y) =
        admittance_scenario::observer_training_arrays(&data, input_filter_hz).map_err(|e| {
            CliError::usage(format!(
                "--input-filter-hz {input_filter_hz} with the data of {}: {e}",
                path.display()
            ))
        })?;
    Ok((data, x, y, train_rows))
}

fn learn_err(e: impl std::fmt::Display) -> CliError {
    CliError {
        code: 1,
        message: e.to_string(),
    }
}

fn fmt_list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.4}"))
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn train(args: &TrainArgs) -> Result<(), CliError> {
    let model = crate::dynamics_cmd::load(&args.chain)?;
    let (data, x, y, train_rows) =
        load_split(&args.data, args.validation_fraction, args.input_filter_hz)?;
    let joints: Vec<&str> = model.joint_names().collect();
    if data
        .joints
        .iter()
        .map(String::as_str)
        .ne(joints.iter().copied())
    {
        return Err(CliError::input(format!(
            "{}: joints [{}] are not the arm's [{}] (chain order)",
            args.data.display(),
            data.joints.join(", "),
            joints.join(", ")
        )));
    }
    let n = data.dof();
    let train = Dataset::new(&x[..train_rows * 3 * n], &y[..train_rows * n], 3 * n, n)
        .map_err(learn_err)?;
    let validation = Dataset::new(&x[train_rows * 3 * n..], &y[train_rows * n..], 3 * n, n)
        .map_err(learn_err)?;
    let mut config = BroadConfig {
        nodes: args.nodes,
        friction: if args.friction_features {
            FrictionFeatures::joint_velocities(n)
        } else {
            FrictionFeatures::none()
        },
        ..BroadConfig::default()
    };
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    let what = format!(
        "training on {} rows ({} held out), {} nodes",
        train_rows,
        data.len() - train_rows,
        args.nodes
    );
    let show = progress::wanted(args.quiet);
    if !args.quiet && !show {
        eprintln!("{what} ...");
    }
    let started = Instant::now();
    let spinner = Spinner::start(show, what);
    let (net, report) = fit(&train, Some(&validation), &config).map_err(learn_err)?;
    let seconds = started.elapsed().as_secs_f64();
    drop(spinner);
    net.save(&args.out).map_err(learn_err)?;
    crate::write_stdout(&format!(
        "samples: {}\nvalidation samples: {}\nnodes: {}\nlambda: {:.3e} (relative {:.1e})\ntime: {:.3} s\nvalidation nrmse: [{}]\nwrote {}\n",
        report.samples,
        report.validation_samples,
        report.nodes,
        report.lambda,
        report.lambda_rel,
        seconds,
        fmt_list(&report.validation_nrmse),
        args.out.display()
    ));
    Ok(())
}

pub fn grow(args: &GrowArgs) -> Result<(), CliError> {
    let mut net = BroadModel::load(&args.model).map_err(|e| CliError::input(e.to_string()))?;
    let (data, x, y, train_rows) =
        load_split(&args.data, args.validation_fraction, args.input_filter_hz)?;
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
    let train = Dataset::new(&x[..train_rows * 3 * n], &y[..train_rows * n], 3 * n, n)
        .map_err(learn_err)?;
    let validation = Dataset::new(&x[train_rows * 3 * n..], &y[train_rows * n..], 3 * n, n)
        .map_err(learn_err)?;
    let config = BroadConfig {
        friction: net.friction().clone(),
        ..BroadConfig::default()
    };
    let started = Instant::now();
    let spinner = Spinner::start(
        progress::wanted(args.quiet),
        format!("growing by {} nodes on {} rows", args.nodes, train_rows),
    );
    let report = net
        .grow(
            &train,
            &GrowthSpec::KMeansPlusPlus {
                count: args.nodes,
                seed: args.seed,
            },
            &config,
        )
        .map_err(learn_err)?;
    let seconds = started.elapsed().as_secs_f64();
    drop(spinner);
    let nrmse = net.evaluate(&validation, 0).map_err(learn_err)?;
    net.save(&args.out).map_err(learn_err)?;
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
