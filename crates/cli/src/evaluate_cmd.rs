//! `admittance evaluate`: every estimator the files given allow, run over a stretch of a
//! free-motion recording (no external force: every output is a false torque). Static
//! models predict the torque sample by sample; the momentum and hybrid observers run over
//! the stretch as a time series from its first sample. The table the identification
//! experiment quotes (docs/experiments.md, "Identification on a real Baxter").

use std::path::{Path, PathBuf};
use std::sync::Arc;

use admittance_control::{
    HybridObserver, MomentumObserver, MomentumObserverConfig, Observer, ObserverInput, StepStatus,
};
use admittance_dynamics::{rnea, Data, Identification};
use admittance_learning::broad::BroadModel;
use clap::Args;

use crate::identify_cmd::Conditioned;
use crate::train_cmd::{
    check_network, input_filter_hz, network_filter_hz, non_negative_hz, positive_number,
    IdentificationFile, Learned,
};
use crate::CliError;

/// `--from`: a time in seconds, finite and >= 0.
fn non_negative_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err("the value must be a time >= 0 s".into()),
    }
}

#[derive(Args)]
pub struct EvaluateArgs {
    /// Free-motion recording (CSV, docs/outputs.md).
    #[arg(long)]
    data: PathBuf,
    #[command(flatten)]
    chain: crate::dynamics_cmd::ChainArgs,
    /// Evaluate the rows with t >= FROM (s) only.
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_seconds, allow_negative_numbers = true)]
    from: f64,
    /// An identification file (`admittance identify`) of this arm.
    #[arg(long)]
    identification: Option<PathBuf>,
    /// A network trained on the torque (`admittance train`): the paper's learned model. A
    /// residual network (`train --nominal`) given here is recognised from its file.
    #[arg(long)]
    network: Vec<PathBuf>,
    /// A network trained on the identification's residual (`admittance train --nominal`).
    #[arg(long)]
    residual: Option<PathBuf>,
    /// Input conditioning (Hz); 0: columns as recorded. Default: the one the files record
    /// (another value is an error), else 0.
    #[arg(long, value_parser = non_negative_hz, allow_negative_numbers = true)]
    input_filter_hz: Option<f64>,
    /// Momentum observer gain K_O (1/s); beyond one over the sample period it is taken as
    /// that (the estimate cannot follow faster than one sample).
    #[arg(long, default_value_t = 50.0, value_parser = positive_number)]
    gain: f64,
    /// A contact floor (`admittance calibrate-contact`): also count the false alarms it
    /// raises on the evaluated rows.
    #[arg(long, requires = "identification")]
    contact_floor: Option<PathBuf>,
}

/// Per-joint squared-error sums of one estimator.
struct Score {
    name: String,
    sq: Vec<f64>,
    count: usize,
}

impl Score {
    fn new(name: impl Into<String>, n: usize) -> Self {
        Score {
            name: name.into(),
            sq: vec![0.0; n],
            count: 0,
        }
    }
    fn add(&mut self, false_torque: &[f64]) {
        for (s, e) in self.sq.iter_mut().zip(false_torque) {
            *s += e * e;
        }
        self.count += 1;
    }
}

fn load_network(path: &PathBuf, n: usize) -> Result<BroadModel, CliError> {
    let net = BroadModel::load(path).map_err(|e| CliError::input(e.to_string()))?;
    check_sizes(path, &net, n)?;
    Ok(net)
}

fn check_sizes(path: &Path, net: &BroadModel, n: usize) -> Result<(), CliError> {
    if net.d_in() != 3 * n || net.d_out() != n {
        return Err(CliError::input(format!(
            "{}: maps {} inputs to {} outputs; this arm needs [q, qdot, qddot] ({}) to {n}",
            path.display(),
            net.d_in(),
            net.d_out(),
            3 * n
        )));
    }
    Ok(())
}

/// The files' networks and residual, each checked against the arm and the identification
/// (a residual given as `--network` is recognised and moved to the residual).
type Networks = (Vec<(String, BroadModel)>, Option<(PathBuf, BroadModel)>);

fn load_networks(
    args: &EvaluateArgs,
    arm: &admittance_dynamics::Model,
    ident: Option<&IdentificationFile>,
) -> Result<Networks, CliError> {
    let n = arm.nq();
    let mut networks = Vec::new();
    let mut residual = None;
    for p in &args.network {
        let net = load_network(p, n)?;
        match check_network(p, &net, arm, ident)? {
            Learned::Torque | Learned::Unrecorded => networks.push((p.display().to_string(), net)),
            Learned::IdentifiedResidual => {
                if let Some((q, _)) = residual.replace((p.clone(), net)) {
                    return Err(CliError::usage(format!(
                        "{} and {}: two residual networks; evaluate one at a time",
                        q.display(),
                        p.display()
                    )));
                }
                eprintln!(
                    "admittance: {} learned the residual of {}: scored as the identification + residual (as --residual)",
                    p.display(),
                    ident.map_or(String::new(), |i| i.path.display().to_string())
                );
            }
        }
    }
    if let Some(p) = &args.residual {
        if residual.is_some() {
            return Err(CliError::usage(format!(
                "--residual {} and a residual network among --network: evaluate one at a time",
                p.display()
            )));
        }
        let net = load_network(p, n)?;
        if ident.is_none() {
            return Err(CliError::usage(
                "--residual needs --identification (the model whose residual it learned)",
            ));
        }
        if check_network(p, &net, arm, ident)? == Learned::Torque {
            return Err(CliError::usage(format!(
                "--residual {}: it learned the free-motion torque, not a residual: give it with --network",
                p.display()
            )));
        }
        residual = Some((p.clone(), net));
    }
    Ok((networks, residual))
}

/// The conditioning the files record (the flag must agree), and the conditioned rows.
fn conditioning(
    args: &EvaluateArgs,
    ident: Option<&IdentificationFile>,
    (networks, residual): &Networks,
) -> Result<f64, CliError> {
    let mut recorded: Vec<(String, f64)> = ident
        .iter()
        .map(|i| (i.path.display().to_string(), i.input_filter_hz))
        .collect();
    let nets = networks
        .iter()
        .map(|(name, net)| (name.clone(), net))
        .chain(
            residual
                .iter()
                .map(|(p, net)| (p.display().to_string(), net)),
        );
    for (name, net) in nets {
        if let Some(hz) = network_filter_hz(net) {
            recorded.push((name, hz));
        }
    }
    input_filter_hz(args.input_filter_hz, &recorded)
}

pub fn evaluate(args: &EvaluateArgs) -> Result<(), CliError> {
    let arm = crate::dynamics_cmd::load(&args.chain)?;
    let joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let data = crate::train_cmd::load_data(&args.data, Some(&joints))?;
    let first = data.t.iter().take_while(|t| **t < args.from).count();
    if data.len() - first < 10 {
        return Err(CliError::usage(format!(
            "--from {}: only {} rows of {} are at or after it (its time runs from {} to {} s; \
             --from is a time of that column)",
            args.from,
            data.len() - first,
            args.data.display(),
            data.t.first().copied().unwrap_or(f64::NAN),
            data.t.last().copied().unwrap_or(f64::NAN)
        )));
    }
    if args.from > 0.0 && first == 0 {
        eprintln!(
            "admittance: warning: --from {}: every row of {} is at or after it (its time starts at {} s): all of it is scored",
            args.from,
            args.data.display(),
            data.t[0]
        );
    }
    let n = arm.nq();
    let ident_file = match &args.identification {
        Some(p) => Some(IdentificationFile::load(p, &arm)?),
        None => None,
    };
    let loaded = load_networks(args, &arm, ident_file.as_ref())?;
    let filter = conditioning(args, ident_file.as_ref(), &loaded)?;
    let rows = Conditioned::new(&args.data, &data, filter)?;
    // The identification's rows: the torque paired with the motion as it was fitted.
    let paired = match &ident_file {
        Some(i) => Some(i.paired(&args.data, &data, filter)?),
        None => None,
    };
    let (networks, residual) = loaded;
    let residual = residual.map(|(_, net)| net);
    let ident: Option<Identification> = ident_file.map(|i| i.ident);
    let config = MomentumObserverConfig {
        gain: admittance_control::JointValues::Uniform(args.gain),
    };
    let err = |e: admittance_control::ConfigError| CliError::usage(e.to_string());
    let mut observers: Vec<(String, Box<dyn Observer>)> = vec![(
        "momentum (URDF)".into(),
        Box::new(MomentumObserver::new(Arc::new(arm.clone()), &config).map_err(err)?),
    )];
    if let Some(id) = &ident {
        observers.push((
            "momentum (identified)".into(),
            Box::new(MomentumObserver::from_identification(id, &config).map_err(err)?),
        ));
        if let Some(r) = &residual {
            let m = MomentumObserver::from_identification(id, &config).map_err(err)?;
            observers.push((
                "hybrid (identified + residual)".into(),
                Box::new(HybridObserver::new(m, r.clone()).map_err(err)?),
            ));
        }
    }
    let mut statics: Vec<Score> = vec![Score::new("URDF (RNEA)", n)];
    if ident.is_some() {
        statics.push(Score::new("identified, rigid body only", n));
        statics.push(Score::new("identified + joint terms", n));
        if residual.is_some() {
            statics.push(Score::new("identified + residual network", n));
        }
    }
    for (name, _) in &networks {
        statics.push(Score::new(format!("network {name}"), n));
    }
    let mut dynamic: Vec<Score> = observers
        .iter()
        .map(|(name, _)| Score::new(name.clone(), n))
        .collect();
    let mut faults = vec![0usize; observers.len()];
    let (mut data_urdf, mut out, mut est, mut x) = (
        Data::new(&arm),
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; 3 * n],
    );
    let mut data_ident = ident.as_ref().map(|i| Data::new(&i.model));
    // The share of `q''` the identification's predictions take follows the motion from its
    // first row (`AccelerationGains`), at the identification's sample rate.
    let mut acceleration_gains = ident.as_ref().map(|i| {
        let mut gains = admittance_dynamics::AccelerationGains::new(&i.summary, None);
        let mut g = vec![0.0; n];
        for k in 0..first {
            gains.update(&rows.qddot[k * n..(k + 1) * n], &mut g);
        }
        (gains, g)
    });
    let mut ws = networks
        .first()
        .map(|(_, m)| m.workspace())
        .or_else(|| residual.as_ref().map(|r| r.workspace()))
        .unwrap_or_default();
    let (mut tau_sum, mut tau_sq) = (vec![0.0; n], vec![0.0; n]);
    // The residual network's coverage of each evaluated sample (1: inside its data).
    let (mut coverage_sum, mut outside) = (0.0, 0usize);
    for k in first..data.len() {
        let r = k * n..(k + 1) * n;
        let (q, qd, qdd, tau) = (
            &rows.q[r.clone()],
            &rows.qdot[r.clone()],
            &rows.qddot[r.clone()],
            &rows.tau[r.clone()],
        );
        let tau_id = paired.as_ref().map_or(tau, |p| &p.tau[r.clone()]);
        // nMSE is relative to the recorded torque's variance (not the conditioned one).
        for i in 0..n {
            let raw = data.tau[k * n + i];
            tau_sum[i] += raw;
            tau_sq[i] += raw * raw;
        }
        x[..n].copy_from_slice(q);
        x[n..2 * n].copy_from_slice(qd);
        x[2 * n..].copy_from_slice(qdd);
        let model_tau =
            rnea(&arm, &mut data_urdf, q, qd, qdd).map_err(|e| CliError::input(e.to_string()))?;
        let mut s = 0;
        let diff = |a: &[f64], b: &[f64], o: &mut [f64]| {
            o.iter_mut().enumerate().for_each(|(i, v)| *v = a[i] - b[i])
        };
        diff(tau, model_tau.as_slice(), &mut out);
        statics[s].add(&out);
        s += 1;
        if let (Some(id), Some(d)) = (&ident, data_ident.as_mut()) {
            let rigid =
                rnea(&id.model, d, q, qd, qdd).map_err(|e| CliError::input(e.to_string()))?;
            diff(tau_id, rigid.as_slice(), &mut out);
            statics[s].add(&out);
            s += 1;
            if let Some((gains, g)) = acceleration_gains.as_mut() {
                gains.update(qdd, g);
                id.predict_with_gains(d, q, qd, qdd, g, &mut est)
                    .map_err(|e| CliError::input(e.to_string()))?;
            }
            diff(tau_id, &est, &mut out);
            statics[s].add(&out);
            s += 1;
            if let Some(r) = &residual {
                let c = r
                    .coverage(&x, &mut ws)
                    .map_err(|e| CliError::input(e.to_string()))?;
                coverage_sum += c;
                outside += usize::from(c < 1.0);
                let full = est.clone();
                r.predict_into(&x, &mut est, &mut ws)
                    .map_err(|e| CliError::input(e.to_string()))?;
                for i in 0..n {
                    out[i] = tau_id[i] - full[i] - est[i];
                }
                statics[s].add(&out);
                s += 1;
            }
        }
        for (_, net) in &networks {
            net.predict_into(&x, &mut est, &mut ws)
                .map_err(|e| CliError::input(e.to_string()))?;
            diff(tau, &est, &mut out);
            statics[s].add(&out);
            s += 1;
        }
        let dt = if k > 0 {
            data.t[k] - data.t[k - 1]
        } else {
            0.01
        };
        let input = ObserverInput {
            time: data.t[k],
            q,
            qdot: qd,
            qddot: qdd,
            tau_commanded: tau,
        };
        // The observers on the identification take its pairing (the first is the URDF's).
        let input_id = ObserverInput {
            tau_commanded: tau_id,
            ..input
        };
        for (o, ((_, obs), score)) in observers.iter_mut().zip(dynamic.iter_mut()).enumerate() {
            let input = if o == 0 { &input } else { &input_id };
            if !matches!(obs.update(input, dt, &mut est), StepStatus::Ok) {
                faults[o] += 1;
            }
            score.add(&est);
        }
    }
    let count = (data.len() - first) as f64;
    let var: Vec<f64> = (0..n)
        .map(|i| (tau_sq[i] / count - (tau_sum[i] / count).powi(2)).max(1e-12))
        .collect();
    let span = data.t[data.len() - 1] - data.t[0];
    let rate = (data.len() - 1) as f64 / span;
    let gain_note = if span > 0.0 && args.gain > rate {
        format!("momentum observer gain {} /s at {rate:.0} Hz samples: taken as {rate:.0} /s (one sample's period; --gain)\n", args.gain)
    } else {
        String::new()
    };
    let mut text = format!(
        "{} rows of {} from t = {:.2} s ({:.1} s), no external force: every estimate is a false torque\ninput filter: {}\n{gain_note}{:<34} {:>8} {:>7}  per joint rms (N m)\n",
        data.len() - first, args.data.display(), data.t[first], data.t[data.len() - 1] - data.t[first],
        if filter > 0.0 { format!("{filter} Hz") } else { "none (the columns as recorded)".into() },
        "estimator", "rms N m", "nMSE"
    );
    let mut bad = false;
    for (k, score) in statics.iter().chain(dynamic.iter()).enumerate() {
        let c = score.count.max(1) as f64;
        let rms = (score.sq.iter().sum::<f64>() / (c * n as f64)).sqrt();
        let nmse = score
            .sq
            .iter()
            .zip(&var)
            .map(|(s, v)| s / c / v)
            .sum::<f64>()
            / n as f64;
        bad |= !rms.is_finite();
        let joints: Vec<String> = score
            .sq
            .iter()
            .map(|s| format!("{:.2}", (s / c).sqrt()))
            .collect();
        let fault = k.checked_sub(statics.len()).map_or(String::new(), |o| {
            if faults[o] > 0 {
                format!("  ({} faults)", faults[o])
            } else {
                String::new()
            }
        });
        text += &format!(
            "{:<34} {:>8.3} {:>7.3}  {}{fault}\n",
            score.name,
            rms,
            nmse,
            joints.join(" ")
        );
    }
    if residual.is_some() {
        text += &format!(
            "residual network coverage: mean {:.3}, {} of {} samples outside its training data (correction faded)\n",
            coverage_sum / count,
            outside,
            data.len() - first
        );
    }
    if ident.is_some() {
        let rms = |score: &Score| {
            let c = score.count.max(1) as f64;
            (score.sq.iter().sum::<f64>() / (c * n as f64)).sqrt()
        };
        let (urdf, fitted) = (rms(&statics[0]), rms(&statics[2]));
        if fitted > urdf {
            text += &format!(
                "the identification predicts these rows worse than the URDF alone ({fitted:.3} against \
                 {urdf:.3} N m): where they leave its training range or speeds (below) it extrapolates; \
                 elsewhere check the recording's signs and units against the one identified\n"
            );
        }
    }
    if let Some(id) = &ident {
        text += &crate::training_range::report(id, &arm, &rows.q[first * n..]);
        text += &crate::training_speed::report(id, &arm, &rows.qdot[first * n..]);
    }
    if let Some(floor) = &args.contact_floor {
        let (id, from) = (ident.as_ref(), args.from);
        text += &crate::evaluate_contact::false_alarm_table(
            floor, &args.data, &data, from, id, filter,
        )?;
    }
    crate::write_stdout(&text);
    if bad {
        return Err(CliError {
            code: 1,
            message: "an estimate was not finite".into(),
        });
    }
    Ok(())
}
