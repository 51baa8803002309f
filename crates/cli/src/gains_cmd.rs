//! `admittance gains`: a starting set of gains for an arm, from its model (the rules of
//! `admittance_control::gains`, docs/method.md section 3), printed as TOML to paste into a
//! scenario.

use std::fmt::Write as _;

use admittance_control::gains::{self, JointInertia, LoopLimits, SUGGESTED_K1};
use clap::Args;

use crate::dynamics_cmd::{load, parse_list, ChainArgs};
use crate::CliError;

#[derive(Args)]
pub struct GainsArgs {
    #[command(flatten)]
    chain: ChainArgs,
    /// The pose the arm works around, comma-separated, chain order (default: the middle of
    /// each joint's limits). Joint inertias are taken there.
    #[arg(long, allow_hyphen_values = true)]
    q: Option<String>,
    /// Control rate (Hz), `plant.control_rate_hz`.
    #[arg(long, default_value_t = 1000.0)]
    rate: f64,
    /// Cut-off of the velocity estimate's low-pass (Hz), `plant.sensors.filter_cutoff_hz`
    /// (the committed scenarios use 40).
    #[arg(long, default_value_t = 40.0)]
    filter_hz: f64,
    /// The estimate's low-pass (Hz), `observer.cutoff_hz`: bounds the admittance.
    #[arg(long, default_value_t = 5.0)]
    estimate_hz: f64,
}

fn list(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    format!("[{}]", parts.join(", "))
}

pub fn gains(args: &GainsArgs) -> Result<(), CliError> {
    for (flag, v) in [
        ("--rate", args.rate),
        ("--filter-hz", args.filter_hz),
        ("--estimate-hz", args.estimate_hz),
    ] {
        if !(v.is_finite() && v >= 0.0) || (flag == "--rate" && v == 0.0) {
            return Err(CliError::usage(format!(
                "{flag} {v}: must be a finite number > 0"
            )));
        }
    }
    let model = load(&args.chain)?;
    let n = model.nq();
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let pose = match &args.q {
        Some(text) => parse_list("q", text, n, "one angle per joint in chain order")?,
        None => admittance_scenario::mid_range(&model),
    };
    let inertia = JointInertia::over(&model, [pose.as_slice()]);
    let limits = LoopLimits {
        control_rate_hz: args.rate,
        velocity_filter_hz: args.filter_hz,
        damping: vec![0.0; n],
    };
    let k1 = vec![SUGGESTED_K1; n];
    let k2: Vec<f64> = (0..n)
        .map(|j| gains::suggested_k2(SUGGESTED_K1, &inertia, &limits, j))
        .collect();
    let kp: Vec<f64> = k2
        .iter()
        .map(|k| gains::round2(SUGGESTED_K1 * k, false))
        .collect();
    let (damping, stiffness) = (vec![3.0; n], vec![5.0; n]);
    let mut advice =
        gains::check_feedback("controller.neural.k2", &joints, &k1, &k2, &inertia, &limits);
    advice.extend(gains::check_admittance(
        "admittance",
        &joints,
        &damping,
        &stiffness,
        None,
        args.estimate_hz,
    ));

    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Starting gains for {} ({} -> {}, {n} joints) from {}",
        model.robot_name,
        model.base_link,
        model.tip().name,
        args.chain_urdf()
    );
    let _ = writeln!(
        out,
        "# at the pose q = {} ({}), {} Hz control, {} Hz velocity filter,",
        list(&pose),
        if args.q.is_some() {
            "--q"
        } else {
            "the middle of the limits"
        },
        args.rate,
        args.filter_hz
    );
    let _ = writeln!(
        out,
        "# {} Hz estimate filter. Joint inertia there (diagonal of M, kg m^2):",
        args.estimate_hz
    );
    let _ = writeln!(
        out,
        "#   {}",
        joints
            .iter()
            .zip(&inertia.max)
            .map(|(j, i)| format!("{j} {i:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(out, "# Rules (docs/method.md section 3): K2 > K1 I; K2 / I under {:.0} rad/s (half the velocity", limits.velocity_bandwidth());
    let _ = writeln!(out, "# filter's bandwidth, half the control rate); here K2 = {} K1 I where the filter allows it.", gains::SUGGESTED_MARGIN);
    let _ = writeln!(
        out,
        "# A scenario that moves far from this pose is checked again when it loads."
    );
    let _ = writeln!(out, "[controller.neural]");
    let _ = writeln!(out, "k1 = {SUGGESTED_K1:?}");
    let _ = writeln!(out, "k2 = {}", list(&k2));
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "# The same loop without learning (a PD baseline variant): kp = K1 K2, kd = K2."
    );
    let _ = writeln!(
        out,
        "# controller.pd = {{ kp = {}, kd = {} }}",
        list(&kp),
        list(&k2)
    );
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "# The paper's admittance; G_d / C_d stays under half the estimate's bandwidth."
    );
    let _ = writeln!(out, "[admittance]");
    let _ = writeln!(out, "damping = 3.0");
    let _ = writeln!(out, "stiffness = 5.0");
    if advice.is_empty() {
        let _ = writeln!(out, "# Every value passes the gain rules.");
    }
    crate::write_stdout(&out);
    for a in &advice {
        eprintln!(
            "admittance: warning: {} ({}[{}], {}): {}",
            a.rule, a.key, a.index, a.joint, a.message
        );
    }
    Ok(())
}

impl GainsArgs {
    fn chain_urdf(&self) -> String {
        self.chain.urdf_path().display().to_string()
    }
}
