//! `admittance identify` and `admittance evaluate`: on a synthetic arm whose truth is known
//! (judged on other motion), their refusals, and on the real Baxter recording when
//! `ADMITTANCE_DATA` names the folder holding `baxter_rand/` (.ci/test sets it): trained on
//! the first 120 s, judged on the last 30 s, the bar of issue 22.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub(crate) fn admittance(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .output()
        .expect("the binary runs")
}

pub(crate) fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The row of `evaluate`'s table named `name`: (rms, nMSE).
pub(crate) fn row(table: &str, name: &str) -> (f64, f64) {
    let line = table
        .lines()
        .find(|l| l.starts_with(name))
        .unwrap_or_else(|| panic!("no row {name} in\n{table}"));
    let nums: Vec<f64> = line[name.len()..]
        .split_whitespace()
        .take(2)
        .map(|v| v.parse().unwrap())
        .collect();
    (nums[0], nums[1])
}

/// Free motion of the Baxter model with friction it does not know, as a CSV.
fn synthetic_csv(dir: &Path, seed: f64, seconds: f64) -> PathBuf {
    let names = crate::free_motion::names(&crate::free_motion::baxter());
    crate::free_motion::multisine_csv(
        dir.join(format!("free_{seed}.csv")),
        seed,
        seconds,
        &names,
        |_, i, qd| 1.5 * qd[i] + 0.8 * (qd[i] / 0.01).tanh(),
    )
}

#[test]
fn identify_then_evaluate_on_other_motion() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = root().join("models/baxter_left_arm.urdf");
    let (train, other) = (
        synthetic_csv(dir.path(), 0.3, 30.0),
        synthetic_csv(dir.path(), 1.9, 10.0),
    );
    let out = dir.path().join("baxter.ident.json");
    let o = admittance(&[
        "identify",
        "--data",
        train.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("blocked cross-validation"),
        "{}",
        text(&o)
    );
    // Each joint's row ends with the positions it was trained on, as the file records them.
    let saved: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let s0 = &saved["payload"]["summary"]["training_range"][0];
    let s0_row = format!(
        "{:.2} to {:.2}",
        s0[0].as_f64().unwrap(),
        s0[1].as_f64().unwrap()
    );
    let printed = text(&o);
    let line = printed
        .lines()
        .find(|l| l.trim_start().starts_with("left_s0"))
        .unwrap();
    assert!(line.ends_with(&s0_row), "{line} / {s0_row}");
    assert!(printed.contains("positions trained on"), "{printed}");
    let o = admittance(&[
        "evaluate",
        "--data",
        other.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--identification",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table = text(&o);
    let (urdf_rms, _) = row(&table, "URDF (RNEA)");
    let (ident_rms, _) = row(&table, "identified + joint terms");
    let (momentum_rms, _) = row(&table, "momentum (identified)");
    assert!(ident_rms < 0.02 * urdf_rms, "{table}");
    assert!(momentum_rms < 0.1 * urdf_rms, "{table}");
    // Another arm's identification is refused, naming the fix.
    let panda = root().join("models/franka_panda.urdf");
    let o = admittance(&[
        "evaluate",
        "--data",
        other.to_str().unwrap(),
        "--urdf",
        panda.to_str().unwrap(),
        "--identification",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    // A user's file is never overwritten.
    let mine = dir.path().join("notes.json");
    std::fs::write(&mine, "{}").unwrap();
    let o = admittance(&[
        "identify",
        "--data",
        train.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--out",
        mine.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "{}");
}

/// The real Baxter recording (`ADMITTANCE_DATA`), or `None` (the test is skipped).
pub(crate) fn baxter_recording() -> Option<PathBuf> {
    let Some(dir) = std::env::var_os("ADMITTANCE_DATA") else {
        eprintln!("skipped: ADMITTANCE_DATA is not set (the folder holding baxter_rand/)");
        return None;
    };
    let data = PathBuf::from(dir).join("baxter_rand/baxter_rand.csv");
    assert!(
        data.exists(),
        "ADMITTANCE_DATA is set but {} is missing",
        data.display()
    );
    Some(data)
}

/// `admittance identify` on the real Baxter's rows before `until` s at 4 Hz, to `out`, with
/// `extra` arguments; succeeds, and returns what it printed and the file.
pub(crate) fn identify_baxter(
    data: &Path,
    until: &str,
    extra: &[&str],
    out: &Path,
) -> (String, serde_json::Value) {
    identify_baxter_at(data, until, "4", extra, out)
}

/// [`identify_baxter`] with the input filter's cut-off `input_filter_hz` (Hz; "0": raw).
pub(crate) fn identify_baxter_at(
    data: &Path,
    until: &str,
    input_filter_hz: &str,
    extra: &[&str],
    out: &Path,
) -> (String, serde_json::Value) {
    let urdf = root().join("models/baxter_left_arm.urdf");
    let mut args = vec![
        "identify",
        "--data",
        data.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--until",
        until,
        "--input-filter-hz",
        input_filter_hz,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let r = admittance(&args);
    assert!(r.status.success(), "{}", text(&r));
    let file = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    (text(&r), file)
}

/// The real Baxter's first 60 s at 4 Hz without springs (`--no-springs`): the shoulder's
/// gravity-assist spring, which the fit may then not take, pushes links against their size;
/// `identify` names them and the file lists them, every mass within its bound.
#[test]
fn real_baxter_links_held_at_the_arms_size_are_named() {
    let Some(data) = baxter_recording() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let no_springs = ["--no-springs"];
    let (printed, file) = identify_baxter(&data, "60", &no_springs, &tmp.path().join("held.json"));
    let line = printed
        .lines()
        .find(|l| l.starts_with("bodies held at the arm's size"))
        .unwrap_or_else(|| panic!("no line naming held bodies in\n{printed}"));
    assert!(line.contains("\"left_lower_shoulder\""), "{line}");
    let summary = &file["payload"]["summary"];
    assert_eq!(
        summary["settings"]["max_mass_ratio"],
        serde_json::json!(2.0)
    );
    let held = summary["bodies_at_extent"].as_array().unwrap();
    assert!(held.contains(&serde_json::json!(1)), "{held:?}");
    let masses: Vec<f64> = file["payload"]["inertial_parameters"]
        .as_array()
        .unwrap()
        .iter()
        .step_by(10)
        .map(|m| m.as_f64().unwrap())
        .collect();
    // Baxter's URDF: 5.70, 3.23, 4.31, 2.07, 2.25, 1.61, 0.54 kg (19.7 in all); the bound is
    // 2 m + 0.05 * 19.7, times the prior's scale (1 here; 1.04 allowed).
    let urdf_mass = [5.70, 3.23, 4.31, 2.07, 2.25, 1.61, 0.54];
    for (b, (m, u)) in masses.iter().zip(urdf_mass).enumerate() {
        assert!(
            *m <= 1.04 * (2.0 * u + 0.05 * 19.7) + 0.02,
            "body {b}: {m} kg"
        );
    }
    // `--max-mass-ratio none` lifts the bound: nothing is held, and the file says so.
    let none = ["--no-springs", "--max-mass-ratio", "none"];
    let (printed, file) = identify_baxter(&data, "60", &none, &tmp.path().join("free.json"));
    assert!(!printed.contains("bodies held"), "{printed}");
    assert!(file["payload"]["summary"]["settings"]["max_mass_ratio"].is_null());
}

#[test]
fn real_baxter_held_out_meets_the_bar() {
    let Some(data) = baxter_recording() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("baxter.ident.json");
    identify_baxter(&data, "120", &[], &out);
    let urdf = root().join("models/baxter_left_arm.urdf");
    let (d, u, o) = (
        data.to_str().unwrap(),
        urdf.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let r = admittance(&[
        "evaluate",
        "--data",
        d,
        "--urdf",
        u,
        "--from",
        "120",
        "--input-filter-hz",
        "4",
        "--identification",
        o,
    ]);
    assert!(r.status.success(), "{}", text(&r));
    let table = text(&r);
    eprintln!("{table}");
    for name in ["identified + joint terms", "momentum (identified)"] {
        let (rms, nmse) = row(&table, name);
        assert!(
            rms <= 1.0 && nmse <= 0.4,
            "{name}: {rms} N m, nMSE {nmse}\n{table}"
        );
    }
}

#[test]
fn a_scenario_runs_its_momentum_observer_on_an_identification() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = root().join("models/baxter_left_arm.urdf");
    let train = synthetic_csv(dir.path(), 0.7, 20.0);
    let ident = dir.path().join("baxter.ident.json");
    let o = admittance(&[
        "identify",
        "--data",
        train.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--out",
        ident.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let scenario = root().join("scenarios/admittance.toml");
    let set = format!("observer.identification=\"{}\"", ident.display());
    let out = dir.path().join("run");
    let o = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "momentum",
        "--set",
        &set,
        "--set",
        "duration=3",
        "--set",
        "evaluation_start=1",
        "--set",
        "observer.nominal_inertia_scale=1",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("momentum"), "{summary}");
    assert!(std::fs::read_to_string(out.join("scenario.toml"))
        .unwrap()
        .contains("identification"));
    // The hybrid would need a network trained on the identification's residual: refused,
    // naming the key, before any training.
    let o = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "hybrid",
        "--set",
        &set,
        "--set",
        "duration=3",
        "--out",
        dir.path().join("run2").to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(text(&o).contains("observer.identification"), "{}", text(&o));
    // Another arm's identification is refused at the same key.
    let panda_ident = dir.path().join("missing.ident.json");
    let o = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--variant",
        "momentum",
        "--set",
        &format!("observer.identification=\"{}\"", panda_ident.display()),
        "--set",
        "duration=3",
        "--set",
        "observer.nominal_inertia_scale=1",
        "--out",
        dir.path().join("run3").to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("observer.identification"), "{}", text(&o));
}

/// A recording with rows lost and a torque 8 % larger than the URDF's arm (a torque constant
/// off): `identify` warns about the gaps it interpolated and says the scale it pulled toward.
#[test]
fn dropped_rows_and_a_torque_of_another_size_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = root().join("models/baxter_left_arm.urdf");
    let whole = std::fs::read_to_string(synthetic_csv(dir.path(), 0.3, 30.0)).unwrap();
    let mut lines = whole.lines();
    let header = lines.next().unwrap();
    let torque: Vec<bool> = header
        .split(',')
        .map(|c| c.trim().starts_with("tau."))
        .collect();
    let mut edited = format!("{header}\n");
    for (_, line) in lines.enumerate().filter(|(k, _)| k % 25 != 7) {
        let cells: Vec<String> = line
            .split(',')
            .zip(&torque)
            .map(|(c, &t)| {
                if t {
                    format!("{}", 1.08 * c.trim().parse::<f64>().unwrap())
                } else {
                    c.to_string()
                }
            })
            .collect();
        edited += &(cells.join(",") + "\n");
    }
    let data = dir.path().join("lossy.csv");
    std::fs::write(&data, edited).unwrap();
    let out = dir.path().join("lossy.ident.json");
    let o = admittance(&[
        "identify",
        "--data",
        data.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        // The columns as recorded: through a 4 Hz filter this synthetic friction's square
        // wave no longer matches its model, and the scale read 1.053.
        "--input-filter-hz",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let printed = text(&o);
    assert!(printed.contains("gaps in the time column"), "{printed}");
    let line = printed
        .lines()
        .find(|l| l.starts_with("the torque is "))
        .unwrap_or_else(|| panic!("{printed}"));
    let scale: f64 = line["the torque is ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((scale - 1.08).abs() < 0.01, "{line}");
}

/// `admittance identify` of the Baxter model on `data` at 4 Hz into `out`, with `extra`.
fn identify_at_4_hz(data: &Path, out: &Path, extra: &[&str]) -> Output {
    let urdf = root().join("models/baxter_left_arm.urdf");
    let mut args = vec![
        "identify",
        "--data",
        data.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--input-filter-hz",
        "4",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    admittance(&args)
}

#[test]
fn a_validation_recording_that_repeats_the_training_rows_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let train = synthetic_csv(dir.path(), 0.3, 12.0);
    let out = dir.path().join("same.ident.json");
    // The same file as validation, fitted on its first 8 s: its first 8 s are the fit's own.
    let same = train.to_str().unwrap();
    let o = identify_at_4_hz(&train, &out, &["--until", "8", "--validation", same]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("repeats") && text(&o).contains("other motion"),
        "{}",
        text(&o)
    );
    assert!(!out.exists());
}

#[test]
fn an_identification_of_a_shorter_chain_names_the_chain_it_was_made_for() {
    let dir = tempfile::tempdir().unwrap();
    let data = synthetic_csv(dir.path(), 0.3, 12.0);
    let out = dir.path().join("six.ident.json");
    let o = identify_at_4_hz(&data, &out, &["--tip", "left_lower_forearm"]);
    assert!(o.status.success(), "{}", text(&o));
    // Evaluated on the whole arm (no --tip): the file says which chain it holds.
    let urdf = root().join("models/baxter_left_arm.urdf");
    let o = admittance(&[
        "evaluate",
        "--data",
        data.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--identification",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("to left_lower_forearm") && text(&o).contains("--tip"),
        "{}",
        text(&o)
    );
}

#[test]
fn an_angle_read_within_one_turn_is_identified_as_the_same_motion() {
    let dir = tempfile::tempdir().unwrap();
    let data = synthetic_csv(dir.path(), 0.3, 12.0);
    // The last joint read in [0, 2 pi), as a driver may report a continuous joint: its
    // negative angles a turn higher, a step of 2 pi at every crossing of zero.
    let text_in = std::fs::read_to_string(&data).unwrap();
    let mut lines = text_in.lines();
    let header = lines.next().unwrap();
    let column = header
        .split(',')
        .position(|c| c.trim() == "q.left_w2")
        .unwrap();
    let mut first_sign = None;
    let mut crossings = 0;
    let mut wrapped = format!("{header}\n");
    for line in lines {
        let mut fields: Vec<String> = line.split(',').map(String::from).collect();
        let q: f64 = fields[column].trim().parse().unwrap();
        let sign = *first_sign.get_or_insert(q >= 0.0);
        crossings += usize::from((q >= 0.0) != sign);
        if q < 0.0 {
            fields[column] = format!("{}", q + std::f64::consts::TAU);
        }
        wrapped.push_str(&fields.join(","));
        wrapped.push('\n');
    }
    assert_eq!(
        first_sign,
        Some(true),
        "the test wants the first angle on [0, 2 pi)"
    );
    assert!(
        crossings > 100,
        "the joint crosses zero: {crossings} rows below it"
    );
    let wrapped_csv = dir.path().join("wrapped.csv");
    std::fs::write(&wrapped_csv, wrapped).unwrap();
    let (plain_out, wrapped_out) = (dir.path().join("a.json"), dir.path().join("b.json"));
    let o = identify_at_4_hz(&data, &plain_out, &[]);
    assert!(o.status.success(), "{}", text(&o));
    let o = identify_at_4_hz(&wrapped_csv, &wrapped_out, &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("q.left_w2 read within one turn"),
        "{}",
        text(&o)
    );
    let numbers = |path: &Path, key: &str| -> Vec<f64> {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let mut out = Vec::new();
        fn walk(v: &serde_json::Value, out: &mut Vec<f64>) {
            match v {
                serde_json::Value::Number(x) => out.push(x.as_f64().unwrap()),
                serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, out)),
                serde_json::Value::Object(o) => o.values().for_each(|x| walk(x, out)),
                _ => {}
            }
        }
        walk(&v["payload"][key], &mut out);
        out
    };
    for key in ["inertial_parameters", "joint_terms"] {
        let (a, b) = (numbers(&plain_out, key), numbers(&wrapped_out, key));
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y).abs() <= 1e-6 * (1.0 + x.abs()),
                "{key}: {x} against {y}"
            );
        }
    }
}

/// The fit regresses on the acceleration through a zero-phase low-pass, 10 Hz on raw signals
/// and twice the conditioning's cut-off above 5 Hz; the file records it and `identify` says
/// so beside the acceleration gain.
#[test]
fn the_fits_acceleration_low_pass_is_recorded() {
    let Some(data) = baxter_recording() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    for (cutoff, want) in [("0", 10.0), ("10", 20.0)] {
        let out = tmp.path().join(format!("{cutoff}.json"));
        let (printed, file) = identify_baxter_at(&data, "30", cutoff, &[], &out);
        let recorded = file["payload"]["summary"]["fit_acceleration_hz"].as_f64();
        assert_eq!(recorded, Some(want), "input filter {cutoff} Hz");
        let line = format!("fitted on q'' low-passed at {want} Hz, zero phase");
        assert!(printed.contains(&line), "{printed}");
    }
}
