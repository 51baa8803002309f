//! `admittance identify --payload DATA --identification FILE --out NEW_FILE`: the tool or
//! payload at the tip (mass, centre of mass, inertia about it) fitted on top of an existing
//! identification from a short recording with it attached, written as a new identification
//! file that carries it (docs/outputs.md, "Identification files"): every consumer of
//! identification files takes it as it is.

use std::collections::BTreeMap;
use std::path::Path;

use admittance_dynamics::{identify_payload, Identification, Payload};
use serde_json::{json, Value};

use super::{check_out, rows_until, Conditioned, IdentifyArgs};
use crate::CliError;

/// Fits the payload in `tool` on top of `--identification` and writes `--out`.
pub fn payload_cmd(args: &IdentifyArgs, tool: &Path) -> Result<(), CliError> {
    check_out(&args.out)?;
    let Some(base_path) = args.identification.as_deref() else {
        return Err(CliError::usage(
            "--payload needs --identification FILE: the identification of the arm without the payload",
        ));
    };
    let arm = crate::dynamics_cmd::load(&args.chain)?;
    let ident =
        Identification::load(base_path, &arm).map_err(|e| CliError::input(e.to_string()))?;
    let joints: Vec<String> = arm.joint_names().map(String::from).collect();
    let data = crate::train_cmd::load_data(tool, Some(&joints))?;
    let rows = rows_until(tool, &data, args.until)?;
    // The samples conditioned as the identification's were: the same cut-off (the summary's,
    // or what `identify` recorded in the file's data).
    let mut provenance = base_data(base_path);
    let filter_hz = match ident.summary.input_filter_hz {
        f if f > 0.0 => f,
        _ => provenance
            .get("input_filter_hz")
            .and_then(Value::as_f64)
            .unwrap_or(0.0),
    };
    let conditioned = Conditioned::new(tool, &data, filter_hz)?;
    let samples = conditioned.samples().slice(0, rows);
    let payload = identify_payload(&ident, &samples)
        .map_err(|e| CliError::input(format!("--payload {}: {e}", tool.display())))?;
    let carried = ident
        .with_payload(&payload)
        .map_err(|e| CliError::input(format!("--payload {}: {e}", tool.display())))?;
    let rms = |i: &Identification| {
        i.false_torque_rms(&samples)
            .map_err(|e| CliError::input(format!("--payload {}: {e}", tool.display())))
    };
    let (before, after) = (rms(&ident)?, rms(&carried)?);
    let seconds = data.t.get(rows - 1).copied().unwrap_or(0.0) - data.t[0];
    let record = json!({
        "mass_kg": payload.mass,
        "com_m": payload.com.as_slice(),
        "inertia_kg_m2": rows_of(&payload),
        "frame": arm.tip().name,
        "data": tool.display().to_string(),
        "rows": rows,
        "seconds": seconds,
        "input_filter_hz": filter_hz,
        "false_torque_rms_without": before,
        "false_torque_rms_with": after,
    });
    provenance.insert("payload".into(), record);
    provenance.insert(
        "identification_without_payload".into(),
        json!(base_path.display().to_string()),
    );
    carried
        .save(&args.out, &arm, provenance)
        .map_err(|e| CliError {
            code: 1,
            message: e.to_string(),
        })?;
    crate::write_stdout(&report(&arm, &payload, &before, &after, seconds, &args.out));
    Ok(())
}

/// The inertia's rows, for JSON.
fn rows_of(p: &Payload) -> Vec<[f64; 3]> {
    (0..3)
        .map(|r| [p.inertia[(r, 0)], p.inertia[(r, 1)], p.inertia[(r, 2)]])
        .collect()
}

/// The `data` the identification without the payload recorded (what it was made from), so
/// that the new file still says it; empty when that file cannot be read as JSON (it loaded,
/// so this does not happen for a file `identify` wrote).
fn base_data(path: &Path) -> BTreeMap<String, Value> {
    admittance_files::read_regular_text(path, admittance_files::TEXT_LIMIT)
        .ok()
        .and_then(|t| serde_json::from_str::<Value>(&t).ok())
        .and_then(|v| v.pointer("/payload/data").cloned())
        .and_then(|d| serde_json::from_value(d).ok())
        .unwrap_or_default()
}

fn report(
    arm: &admittance_dynamics::Model,
    p: &Payload,
    before: &[f64],
    after: &[f64],
    seconds: f64,
    out: &Path,
) -> String {
    let total = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let mut text = format!(
        "payload at {} from {seconds:.1} s: mass {:.4} kg, centre of mass [{:.4}, {:.4}, {:.4}] m (tip frame)\n\
         inertia about the centre of mass (kg m^2, tip axes):\n",
        arm.tip().name, p.mass, p.com.x, p.com.y, p.com.z
    );
    for r in rows_of(p) {
        text += &format!("  [{:>10.6} {:>10.6} {:>10.6}]\n", r[0], r[1], r[2]);
    }
    text += &format!(
        "false torque on this recording (rms, N m):\n  {:<16} {:>10} {:>12}\n",
        "joint", "without", "with payload"
    );
    for (i, name) in arm.joint_names().enumerate() {
        text += &format!("  {name:<16} {:>10.3} {:>12.3}\n", before[i], after[i]);
    }
    text += &format!(
        "  {:<16} {:>10.3} {:>12.3}\nwrote {} (the identification carrying the payload)\n",
        "all joints",
        total(before),
        total(after),
        out.display()
    );
    text
}

/// `--data`'s parser: any path, the empty one too (the default when `--payload` is given;
/// clap's own path parser refuses it).
pub fn any_path(text: &str) -> Result<std::path::PathBuf, std::convert::Infallible> {
    Ok(std::path::PathBuf::from(text))
}
