//! Figures never hang or panic (issue 14): hand-made run folders whose series hold huge
//! finite values, non-finite values, a constant or an empty series go through
//! `admittance_report::generate` on a thread joined with a deadline. Each case also names
//! what the report must say about the samples it could not draw.

use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use admittance_report::{generate, Options};

const JOINTS: [&str; 2] = ["left_s0", "left_s1"];
const PER_JOINT: [&str; 9] = [
    "q_d",
    "q_r",
    "q",
    "qdot",
    "q_meas",
    "tau_cmd",
    "tau_applied",
    "tau_ext",
    "tau_ext_hat",
];

/// How a case damages the series.
#[derive(Clone, Copy, Debug)]
enum Damage {
    /// Every data column holds this value at a few rows.
    Value(f64),
    /// Every data column is this constant.
    Constant(f64),
    /// No rows at all.
    Empty,
    /// The time column holds this value at a few rows.
    Time(f64),
    /// The time column holds this value in its last row.
    LastTime(f64),
    /// The time column is this constant.
    ConstantTime(f64),
    /// One row only.
    OneRow,
}

fn value_text(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v == f64::INFINITY {
        "inf".into()
    } else if v == f64::NEG_INFINITY {
        "-inf".into()
    } else {
        format!("{v:e}")
    }
}

fn csv(
    columns: &[String],
    rows: usize,
    damage: Damage,
    data: impl Fn(usize, usize) -> f64,
) -> String {
    let mut out = columns.join(",");
    out.push('\n');
    let rows = if matches!(damage, Damage::Empty) {
        0
    } else if matches!(damage, Damage::OneRow) {
        1
    } else {
        rows
    };
    for r in 0..rows {
        let hit = r % 37 == 5;
        let cells: Vec<String> = (0..columns.len())
            .map(|c| {
                let v = if c == 0 {
                    match damage {
                        Damage::Time(v) if hit => v,
                        Damage::ConstantTime(v) => v,
                        Damage::LastTime(v) if r + 1 == rows => v,
                        _ => r as f64 * 0.05,
                    }
                } else {
                    match damage {
                        Damage::Value(v) if hit => v,
                        Damage::Constant(v) => v,
                        _ => data(r, c),
                    }
                };
                value_text(v)
            })
            .collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

fn joint_columns(extra: &[&str]) -> Vec<String> {
    let mut names = vec!["t".to_string()];
    for p in PER_JOINT {
        for j in JOINTS {
            names.push(format!("{p}.{j}"));
        }
    }
    names.extend(extra.iter().map(|s| s.to_string()));
    names
}

fn smooth(r: usize, c: usize) -> f64 {
    (r as f64 * 0.05 * (1.0 + 0.1 * c as f64)).sin()
}

/// Writes a run folder of `scenario` with `variants`, every series damaged by `damage`.
fn write_folder(dir: &Path, scenario: &str, variants: &[&str], toml: &str, damage: Damage) {
    let rows = 800; // 40 s at 20 Hz
    let mut extra = vec!["ee_error"];
    if scenario == "dynamic_nodes" {
        extra.extend([
            "f.left_s0",
            "f.left_s1",
            "f_hat.left_s0",
            "f_hat.left_s1",
            "nodes.f",
        ]);
    }
    let columns = joint_columns(&extra);
    let nodes_col = columns.len() - 1;
    for v in variants {
        let text = csv(&columns, rows, damage, |r, c| {
            if scenario == "dynamic_nodes" && c == nodes_col {
                // 8 nodes, 4 discarded at 20 s, 2 grown at 28 and 30 s.
                let t = r as f64 * 0.05;
                (if t < 20.0 { 8.0 } else { 4.0 }) + f64::from(t >= 28.0) + f64::from(t >= 30.0)
            } else {
                smooth(r, c)
            }
        });
        std::fs::write(dir.join(format!("{v}.csv")), text).unwrap();
    }
    if scenario == "dynamic_nodes" {
        let names: Vec<String> = std::iter::once("t".to_string())
            .chain((0..10).map(|k| format!("w.{k}")))
            .collect();
        let text = csv(&names, rows / 5, damage, |r, c| {
            let t = r as f64 * 0.05;
            let alive = match c - 1 {
                0..=3 => true,
                4..=7 => t < 20.0,
                8 => t >= 28.0,
                _ => t >= 30.0,
            };
            if alive {
                0.1 * c as f64 * (1.0 - (-t).exp())
            } else {
                f64::NAN
            }
        });
        std::fs::write(dir.join(format!("weights_{}.csv", variants[0])), text).unwrap();
    }
    if scenario == "admittance" {
        let names: Vec<String> = std::iter::once("t".to_string())
            .chain(JOINTS.iter().map(|j| format!("target.{j}")))
            .chain(JOINTS.iter().map(|j| format!("prediction.{j}")))
            .collect();
        let text = csv(&names, rows, damage, smooth);
        std::fs::write(dir.join("validation_learned.csv"), text).unwrap();
    }
    if scenario == "free_motion" {
        let names: Vec<String> = std::iter::once("t".to_string())
            .chain(
                ["q", "qdot", "qddot", "tau"]
                    .iter()
                    .flat_map(|p| JOINTS.iter().map(move |j| format!("{p}.{j}"))),
            )
            .collect();
        std::fs::write(
            dir.join("free_motion.csv"),
            csv(&names, rows, damage, smooth),
        )
        .unwrap();
    }
    let metrics: Vec<String> = variants
        .iter()
        .map(|v| {
            format!(
                "\"{v}\": {{\"tracking_rmse\": [0.1, 0.2], \"ee_error_max\": 0.01, \"faults\": 0}}"
            )
        })
        .collect();
    let summary = format!(
        "{{\"format\": \"admittance-run\", \"format_version\": 1, \"scenario\": \"{scenario}\", \"joints\": [\"left_s0\", \"left_s1\"], \"variant_order\": [{}], \"variants\": {{{}}}}}",
        variants.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", "),
        metrics.join(", ")
    );
    std::fs::write(dir.join("summary.json"), summary).unwrap();
    std::fs::write(dir.join("scenario.toml"), toml).unwrap();
}

const DEADZONE_TOML: &str = "name = \"deadzone\"\nduration = 40.0\nevaluation_start = 20.0\n\
[arm]\nurdf = \"no-such-arm.urdf\"\n\
[controller]\nkind = \"neural\"\n\
[[plant.deadzones]]\njoint = \"left_s0\"\nd_left = -0.49\nd_right = 0.49\n\
[variants.nn_uncompensated]\ncontroller.neural.deadzone_compensation = false\n\
[variants.nn_compensated_wide]\nplant.deadzones = [{ joint = \"left_s0\", d_left = -5.0, d_right = 5.0 }]\n\
[variants.nn_uncompensated_wide]\ncontroller.neural.deadzone_compensation = false\n\
plant.deadzones = [{ joint = \"left_s0\", d_left = -5.0, d_right = 5.0 }]\n";
const ADMITTANCE_TOML: &str = "name = \"admittance\"\nduration = 40.0\nevaluation_start = 2.0\n\
[[plant.environment.joint_springs]]\njoints = [\"left_s0\"]\nt_start = 12.0\nt_end = 30.0\n\
[admittance]\ndamping = 3\nstiffness = 5\n[observer]\nkind = \"learned\"\n\
[admittance.saturation]\nrho = 0.95\ncentre = 0.0\nhalf_range = [1.1, inf]\n";
const DYNAMIC_TOML: &str =
    "name = \"dynamic_nodes\"\nduration = 40.0\n[dynamic_nodes]\napproximation_window = 5.0\n";

/// The scenarios of a case: name, variants, scenario.toml.
fn scenarios() -> Vec<(&'static str, Vec<&'static str>, String)> {
    vec![
        (
            "deadzone",
            vec![
                "nn_compensated",
                "nn_uncompensated",
                "nn_compensated_wide",
                "nn_uncompensated_wide",
            ],
            DEADZONE_TOML.to_string(),
        ),
        (
            "admittance",
            vec!["learned", "oracle"],
            ADMITTANCE_TOML.to_string(),
        ),
        ("dynamic_nodes", vec!["dynamic"], DYNAMIC_TOML.to_string()),
        (
            "free_motion",
            vec!["base"],
            "name = \"free_motion\"\n[record]\nfree_motion_csv = true\n".to_string(),
        ),
        (
            "something_else",
            vec!["a", "b"],
            "name = \"something_else\"\n".to_string(),
        ),
    ]
}

/// Runs `generate` on a thread; fails the test when it does not return within the
/// deadline (a hang) or panics.
fn generate_within(dir: &Path, what: &str) -> admittance_report::Outcome {
    let (tx, rx) = mpsc::channel();
    let owned = dir.to_path_buf();
    std::thread::spawn(move || {
        let options = Options {
            recording: false,
            threads: 1,
            ..Options::default()
        };
        let _ = tx.send(generate(&owned, &options).map_err(|e| e.to_string()));
    });
    match rx.recv_timeout(Duration::from_secs(60)) {
        Ok(Ok(outcome)) => outcome,
        Ok(Err(e)) => panic!("{what}: generate failed: {e}"),
        Err(mpsc::RecvTimeoutError::Timeout) => {
            panic!("{what}: generate hangs (no answer in 60 s)")
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: generate panicked"),
    }
}

fn check(damage: Damage) {
    for (scenario, variants, toml) in scenarios() {
        let tmp = tempfile::tempdir().unwrap();
        write_folder(tmp.path(), scenario, &variants, &toml, damage);
        let what = format!("{damage:?}, scenario {scenario}");
        let outcome = generate_within(tmp.path(), &what);
        assert!(tmp.path().join("report.html").is_file(), "{what}");
        let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
        let undrawable = match damage {
            Damage::Value(v) | Damage::Time(v) | Damage::LastTime(v) | Damage::Constant(v) => {
                !(v.is_finite() && v.abs() <= 1e12)
            }
            _ => false,
        };
        // Every drawn figure that met such samples says so, and the report warns.
        if undrawable && !outcome.notes.is_empty() {
            assert!(
                md.contains("not drawn") && md.contains("**Warning:**"),
                "{what}: the report does not say which samples were left out:\n{md}"
            );
        }
        if undrawable && !outcome.figures.is_empty() && scenario != "dynamic_nodes" {
            assert!(
                !outcome.notes.is_empty(),
                "{what}: no figure says what it left out"
            );
        }
    }
}

#[test]
fn huge_positive_values_do_not_hang() {
    check(Damage::Value(1e308));
}

#[test]
fn huge_negative_values_do_not_hang() {
    check(Damage::Value(-1e308));
}

/// Today's code panicked on NaN times (plotters' assertion on a NaN axis range).
#[test]
fn nan_values_do_not_hang() {
    check(Damage::Value(f64::NAN));
    check(Damage::Time(f64::NAN));
    check(Damage::LastTime(f64::NAN));
}

/// Today's code hung on an infinite time (in plotters' tick search).
#[test]
fn infinite_values_do_not_hang() {
    check(Damage::Value(f64::INFINITY));
    check(Damage::Value(f64::NEG_INFINITY));
    check(Damage::Time(f64::INFINITY));
    check(Damage::LastTime(f64::INFINITY));
}

#[test]
fn huge_times_do_not_hang() {
    check(Damage::Time(1e308));
}

/// Today's code hung on a constant series at f64::MAX (its padded axis overflowed).
#[test]
fn constant_series_do_not_hang() {
    check(Damage::Constant(f64::MAX));
    check(Damage::Constant(1e300));
    check(Damage::Constant(0.0));
    check(Damage::ConstantTime(3.0));
}

#[test]
fn empty_series_do_not_hang() {
    check(Damage::Empty);
    check(Damage::OneRow);
}

#[test]
fn a_huge_deadzone_in_the_scenario_does_not_hang() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = DEADZONE_TOML.replace("d_right = 0.49", "d_right = 1e308");
    write_folder(
        tmp.path(),
        "deadzone",
        &["nn_compensated", "nn_uncompensated"],
        &toml,
        Damage::Value(0.5),
    );
    generate_within(tmp.path(), "d_right = 1e308");
    let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    assert!(md.contains("not drawn"), "{md}");
}
