//! The reliability harness (issue 14): the command line against damaged inputs, seeded and
//! bounded. Each family mutates real inputs (the committed scenario files, a recorded
//! free-motion CSV, a trained model file, the Baxter URDF), runs the `admittance` binary on
//! each with a wall-clock timeout and checks the contract:
//!
//! - no panic (exit 101 or "panicked" on stderr), no abort or signal, no hang;
//! - an exit code of 0, 1, 2, 3 or 4 (a run that finished but broke a health rule) only;
//!   errors (2, 3) in one or two lines;
//! - exit 0 (and 4) only with a complete summary whose metrics are finite (a few may be null);
//! - nothing the user owns is lost: a sentinel file beside the output survives, and a
//!   folder of the user's given as `--out` is refused and kept.
//!
//! `cargo test --release -p admittance-cli --test reliability` runs a few cases per family
//! (about a minute on two cores: what CI runs). For a long local run:
//! `ADMITTANCE_RELIABILITY_CASES=400 ADMITTANCE_RELIABILITY_SEED=7 cargo test --release -p
//! admittance-cli --test reliability -- --nocapture` (docs/reliability.md). A violation
//! prints its reproducer: the damaged input is kept in a folder named in the message.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The checkout the test runs in: cargo's run-time `CARGO_MANIFEST_DIR` first, because
/// docs/reliability.md's commands also run from copies of the checkout that share its
/// `target/` (scripts/doc_commands.py), where the compile-time path may be another copy's.
fn root() -> PathBuf {
    std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
        .join("../..")
}

fn cases(default: usize) -> usize {
    std::env::var("ADMITTANCE_RELIABILITY_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn seed() -> u64 {
    std::env::var("ADMITTANCE_RELIABILITY_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1)
}

/// A small deterministic generator (SplitMix64): the same seed, the same cases.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Values that have broken parsers and simulations before.
const BAD_NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-inf",
    "1e30",
    "4294967296",
    "18446744073709551616",
    "-0.0",
    "1e-320",
    "\"text\"",
    "true",
    "[]",
    "{}",
    // Valid but extreme: gains, masses, gravity, stiffness that make a run blow up.
    "1e6",
    "1e9",
    "-100",
    "100",
    "0.001",
];

/// The outcome of one command.
struct Outcome {
    code: Option<i32>,
    stderr: String,
    timed_out: bool,
    seconds: f64,
}

fn run(args: &[&str], timeout: Duration) -> Outcome {
    let start = Instant::now();
    let quiet: &[&str] = if matches!(args.first(), Some(&("run" | "train" | "grow"))) {
        &["--quiet"]
    } else {
        &[]
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .args(quiet)
        .env("ADMITTANCE_CACHE_DIR", cache_dir())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn admittance");
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let mut timed_out = false;
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > timeout {
            timed_out = true;
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Outcome {
        code,
        stderr: reader.join().unwrap_or_default(),
        timed_out,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// One cache for every run of the harness, so that training is paid once per setting.
fn cache_dir() -> PathBuf {
    std::env::temp_dir().join("admittance-reliability-cache")
}

/// What went wrong with one case, if anything.
fn violation(o: &Outcome, out: Option<&Path>) -> Option<String> {
    if o.timed_out {
        return Some(format!("hang: no exit after {:.0} s", o.seconds));
    }
    if o.stderr.contains("panicked") {
        return Some(format!("panic: {}", o.stderr.trim()));
    }
    let Some(code) = o.code else {
        return Some("killed by a signal (abort?)".into());
    };
    if !(0..=4).contains(&code) {
        return Some(format!("exit {code}: {}", o.stderr.trim()));
    }
    let errors: Vec<&str> = o
        .stderr
        .lines()
        .filter(|l| !l.starts_with("admittance: warning:"))
        .collect();
    // One or two lines per problem; a scenario with several problems lists each on a line
    // of its own that starts with its file and line.
    let extra_located = errors.iter().skip(1).all(|l| located(l));
    if (code == 2 || code == 3) && (errors.is_empty() || (errors.len() > 2 && !extra_located)) {
        return Some(format!(
            "exit {code} with {} lines of error:\n{}",
            errors.len(),
            o.stderr
        ));
    }
    if code == 0 || code == 4 {
        if let Some(dir) = out {
            return summary_problem(&dir.join("summary.json"));
        }
    }
    None
}

/// `FILE:LINE: ...`: a line that names where its problem is.
fn located(line: &str) -> bool {
    let Some((head, _)) = line.split_once(": ") else {
        return false;
    };
    head.rsplit_once(':').is_some_and(|(file, n)| {
        !file.is_empty() && !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit())
    })
}

/// Keys that may be null in a successful run (docs/outputs.md).
const MAY_BE_NULL: &[&str] = &[
    "external_torque_nrmse",
    "diverged_at",
    "wrench_estimate_rmse",
    "wrench_estimate_nrmse",
    "hand_compliance_error_rms",
    "hand_drift_after_release",
    "false_force_rms",
];

fn summary_problem(path: &Path) -> Option<String> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) => return Some(format!("exit 0 without {}: {e}", path.display())),
    };
    let json: serde_json::Value = match serde_json::from_str(&text) {
        Ok(j) => j,
        Err(e) => return Some(format!("exit 0 with an unreadable summary: {e}")),
    };
    let Some(variants) = json["variants"].as_object().filter(|v| !v.is_empty()) else {
        return Some("exit 0 with no variants in summary.json".into());
    };
    for (name, metrics) in variants {
        if metrics["diverged"] == serde_json::Value::Bool(true) {
            return Some(format!("exit 0 although variant {name} diverged"));
        }
        for (key, value) in metrics.as_object().into_iter().flatten() {
            if let Some(bad) = non_finite(value) {
                if !(bad == "null" && MAY_BE_NULL.contains(&key.as_str())) {
                    return Some(format!("exit 0 with {name}.{key} = {bad}"));
                }
            }
        }
    }
    None
}

/// `Some("null")` or `Some("NaN")`-like text when a metric is not a finite number (lists
/// and maps are searched; strings and booleans are fine).
fn non_finite(v: &serde_json::Value) -> Option<String> {
    match v {
        serde_json::Value::Null => Some("null".into()),
        serde_json::Value::Number(n) => {
            n.as_f64().filter(|x| !x.is_finite()).map(|x| x.to_string())
        }
        serde_json::Value::Array(a) => a.iter().find_map(non_finite),
        serde_json::Value::Object(o) => o.values().find_map(non_finite),
        _ => None,
    }
}

/// The tally of one family, printed as a table row; panics listing every violation.
struct Family {
    name: &'static str,
    runs: usize,
    codes: [usize; 6],
    violations: Vec<String>,
    keep: tempfile::TempDir,
}

impl Family {
    fn new(name: &'static str) -> Self {
        Family {
            name,
            runs: 0,
            codes: [0; 6],
            violations: Vec::new(),
            keep: tempfile::Builder::new()
                .prefix(&format!("admittance-reliability-{name}-"))
                .tempdir()
                .unwrap(),
        }
    }

    fn dir(&self) -> &Path {
        self.keep.path()
    }

    fn record(&mut self, o: &Outcome, problem: Option<String>, reproduce: impl FnOnce() -> String) {
        self.runs += 1;
        if std::env::var_os("ADMITTANCE_RELIABILITY_VERBOSE").is_some() {
            eprintln!(
                "[{}] exit {:?}: {}",
                self.name,
                o.code,
                o.stderr.lines().next().unwrap_or("")
            );
        }
        match o.code {
            Some(c @ 0..=4) => self.codes[c as usize] += 1,
            _ => self.codes[5] += 1,
        }
        if let Some(p) = problem {
            self.violations
                .push(format!("{p}\n    reproduce: {}", reproduce()));
        }
    }

    fn finish(self) {
        eprintln!(
            "{:<22} runs {:>4}  exit 0: {:>4}  1: {:>4}  2: {:>4}  3: {:>4}  4: {:>4}  other: {:>3}  violations: {}",
            self.name,
            self.runs,
            self.codes[0],
            self.codes[1],
            self.codes[2],
            self.codes[3],
            self.codes[4],
            self.codes[5],
            self.violations.len()
        );
        if !self.violations.is_empty() {
            let kept = self.keep.keep();
            panic!(
                "{}: {} violation(s) (inputs kept in {}):\n{}",
                self.name,
                self.violations.len(),
                kept.display(),
                self.violations.join("\n")
            );
        }
    }
}

/// A copy of `scenarios/` and `models/` under `dir`, so that mutated files keep their
/// relative paths (`../models/...`, the data scenarios) and nothing in the checkout changes.
fn workspace_copy(dir: &Path) -> PathBuf {
    for sub in ["scenarios", "models"] {
        let to = dir.join(sub);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(root().join(sub)).unwrap() {
            let e = e.unwrap();
            if e.path().is_file() {
                std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
            }
        }
    }
    dir.join("scenarios")
}

/// One mutation of a TOML scenario text.
fn mutate_toml(text: &str, rng: &mut Rng) -> Vec<u8> {
    let lines: Vec<&str> = text.lines().collect();
    let valued: Vec<usize> = (0..lines.len())
        .filter(|&i| {
            let l = lines[i].trim_start();
            !l.starts_with('#') && l.contains(" = ")
        })
        .collect();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    match rng.below(9) {
        // A value replaced by a bad number or a value of the wrong type.
        0..=2 => {
            let i = *rng.pick(&valued);
            let key = out[i].split(" = ").next().unwrap().to_string();
            out[i] = format!("{key} = {}", rng.pick(BAD_NUMBERS));
        }
        // A number inside a list or inline table replaced.
        3 => {
            let i = *rng.pick(&valued);
            let line = out[i].clone();
            let spans: Vec<(usize, usize)> = number_spans(&line);
            if !spans.is_empty() {
                let (a, b) = *rng.pick(&spans);
                out[i] = format!("{}{}{}", &line[..a], rng.pick(BAD_NUMBERS), &line[b..]);
            }
        }
        // A key deleted, or a table duplicated.
        4 => {
            let i = *rng.pick(&valued);
            out.remove(i);
        }
        5 => {
            let tables: Vec<usize> = (0..out.len())
                .filter(|&i| out[i].starts_with('[') && !out[i].starts_with("[["))
                .collect();
            if !tables.is_empty() {
                let i = *rng.pick(&tables);
                out.push(out[i].clone());
            }
        }
        // An unknown key, deep nesting.
        6 => {
            let i = *rng.pick(&valued);
            out.insert(i, "unknown_knob = 3".into());
        }
        7 => out.push(format!(
            "deep = {}{}",
            "[".repeat(200 + rng.below(3000)),
            "]".repeat(3)
        )),
        // Truncated.
        _ => {
            let bytes = out.join("\n");
            let cut = rng.below(bytes.len());
            let mut b = bytes.as_bytes()[..cut].to_vec();
            if rng.below(2) == 0 {
                b.extend_from_slice(&[0xff, 0xfe, b'\n']); // and not UTF-8
            }
            return b;
        }
    }
    out.join("\n").into_bytes()
}

/// Byte ranges of the numbers in a line.
fn number_spans(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !b[i - 1].is_ascii_alphanumeric() && b[i - 1] != b'_');
        if starts {
            let s = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            let mut e = i;
            while e < b.len()
                && (b[e].is_ascii_digit() || matches!(b[e], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                e += 1;
            }
            spans.push((s, e));
            i = e;
        } else {
            i += 1;
        }
    }
    spans
}

/// Scenario files, each with a variant that needs no network training (training is
/// covered by its own family and by the full runs).
fn scenario_targets() -> Vec<(&'static str, Option<&'static str>)> {
    vec![
        ("deadzone.toml", None),
        ("dynamic_nodes.toml", None),
        ("admittance.toml", Some("momentum")),
        ("hand_contact.toml", Some("oracle")),
        ("free_motion.toml", None),
        ("free_motion_validation.toml", None),
    ]
}

#[test]
fn mutated_scenario_files() {
    let mut family = Family::new("scenario mutations");
    let scenarios = workspace_copy(family.dir());
    let mut rng = Rng(seed());
    let targets = scenario_targets();
    for k in 0..cases(60) {
        let (file, variant) = *rng.pick(&targets);
        let text = std::fs::read_to_string(scenarios.join(file)).unwrap();
        let mutated = scenarios.join(format!("case_{k}_{file}"));
        std::fs::write(&mutated, mutate_toml(&text, &mut rng)).unwrap();
        let out = family.dir().join(format!("out_{k}"));
        let sentinel = family.dir().join(format!("mine_{k}.txt"));
        std::fs::write(&sentinel, "the user's").unwrap();
        let (m, o) = (
            mutated.to_str().unwrap().to_string(),
            out.to_str().unwrap().to_string(),
        );
        let mut args = vec![
            "run",
            &m,
            "--out",
            &o,
            "--no-recording",
            "--set",
            "duration=0.3",
            "--set",
            "evaluation_start=0.1",
        ];
        if let Some(v) = variant {
            args.extend_from_slice(&["--variant", v]);
        }
        let outcome = run(&args, Duration::from_secs(60));
        let mut problem = violation(&outcome, Some(&out));
        if std::fs::read_to_string(&sentinel).ok().as_deref() != Some("the user's") {
            problem = Some("a file beside --out was lost".into());
        }
        family.record(&outcome, problem, || {
            format!("admittance {}", args.join(" "))
        });
    }
    family.finish();
}

/// Output targets the tool did not write are refused and kept; killed runs leave nothing
/// that a rerun does not clean.
#[test]
fn user_folders_and_killed_runs() {
    let mut family = Family::new("--out and kills");
    let scenarios = workspace_copy(family.dir());
    let scenario = scenarios.join("deadzone.toml");
    let s = scenario.to_str().unwrap().to_string();
    let mut rng = Rng(seed() ^ 0x5eed);
    for k in 0..cases(6) {
        // A folder of the user's, and a file of the user's, as --out.
        let mine = family.dir().join(format!("mine_{k}"));
        std::fs::create_dir_all(&mine).unwrap();
        std::fs::write(mine.join("thesis.tex"), "years").unwrap();
        let file = family.dir().join(format!("notes_{k}.txt"));
        std::fs::write(&file, "notes").unwrap();
        for target in [&mine, &file] {
            let t = target.to_str().unwrap().to_string();
            let args = [
                "run",
                &s,
                "--out",
                &t,
                "--set",
                "duration=0.2",
                "--no-recording",
            ];
            let o = run(&args, Duration::from_secs(60));
            let mut problem = violation(&o, None);
            if o.code == Some(0) {
                problem = Some("replaced a target the tool did not write".into());
            }
            let kept = std::fs::read_to_string(mine.join("thesis.tex"))
                .ok()
                .as_deref()
                == Some("years")
                && std::fs::read_to_string(&file).ok().as_deref() == Some("notes");
            if !kept {
                problem = Some("lost the user's file".into());
            }
            family.record(&o, problem, || format!("admittance {}", args.join(" ")));
        }
        // A run killed at a random moment, then run again to the same --out.
        let out = family.dir().join(format!("killed_{k}"));
        let o_s = out.to_str().unwrap().to_string();
        let args = [
            "run",
            &s,
            "--out",
            &o_s,
            "--variant",
            "pd",
            "--set",
            "duration=2",
            "--set",
            "evaluation_start=0.5",
            "--no-recording",
        ];
        let mut child = Command::new(env!("CARGO_BIN_EXE_admittance"))
            .args(args)
            .arg("--quiet")
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(rng.below(400) as u64));
        let _ = child.kill();
        let _ = child.wait();
        let o = run(&args, Duration::from_secs(60));
        let mut problem = violation(&o, Some(&out));
        let leftovers: Vec<String> = std::fs::read_dir(family.dir())
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| n.starts_with(&format!(".killed_{k}.partial")))
            .collect();
        if !leftovers.is_empty() {
            problem = Some(format!(
                "stale partial folders after the rerun: {leftovers:?}"
            ));
        }
        family.record(&o, problem, || {
            format!(
                "kill `admittance {}` mid-run, then run it again",
                args.join(" ")
            )
        });
    }
    family.finish();
}

/// A short free-motion recording and a network trained on it, shared by the data families.
fn recorded_data(dir: &Path) -> (PathBuf, PathBuf) {
    let out = dir.join("recording");
    let scenario = root().join("scenarios/free_motion.toml");
    let o = run(
        &[
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--set",
            "duration=4",
            "--no-recording",
        ],
        Duration::from_secs(120),
    );
    assert_eq!(o.code, Some(0), "recording: {}", o.stderr);
    let csv = out.join("free_motion.csv");
    let model = dir.join("model.broad");
    let urdf = root().join("models/baxter_left_arm.urdf");
    let o = run(
        &[
            "train",
            "--data",
            csv.to_str().unwrap(),
            "--urdf",
            urdf.to_str().unwrap(),
            "--tip",
            "left_hand",
            "--nodes",
            "40",
            "--out",
            model.to_str().unwrap(),
        ],
        Duration::from_secs(120),
    );
    assert_eq!(o.code, Some(0), "training: {}", o.stderr);
    (csv, model)
}

#[test]
fn damaged_free_motion_data_and_model_files() {
    let mut family = Family::new("data and models");
    let (csv, model) = recorded_data(family.dir());
    let urdf = root().join("models/baxter_left_arm.urdf");
    let u = urdf.to_str().unwrap().to_string();
    let text = std::fs::read_to_string(&csv).unwrap();
    let bytes = std::fs::read(&model).unwrap();
    let mut rng = Rng(seed() ^ 0xc5f);
    for k in 0..cases(30) {
        // A CSV with a damaged cell, header or column, trained on.
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        match rng.below(5) {
            0 | 1 => {
                let r = 1 + rng.below(lines.len() - 1);
                let mut cells: Vec<String> = lines[r].split(',').map(String::from).collect();
                let c = rng.below(cells.len());
                cells[c] = rng
                    .pick(&["nan", "1e300", "-1e300", "inf", "text", "", "1,2"])
                    .to_string();
                lines[r] = cells.join(",");
            }
            2 => {
                let mut header: Vec<String> = lines[0].split(',').map(String::from).collect();
                let (a, b) = (rng.below(header.len()), rng.below(header.len()));
                header.swap(a, b);
                lines[0] = header.join(",");
            }
            3 => {
                let n = lines.len();
                lines.truncate(1 + rng.below(n - 1));
            }
            _ => {
                let drop = rng.below(lines[0].split(',').count());
                for l in lines.iter_mut() {
                    let cells: Vec<&str> = l.split(',').collect();
                    *l = cells
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| *i != drop)
                        .map(|(_, c)| *c)
                        .collect::<Vec<_>>()
                        .join(",");
                }
            }
        }
        let damaged = family.dir().join(format!("case_{k}.csv"));
        std::fs::write(&damaged, lines.join("\n")).unwrap();
        let out = family.dir().join(format!("model_{k}.broad"));
        let nodes = rng
            .pick(&["30", "200000", "1000000000", "4294967296"])
            .to_string();
        let (d, o_s) = (
            damaged.to_str().unwrap().to_string(),
            out.to_str().unwrap().to_string(),
        );
        let args = [
            "train",
            "--data",
            &d,
            "--urdf",
            &u,
            "--tip",
            "left_hand",
            "--nodes",
            &nodes,
            "--out",
            &o_s,
        ];
        let o = run(&args, Duration::from_secs(60));
        let mut problem = violation(&o, None);
        if o.code == Some(0) && !out.is_file() {
            problem = Some("train exited 0 without writing its model".into());
        }
        family.record(&o, problem, || format!("admittance {}", args.join(" ")));

        // A model file with flipped or missing bytes, grown.
        let mut b = bytes.clone();
        if rng.below(2) == 0 {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
        } else {
            let n = b.len();
            b.truncate(rng.below(n));
        }
        let damaged_model = family.dir().join(format!("case_{k}.broad"));
        std::fs::write(&damaged_model, b).unwrap();
        let grown = family.dir().join(format!("grown_{k}.broad"));
        let (dm, g, c) = (
            damaged_model.to_str().unwrap().to_string(),
            grown.to_str().unwrap().to_string(),
            csv.to_str().unwrap().to_string(),
        );
        let args = [
            "grow", "--model", &dm, "--nodes", "10", "--data", &c, "--out", &g,
        ];
        let o = run(&args, Duration::from_secs(60));
        let mut problem = violation(&o, None);
        if o.code == Some(0) {
            problem = Some("grew a damaged model file".into());
        }
        family.record(&o, problem, || format!("admittance {}", args.join(" ")));
    }
    family.finish();
}

#[test]
fn odd_urdfs() {
    let mut family = Family::new("URDF mutations");
    let mut seeds: Vec<String> = std::fs::read_dir(root().join("fuzz/seeds"))
        .unwrap()
        .filter_map(|e| std::fs::read_to_string(e.ok()?.path()).ok())
        .collect();
    seeds.push(std::fs::read_to_string(root().join("models/baxter_left_arm.urdf")).unwrap());
    let mut rng = Rng(seed() ^ 0x0d0f);
    for k in 0..cases(60) {
        let text = rng.pick(&seeds).clone();
        let spans = number_spans(&text);
        let mutated = match rng.below(4) {
            0 | 1 if !spans.is_empty() => {
                let (a, b) = *rng.pick(&spans);
                let value = rng.pick(&["0", "-1", "1e308", "nan", "inf", "1e200", "x"]);
                format!("{}{}{}", &text[..a], value, &text[b..])
            }
            2 => {
                let mut cut = rng.below(text.len());
                while !text.is_char_boundary(cut) {
                    cut -= 1;
                }
                text[..cut].to_string()
            }
            _ => {
                let kinds = ["type=\"floating\"", "type=\"planar\"", "type=\"ball\""];
                let kind = kinds[rng.below(kinds.len())];
                text.replacen("type=\"revolute\"", kind, 1)
            }
        };
        let file = family.dir().join(format!("case_{k}.urdf"));
        std::fs::write(&file, mutated).unwrap();
        let f = file.to_str().unwrap().to_string();
        for args in [
            vec!["model", "--urdf", &f],
            vec![
                "dynamics",
                "--urdf",
                &f,
                "--q",
                "0.1,0.2,0.3,0.4,0.5,0.6,0.7",
                "--v",
                "1e200,0,0,0,0,0,0",
            ],
        ] {
            let o = run(&args, Duration::from_secs(30));
            let problem = violation(&o, None);
            family.record(&o, problem, || format!("admittance {}", args.join(" ")));
        }
    }
    family.finish();
}
