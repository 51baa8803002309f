//! `admittance train` / `grow` on the cases of issue 14: model files that know their arm
//! and settings (the README's `grow` example), non-finite fits, requests that cannot fit,
//! our own argument errors, `--out` that would destroy something, and free-motion files
//! with shuffled or extra columns. Each case failed before (exit 0 with NaN, an abort, a
//! replaced device, a refused valid file...).
//!
//! `ADMITTANCE_TEST_BIN=/path/to/admittance` runs the same checks against another build.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bin() -> String {
    std::env::var("ADMITTANCE_TEST_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_admittance").into())
}

fn admittance(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(bin())
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Two seconds of simulated free motion (2000 rows) in `dir`.
fn free_motion(dir: &Path) -> PathBuf {
    let run = dir.join("run");
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/free_motion.toml",
        "--out",
        s(&run),
        "--quiet",
        "--set",
        "duration=2.0",
    ]);
    assert_eq!(code, 0, "{err}");
    run.join("free_motion.csv")
}

const ARM: [&str; 6] = [
    "--urdf",
    "models/baxter_left_arm.urdf",
    "--base",
    "base",
    "--tip",
    "left_hand",
];

fn train(data: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["train", "--data", s(data), "--out", s(out), "--quiet"];
    args.extend_from_slice(&ARM);
    args.extend_from_slice(extra);
    if !extra.contains(&"--nodes") {
        args.extend_from_slice(&["--nodes", "20"]);
    }
    admittance(&args)
}

fn grow(model: &Path, data: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "grow",
        "--model",
        s(model),
        "--data",
        s(data),
        "--out",
        s(out),
        "--nodes",
        "5",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    admittance(&args)
}

#[test]
fn grow_takes_the_settings_from_the_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let model = dir.path().join("arm.broad");
    let (code, _, err) = train(
        &data,
        &model,
        &["--friction-features", "--input-filter-hz", "10"],
    );
    assert_eq!(code, 0, "{err}");
    // The README's example: no filter flag. Before: "growth data does not match the
    // training data", exit 1.
    let grown = dir.path().join("grown.broad");
    let (code, out, err) = grow(&model, &data, &grown, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("nodes: 25 (+5)"), "{out}");
    // The same value is fine; another one is an argument error saying what differs.
    let (code, _, err) = grow(&model, &data, &grown, &["--input-filter-hz", "10"]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = grow(&model, &data, &grown, &["--input-filter-hz", "0"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--input-filter-hz 0, but")
            && err.contains("trained with --input-filter-hz 10"),
        "{err}"
    );
    let (code, _, err) = grow(&model, &data, &grown, &["--validation-fraction", "0.3"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("blocked cross-validation over 5 stretches"),
        "{err}"
    );
    // The file records the arm and the settings.
    let bytes = std::fs::read(&grown).unwrap();
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + h_len]).unwrap();
    assert_eq!(header["format_version"], 2);
    assert_eq!(header["arm"]["joints"][0], "left_s0");
    assert_eq!(header["arm"]["fingerprint"].as_str().unwrap().len(), 16);
    assert_eq!(header["data"]["input_filter_hz"], 10.0);
    assert_eq!(
        header["data"]["validation"]["kind"],
        "blocked_cross_validation"
    );
    assert_eq!(header["data"]["validation"]["folds"], 5);
    assert_eq!(header["data"]["target"]["kind"], "free_motion_torque");
    assert_eq!(header["growth"][0]["nodes_added"], 5);
    assert_eq!(header["fit"]["nodes"], 20);
}

#[test]
fn a_model_of_another_arm_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let model = dir.path().join("arm.broad");
    assert_eq!(train(&data, &model, &[]).0, 0);
    let out = dir.path().join("grown.broad");
    // The other arm's data (before: it grew on them, exit 0).
    let text = std::fs::read_to_string(&data).unwrap();
    let (header, body) = text.split_once('\n').unwrap();
    let right = dir.path().join("right.csv");
    std::fs::write(
        &right,
        format!("{}\n{body}", header.replace("left_", "right_")),
    )
    .unwrap();
    let (code, _, err) = grow(&model, &right, &out, &[]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("missing column `q.left_s0`"), "{err}");
    assert!(err.contains("the file's joints are [right_s0"), "{err}");
    // The same joint names on a heavier arm model: the fingerprint differs.
    let urdf = std::fs::read_to_string(root().join("models/baxter_left_arm.urdf")).unwrap();
    let heavy = urdf.replacen("<mass value=\"2.07206\"", "<mass value=\"2.5\"", 1);
    assert_ne!(heavy, urdf);
    let heavy_path = dir.path().join("heavy.urdf");
    std::fs::write(&heavy_path, heavy).unwrap();
    let (code, _, err) = grow(
        &model,
        &data,
        &out,
        &[
            "--urdf",
            s(&heavy_path),
            "--base",
            "base",
            "--tip",
            "left_hand",
        ],
    );
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("arm fingerprint"), "{err}");
    assert!(!out.exists());
    // The arm it was trained for passes.
    let mut args = vec!["--urdf"];
    args.extend_from_slice(&ARM[1..]);
    let (code, _, err) = grow(&model, &data, &out, &args);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn growth_on_other_data_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let model = dir.path().join("arm.broad");
    assert_eq!(train(&data, &model, &[]).0, 0);
    let text = std::fs::read_to_string(&data).unwrap();
    let short = dir.path().join("short.csv");
    let lines: Vec<&str> = text.lines().collect();
    std::fs::write(&short, lines[..lines.len() - 100].join("\n")).unwrap();
    // Before: exit 1.
    let (code, _, err) = grow(&model, &short, &dir.path().join("g.broad"), &[]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("does not match the training data"), "{err}");
}

#[test]
fn a_huge_torque_is_bad_input_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = header.iter().position(|c| *c == "tau.left_e1").unwrap();
    let mut fields: Vec<String> = lines[100].split(',').map(String::from).collect();
    fields[col] = "1e300".into();
    lines[100] = fields.join(",");
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let model = dir.path().join("m.broad");
    // Before: "validation nrmse: [NaN, ...]", a model grow cannot use, exit 0.
    let (code, out, err) = train(&bad, &model, &[]);
    assert_eq!(code, 3, "{out}{err}");
    assert!(
        err.contains("bad.csv:101: column `tau.left_e1`: 1e300 is beyond"),
        "{err}"
    );
    assert!(!model.exists());
}

#[test]
fn arguments_get_our_own_messages() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let model = dir.path().join("m.broad");
    // Before: clap's "unexpected argument '-5'".
    let (code, _, err) = train(&data, &model, &["--nodes", "-5"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("'-5' for '--nodes") && err.contains("positive integer"),
        "{err}"
    );
    // Before: NaN accepted and treated as 0 (exit 0).
    for (flag, value) in [
        ("--input-filter-hz", "nan"),
        ("--input-filter-hz", "-3"),
        ("--input-filter-hz", "inf"),
        ("--validation-fraction", "nan"),
        ("--max-memory-gb", "0"),
    ] {
        let (code, _, err) = train(&data, &model, &[flag, value]);
        assert_eq!(code, 2, "{flag} {value}: {err}");
        assert!(err.contains(&format!("'{value}' for '{flag}")), "{err}");
    }
    assert!(!model.exists());
}

#[test]
fn requests_that_cannot_fit_are_refused_at_once_with_the_figure() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let model = dir.path().join("m.broad");
    // Before: an abort ("memory allocation of 168000000000 bytes failed", exit 134) and
    // over a minute of silent work.
    for nodes in ["1000000000", "200000", "4294967296"] {
        let started = Instant::now();
        let (code, _, err) = train(&data, &model, &["--nodes", nodes]);
        assert_eq!(code, 2, "{nodes}: {err}");
        assert!(
            err.contains(&format!(
                "{nodes} nodes need at least as many training rows, the data have 2000"
            )),
            "{err}"
        );
        assert!(started.elapsed() < Duration::from_secs(20));
    }
    // Within the rows but over a memory limit: the figure and the flag to raise it.
    let (code, _, err) = train(
        &data,
        &model,
        &["--nodes", "1000", "--max-memory-gb", "0.01"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("1000 nodes need")
            && err.contains("MB of memory, more than the limit of 10 MB"),
        "{err}"
    );
    assert!(err.contains("--max-memory-gb"), "{err}");
    let (code, _, err) = train(&data, &model, &["--nodes", "1000", "--max-tflop", "0.001"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("floating-point operations") && err.contains("--max-tflop"),
        "{err}"
    );
    assert!(!model.exists());
}

#[test]
fn out_never_replaces_what_the_tool_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let user_file = dir.path().join("notes.txt");
    std::fs::write(&user_file, "mine").unwrap();
    let folder = dir.path().join("models");
    std::fs::create_dir(&folder).unwrap();
    let mut cases: Vec<(PathBuf, &str)> = vec![
        (user_file.clone(), "is not a model file"),
        (folder.clone(), "is a folder"),
        (dir.path().join("missing/m.broad"), "its folder"),
    ];
    #[cfg(unix)]
    {
        let dev = dir.path().join("dev.broad");
        std::os::unix::fs::symlink("/dev/null", &dev).unwrap();
        cases.push((dev, "is a device"));
        let fifo = dir.path().join("fifo.broad");
        if Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            cases.push((fifo, "is a FIFO"));
        }
    }
    for (out, needle) in &cases {
        // Refused before any work: no "training on" line (not quiet here).
        let mut args = vec![
            "train",
            "--data",
            s(&data),
            "--out",
            s(out),
            "--nodes",
            "20",
        ];
        args.extend_from_slice(&ARM);
        let (code, _, err) = admittance(&args);
        assert_eq!(code, 2, "{}: {err}", out.display());
        assert!(err.contains("--out") && err.contains(needle), "{err}");
        assert!(!err.contains("training on"), "{err}");
        let (code, _, err) = grow(&user_file, &data, out, &[]);
        assert_eq!(code, 2, "grow {}: {err}", out.display());
    }
    assert_eq!(std::fs::read_to_string(&user_file).unwrap(), "mine");
    assert!(folder.is_dir());
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let dev = dir.path().join("dev.broad");
        assert!(std::fs::symlink_metadata(&dev)
            .unwrap()
            .file_type()
            .is_symlink());
        assert!(std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());
    }
    // A model file is replaced; a link to one writes through the link.
    let model = dir.path().join("m.broad");
    assert_eq!(train(&data, &model, &[]).0, 0);
    assert_eq!(train(&data, &model, &["--nodes", "30"]).0, 0);
    #[cfg(unix)]
    {
        let link = dir.path().join("link.broad");
        std::os::unix::fs::symlink(&model, &link).unwrap();
        assert_eq!(train(&data, &link, &["--nodes", "25"]).0, 0);
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
    }
}

#[test]
fn shuffled_and_extra_columns_train_the_same_model() {
    let dir = tempfile::tempdir().unwrap();
    let data = free_motion(dir.path());
    let text = std::fs::read_to_string(&data).unwrap();
    // Columns reversed (the joints too) and a text column in front.
    let shuffled: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(k, l)| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.reverse();
            let note = if k == 0 { "note" } else { "free text" };
            format!("{note},{}", f.join(","))
        })
        .collect();
    let other = dir.path().join("shuffled.csv");
    std::fs::write(&other, shuffled.join("\n")).unwrap();
    let (a, b) = (dir.path().join("a.broad"), dir.path().join("b.broad"));
    let (code, _, err) = train(&data, &a, &["--input-filter-hz", "10"]);
    assert_eq!(code, 0, "{err}");
    // Before: "is not a number" for the text column, or the joints' order refused.
    let (code, _, err) = train(&other, &b, &["--input-filter-hz", "10"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // A bad number names the line and the column; a missing column is named.
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[7] = lines[7].replacen(',', ",1.2.3", 1);
    std::fs::write(&other, lines.join("\n")).unwrap();
    let (code, _, err) = train(&other, &b, &[]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("shuffled.csv:8: column `q.left_s0`: `1.2.3"),
        "{err}"
    );
    let no_tau: Vec<String> = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            f[..f.len() - 1].join(",")
        })
        .collect();
    std::fs::write(&other, no_tau.join("\n")).unwrap();
    let (code, _, err) = train(&other, &b, &[]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("missing column `tau.left_w2`"), "{err}");
}
