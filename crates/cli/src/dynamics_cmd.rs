//! `admittance dynamics` and `admittance model`.

use std::path::PathBuf;

use admittance_dynamics::{
    coriolis_matrix, crba, forward_kinematics, gravity_torque, rnea, tip_jacobian, Data,
    DynamicsError, JointKind, Model, UrdfOptions,
};
use clap::Args;
use serde_json::json;

use crate::CliError;

#[derive(Args)]
pub struct ChainArgs {
    /// URDF file of the arm.
    #[arg(long)]
    urdf: PathBuf,
    /// Base link (default: the URDF's root link).
    #[arg(long)]
    base: Option<String>,
    /// Tip link (default: the arm's hand: the end of the deepest moving joint, past
    /// gripper fingers; `admittance model` shows what was chosen).
    #[arg(long)]
    tip: Option<String>,
    /// Refuse physically impossible inertias on the chain instead of loading them with a
    /// warning.
    #[arg(long)]
    strict: bool,
    /// Hold a joint of a branch off the chain, or above the base (it turns the mount, and
    /// gravity with it), at VALUE (rad or m) instead of 0; repeatable.
    #[arg(long, value_name = "JOINT=VALUE", allow_hyphen_values = true)]
    lock: Vec<String>,
    /// Leave the branch behind JOINT out of the model (its mass too) instead of locking it;
    /// repeatable.
    #[arg(long, value_name = "JOINT")]
    drop: Vec<String>,
}

impl ChainArgs {
    /// The URDF file.
    pub fn urdf_path(&self) -> &std::path::Path {
        &self.urdf
    }

    /// The loader's options from the flags.
    fn options(&self) -> Result<UrdfOptions, CliError> {
        let mut lock = Vec::new();
        for item in &self.lock {
            let parsed = item
                .split_once('=')
                .and_then(|(j, v)| Some((j.trim(), v.trim().parse::<f64>().ok()?)));
            match parsed {
                Some((joint, value)) if !joint.is_empty() && value.is_finite() => {
                    lock.push((joint.to_string(), value))
                }
                _ => {
                    return Err(CliError::usage(format!(
                        "--lock {item}: write JOINT=VALUE with a finite VALUE in rad or m, e.g. --lock head_pan=0.3"
                    )))
                }
            }
        }
        Ok(UrdfOptions {
            base: self.base.clone(),
            tip: self.tip.clone(),
            strict: self.strict,
            lock,
            drop: self.drop.clone(),
        })
    }
}

#[derive(Args)]
pub struct DynamicsArgs {
    #[command(flatten)]
    chain: ChainArgs,
    /// Joint positions, comma-separated, chain order (continuous joints: the angle).
    #[arg(long, allow_hyphen_values = true)]
    q: String,
    /// Joint velocities (default zeros).
    #[arg(long, allow_hyphen_values = true)]
    v: Option<String>,
    /// Joint accelerations (default zeros).
    #[arg(long, allow_hyphen_values = true)]
    a: Option<String>,
    /// Gravity in the base frame, GX,GY,GZ (default 0,0,-9.81).
    #[arg(long, allow_hyphen_values = true)]
    gravity: Option<String>,
}

#[derive(Args)]
pub struct ModelArgs {
    #[command(flatten)]
    chain: ChainArgs,
}

/// Loads the chain the flags describe and prints the loader's warnings on stderr. Any
/// file that cannot be read or understood (missing, not UTF-8, not a valid URDF) is bad
/// input (exit 3).
pub fn load(chain: &ChainArgs) -> Result<Model, CliError> {
    let options = chain.options()?;
    let model = Model::from_urdf_file_with(&chain.urdf, &options).map_err(|e| match e {
        DynamicsError::Io { .. } => CliError::input(format!("{e}; check the --urdf path")),
        other => CliError::input(other.to_string()),
    })?;
    for w in model.warnings() {
        eprintln!("admittance: warning: {w}");
    }
    Ok(model)
}

/// Parses `a,b,c` into exactly `expected` finite numbers.
pub fn parse_list(
    flag: &str,
    text: &str,
    expected: usize,
    what: &str,
) -> Result<Vec<f64>, CliError> {
    let mut values = Vec::new();
    for (k, part) in text.split(',').enumerate() {
        let part = part.trim();
        match part.parse::<f64>() {
            Ok(v) if v.is_finite() => values.push(v),
            _ => {
                return Err(CliError::usage(format!(
                    "--{flag}: value {} ({part:?}) is not a finite number",
                    k + 1
                )))
            }
        }
    }
    if values.len() != expected {
        return Err(CliError::usage(format!(
            "--{flag} has {} values but needs {expected} ({what})",
            values.len()
        )));
    }
    Ok(values)
}

fn rows(m: &nalgebra::DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

pub fn dynamics(args: &DynamicsArgs) -> Result<(), CliError> {
    let mut model = load(&args.chain)?;
    let n = model.nq();
    let names: Vec<String> = model.joint_names().map(String::from).collect();
    let what = format!("one per joint: {}", names.join(", "));
    let q = parse_list("q", &args.q, n, &what)?;
    let v = match &args.v {
        Some(t) => parse_list("v", t, n, &what)?,
        None => vec![0.0; n],
    };
    let a = match &args.a {
        Some(t) => parse_list("a", t, n, &what)?,
        None => vec![0.0; n],
    };
    if let Some(g) = &args.gravity {
        let g = parse_list("gravity", g, 3, "GX,GY,GZ")?;
        model.gravity = nalgebra::Vector3::new(g[0], g[1], g[2]);
    }
    let mut data = Data::new(&model);
    // Lengths were checked above, so the algorithms cannot fail here.
    let internal = |e: admittance_dynamics::DimensionError| CliError {
        code: 1,
        message: e.to_string(),
    };
    let tau = rnea(&model, &mut data, &q, &v, &a)
        .map_err(internal)?
        .as_slice()
        .to_vec();
    let mass = rows(crba(&model, &mut data, &q).map_err(internal)?);
    let gravity = gravity_torque(&model, &mut data, &q)
        .map_err(internal)?
        .as_slice()
        .to_vec();
    let coriolis = rows(coriolis_matrix(&model, &mut data, &q, &v).map_err(internal)?);
    let jac = tip_jacobian(&model, &mut data, &q).map_err(internal)?;
    let jacobian: Vec<Vec<f64>> = (0..6)
        .map(|r| jac.row(r).iter().copied().collect())
        .collect();
    forward_kinematics(&model, &mut data, &q).map_err(internal)?;
    let tip = data.tip_placement(&model);
    let rotation: Vec<Vec<f64>> = (0..3)
        .map(|r| tip.rotation.row(r).iter().copied().collect())
        .collect();
    let results = tau
        .iter()
        .chain(gravity.iter())
        .chain(mass.iter().flatten())
        .chain(coriolis.iter().flatten())
        .chain(jacobian.iter().flatten())
        .chain(tip.translation.iter());
    if results.into_iter().any(|x| !x.is_finite()) {
        return Err(CliError::input(format!(
            "the results overflow: --q, --v, --a or --gravity hold values too large for f64 arithmetic (largest |value| {:e}); use physical values",
            q.iter()
                .chain(&v)
                .chain(&a)
                .fold(0.0_f64, |m, x| m.max(x.abs()))
        )));
    }
    let out = json!({
        "joints": names,
        "tau": tau,
        "mass_matrix": mass,
        "gravity": gravity,
        "coriolis": coriolis,
        "position": tip.translation.as_slice(),
        "rotation": rotation,
        "jacobian": jacobian,
    });
    crate::write_stdout(&format!("{out}\n"));
    Ok(())
}

fn limit(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.4}")
    } else {
        "-".into()
    }
}

/// `writeln!` into a String (writing to a String cannot fail).
macro_rules! outln {
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($out, $($arg)*);
    }};
}

pub fn model(args: &ModelArgs) -> Result<(), CliError> {
    let model = load(&args.chain)?;
    let mut out = String::new();
    outln!(out, "robot    {}", model.robot_name);
    outln!(out, "source   {}", model.source);
    outln!(
        out,
        "chain    {} -> {} ({} moving joints)",
        model.base_link,
        model.tip().name,
        model.nq()
    );
    let g = model.gravity;
    if g != nalgebra::Vector3::new(0.0, 0.0, -9.81) {
        // No "-0.0000" for the rounding residue of a half turn.
        let g = g.map(|v| if v.abs() < 5e-5 { 0.0 } else { v });
        outln!(
            out,
            "gravity  ({:.4}, {:.4}, {:.4}) m/s^2 in {}'s axes (the root link's -z: the joints above the base turn it)",
            g.x,
            g.y,
            g.z,
            model.base_link
        );
    }
    out.push('\n');
    outln!(
        out,
        "{:>2}  {:<18} {:<10} {:<24} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8}",
        "#",
        "joint",
        "type",
        "axis",
        "lower",
        "upper",
        "velocity",
        "effort",
        "damping",
        "friction"
    );
    for (i, j) in model.joints.iter().enumerate() {
        let axis = format!("({:.3}, {:.3}, {:.3})", j.axis.x, j.axis.y, j.axis.z);
        let kind = match j.kind {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
        };
        outln!(
            out,
            "{:>2}  {:<18} {:<10} {:<24} {:>9} {:>9} {:>9} {:>9} {:>8.4} {:>8.4}",
            i,
            j.name,
            kind,
            axis,
            limit(j.limits.lower),
            limit(j.limits.upper),
            limit(j.limits.velocity),
            limit(j.limits.effort),
            j.damping,
            j.friction
        );
    }
    out.push('\n');
    outln!(out, "{:<28} {:>10}  carried by", "link", "mass (kg)");
    for lm in &model.link_masses {
        let by = lm.joint.map_or("base (static)".to_string(), |j| {
            format!("joint {}", model.joints[j].name)
        });
        outln!(out, "{:<28} {:>10.4}  {}", lm.link, lm.mass, by);
    }
    out.push('\n');
    outln!(out, "total moving mass {:.4} kg", model.total_moving_mass());
    for b in model.locked_branches() {
        let joints: Vec<String> = b.joints.iter().map(|(j, v)| format!("{j}={v}")).collect();
        let by = b.carried_by.map_or("the base (static)".to_string(), |j| {
            format!("joint {}", model.joints[j].name)
        });
        outln!(
            out,
            "locked branch at {}: {:.4} kg carried by {} (held at {}; --lock JOINT=VALUE moves it, --drop {} leaves it out)",
            b.joint,
            b.mass,
            by,
            joints.join(", "),
            b.joint
        );
    }
    for b in model.dropped_branches() {
        outln!(
            out,
            "dropped branch at {}: {:.4} kg not modelled (links {})",
            b.joint,
            b.mass,
            b.links.join(", ")
        );
    }
    if !model.warnings().is_empty() {
        out.push('\n');
        outln!(
            out,
            "{} warning(s) (--strict refuses them):",
            model.warnings().len()
        );
        for w in model.warnings() {
            outln!(out, "  {w}");
        }
    }
    crate::write_stdout(&out);
    Ok(())
}
