//! The README's main command on a short run, and `admittance report` / `list`: every
//! output of a run folder exists and parses (summary.json, the CSVs, recording.mcap read
//! back with the mcap crate, the PNGs decoded, the SVGs and report.html parsed as XML with
//! no external references), and bad run folders give exit code 3 with one line naming the
//! file.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn admittance(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .current_dir(root())
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// A fresh folder under the system's temporary directory, removed with everything in it
/// when the returned guard drops (also when the test fails).
fn tempdir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("admittance-report-cli-{tag}-"))
        .tempdir()
        .unwrap()
}

/// Runs the deadzone scenario for 3 s into `dir/run`.
fn short_run(dir: &Path) -> PathBuf {
    let out = dir.join("run");
    let (code, _, err) = admittance(&[
        "run",
        "scenarios/deadzone.toml",
        "--set",
        "duration=3",
        "--set",
        "evaluation_start=1",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    out
}

/// Parses a CSV: every row has the header's column count and only numbers.
fn check_csv(path: &Path) -> (Vec<String>, usize) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    assert_eq!(header[0], "t");
    let mut rows = 0;
    for (k, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(
            fields.len(),
            header.len(),
            "{}: line {}",
            path.display(),
            k + 2
        );
        for f in fields {
            assert!(
                f.parse::<f64>().is_ok(),
                "{}: line {}: {f}",
                path.display(),
                k + 2
            );
        }
        rows += 1;
    }
    (header, rows)
}

#[test]
fn run_writes_every_output_and_report_regenerates_them() {
    let tmp = tempdir("full");
    let dir = tmp.path();
    let out = short_run(dir);

    // summary.json
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["format_version"], 1);
    let variants: Vec<String> = summary["variants"]
        .as_object()
        .unwrap()
        .keys()
        .cloned()
        .collect();
    assert!(
        variants.contains(&"nn_compensated".to_string()),
        "{variants:?}"
    );

    // CSVs
    let mut rows_of = BTreeMap::new();
    for v in &variants {
        let (header, rows) = check_csv(&out.join(format!("{v}.csv")));
        assert!(rows > 100, "{v}: {rows} rows");
        assert!(header.iter().any(|c| c == "tau_ext_hat.left_s0"));
        rows_of.insert(v.clone(), (header, rows));
    }

    // recording.mcap: channels per variant, one message per CSV row and channel, JSON payloads.
    let bytes = std::fs::read(out.join("recording.mcap")).unwrap();
    let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
    let mut last_time: BTreeMap<String, u64> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().expect("a schema");
        assert_eq!(schema.encoding, "jsonschema");
        let _: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        let payload: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        let t = payload["t"].as_f64().unwrap();
        assert_eq!(m.log_time, (t * 1e9).round() as u64);
        let prev = last_time.insert(m.channel.topic.clone(), m.log_time);
        assert!(
            prev.is_none_or(|p| p < m.log_time),
            "{}: time not increasing",
            m.channel.topic
        );
        if m.channel.topic.ends_with("/joint_state") {
            assert!(
                payload["q"]["left_s0"].is_number() && payload["q_meas"]["left_w2"].is_number()
            );
        }
        *per_topic.entry(m.channel.topic.clone()).or_default() += 1;
    }
    for v in &variants {
        let rows = rows_of[v].1;
        for group in ["joint_state", "reference", "torque", "external_torque"] {
            assert_eq!(
                per_topic.get(&format!("/{v}/{group}")),
                Some(&rows),
                "/{v}/{group}: {per_topic:?}"
            );
        }
        let has_nodes = rows_of[v].0.iter().any(|c| c.starts_with("nodes."));
        assert_eq!(
            per_topic.contains_key(&format!("/{v}/nodes")),
            has_nodes,
            "{v}"
        );
    }
    let metadata: Vec<mcap::records::Metadata> = mcap::read::LinearReader::new(&bytes)
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            mcap::records::Record::Metadata(m) => Some(m),
            _ => None,
        })
        .collect();
    assert_eq!(metadata.len(), 1);
    assert_eq!(metadata[0].metadata["format_version"], "1");

    // Figures: the paper's Figs 7-12 and the wide pair, PNGs that decode, SVGs that parse.
    let figures = out.join("figures");
    let mut pngs = Vec::new();
    for e in std::fs::read_dir(&figures).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if name.ends_with(".png") {
            let decoder =
                png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&p).unwrap()));
            let mut reader = decoder.read_info().unwrap();
            let mut buf = vec![0; reader.output_buffer_size()];
            let info = reader.next_frame(&mut buf).unwrap();
            assert!(info.width >= 800 && info.height >= 300, "{name}");
            // Not blank: some pixels are coloured.
            assert!(
                buf.chunks(3).any(|px| px[0] != px[1] || px[1] != px[2]),
                "{name} has no colour"
            );
            pngs.push(name);
        } else if name.ends_with(".svg") {
            let text = std::fs::read_to_string(&p).unwrap();
            roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(
                text.contains("@font-face") && text.contains("data:font/ttf;base64,"),
                "{name}"
            );
        }
    }
    pngs.sort();
    let ids: Vec<&str> = pngs.iter().map(|n| &n[..n.find('_').unwrap()]).collect();
    let mut expected = vec!["fig07", "fig08", "fig09", "fig10", "fig11", "fig12"];
    let has = |v: &str| variants.iter().any(|x| x == v);
    if has("nn_compensated_wide") && has("nn_uncompensated_wide") {
        expected.extend(["fig11b", "fig12b"]);
        expected.sort();
    }
    assert_eq!(ids, expected);

    // report.html: well-formed, self-contained, one image per figure, the figure table.
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // `<!DOCTYPE html>` is the only DTD; the rest must be well-formed XML.
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(&html, options).unwrap();
    assert_eq!(doc.root_element().tag_name().name(), "html");
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "external reference in report.html"
    );
    let imgs: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("img"))
        .collect();
    assert_eq!(imgs.len(), pngs.len());
    assert!(imgs.iter().all(|i| i
        .attribute("src")
        .unwrap()
        .starts_with("data:image/png;base64,")));
    assert!(html.contains("@font-face"));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("figures/fig12_s0_control_inputs.png") && md.contains("| `ee_error_max` | m |")
    );
    // It opens with the experiment's claim and the headline beside the paper's.
    assert!(
        md.starts_with("# Experiment A: deadzone compensation"),
        "{md}"
    );
    let opening = &md[..md.find("## Metrics").unwrap()];
    assert!(
        opening.contains("| quantity | paper | this run | agrees |")
            && opening.contains("below 0.04 m"),
        "{opening}"
    );

    // `admittance report` regenerates the figures, reports and recording.
    std::fs::remove_dir_all(&figures).unwrap();
    std::fs::remove_file(out.join("recording.mcap")).unwrap();
    std::fs::remove_file(out.join("report.html")).unwrap();
    let (code, _, err) = admittance(&["report", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read_dir(&figures).unwrap().count(), 2 * pngs.len());
    assert_eq!(
        std::fs::read(out.join("recording.mcap")).unwrap().len(),
        bytes.len()
    );
    assert!(out.join("report.html").is_file());
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    // Again, over the figures in place: swapped in whole, nothing left beside them.
    let (code, _, err) = admittance(&["report", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read_dir(&figures).unwrap().count(), 2 * pngs.len());
    let hidden = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .count();
    assert_eq!(
        hidden, 0,
        "temporary folders left after replacing the figures"
    );

    // Bad folders: exit 3, one line naming the file.
    let summary_path = out.join("summary.json");
    let good = std::fs::read_to_string(&summary_path).unwrap();
    let cases = [
        (
            "corrupted",
            good[..good.len() / 2].to_string(),
            "summary.json",
            "not valid JSON",
        ),
        (
            "newer version",
            good.replace("\"format_version\": 1", "\"format_version\": 99"),
            "summary.json",
            "format_version 99",
        ),
    ];
    for (what, text, file, words) in cases {
        std::fs::write(&summary_path, text).unwrap();
        let (code, _, err) = admittance(&["report", out.to_str().unwrap()]);
        assert_eq!(code, 3, "{what}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
        assert!(err.contains(file) && err.contains(words), "{what}: {err}");
    }
    std::fs::write(&summary_path, &good).unwrap();
    std::fs::remove_file(out.join("pd.csv")).unwrap();
    let (code, _, err) = admittance(&["report", out.to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("pd.csv") && err.contains("missing"), "{err}");
    let (code, _, err) = admittance(&["report", dir.join("nowhere").to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
}

/// Runs `admittance ARGS` and kills it after `seconds`: `None` when it did not finish.
fn admittance_within(args: &[&str], seconds: u64) -> Option<(i32, String)> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .current_dir(root())
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(seconds);
    while std::time::Instant::now() < deadline {
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            use std::io::Read as _;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            return Some((status.code().unwrap_or(-1), err));
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// Issue 14: a folder whose scenario has `d_right = 1e308` and whose series hold 1e308,
/// NaN and inf made `admittance report` hang in the plotting library. It now finishes,
/// and the report says what it could not draw.
#[test]
fn report_on_huge_and_non_finite_values_finishes() {
    let tmp = tempdir("huge");
    let dir = tmp.path();
    let joints = ["left_s0", "left_s1"];
    let prefixes = ["q_d", "q_r", "q", "tau_cmd", "tau_applied"];
    let mut header = vec!["t".to_string()];
    for p in prefixes {
        header.extend(joints.iter().map(|j| format!("{p}.{j}")));
    }
    header.push("ee_error".into());
    let mut csv = header.join(",") + "\n";
    for r in 0..400 {
        let t = r as f64 * 0.05;
        let value = match r % 50 {
            7 => "1e308".to_string(),
            8 => "-1e308".to_string(),
            9 => "NaN".to_string(),
            10 => "inf".to_string(),
            _ => format!("{}", (t * 0.7).sin()),
        };
        let row: Vec<String> = std::iter::once(format!("{t}"))
            .chain((1..header.len()).map(|_| value.clone()))
            .collect();
        csv += &(row.join(",") + "\n");
    }
    for v in ["nn_compensated", "nn_uncompensated"] {
        std::fs::write(dir.join(format!("{v}.csv")), &csv).unwrap();
    }
    std::fs::write(
        dir.join("summary.json"),
        r#"{"format": "admittance-run", "format_version": 1, "scenario": "deadzone", "joints": ["left_s0", "left_s1"],
            "variants": {"nn_compensated": {"ee_error_max": 0.001}, "nn_uncompensated": {"ee_error_max": 0.002}}}"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("scenario.toml"),
        "name = \"deadzone\"\nevaluation_start = 5.0\n[arm]\nurdf = \"nowhere.urdf\"\n[controller]\nkind = \"neural\"\n[[plant.deadzones]]\njoint = \"left_s0\"\nd_left = -0.49\nd_right = 1e308\n[variants.nn_uncompensated]\ncontroller.neural.deadzone_compensation = false\n",
    )
    .unwrap();
    let (code, err) = admittance_within(&["report", dir.to_str().unwrap(), "--quiet"], 120)
        .expect("`admittance report` hangs on huge or non-finite values");
    assert_eq!(code, 0, "{err}");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        md.contains("not drawn") && md.contains("**Warning:**"),
        "{md}"
    );
    assert!(md.contains("the line at y = 1e308"), "{md}");
    for f in [
        "fig08_end_effector_error.png",
        "fig12_s0_control_inputs.png",
    ] {
        assert!(dir.join("figures").join(f).is_file(), "{f}");
    }
}

/// Issue 25: the report is chosen by what the scenario contains, not by its name. The
/// committed Panda deadzone scenario, copied under another file name and scenario name,
/// gets experiment A's report with the figures of its deadzone joint, and its run folder
/// records the deadzone the plant applied (settings.json).
#[test]
fn a_renamed_panda_deadzone_scenario_gets_the_deadzone_report() {
    let tmp = tempdir("renamed");
    let dir = tmp.path();
    let text = std::fs::read_to_string(root().join("scenarios/panda_deadzone.toml"))
        .unwrap()
        .replace("name = \"panda_deadzone\"", "name = \"my_arm_trial\"")
        .replace(
            "urdf = \"../models/franka_panda.urdf\"",
            &format!(
                "urdf = {:?}",
                root()
                    .join("models/franka_panda.urdf")
                    .canonicalize()
                    .unwrap()
            ),
        );
    let scenario = dir.join("trial.toml");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.join("run");
    let (code, _, err) = admittance(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--variant",
        "nn_compensated",
        "--variant",
        "nn_uncompensated",
        "--variant",
        "pd",
        "--set",
        "duration=1",
        "--set",
        "evaluation_start=0.5",
        // A 1 s run is all start-up transient: the hand-error rule is not what this checks.
        "--set",
        "health.max_hand_error=inf",
        "--no-recording",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.starts_with("# Experiment A: deadzone compensation (scenario `my_arm_trial`)"),
        "{md}"
    );
    assert!(
        md.contains("panda_joint1 tracking RMSE, compensated / PD"),
        "{md}"
    );
    assert!(
        !md.contains("settings.json"),
        "a new folder has its settings: {md}"
    );
    for f in [
        "fig08_end_effector_error",
        "fig11_s0_errors",
        "fig12_s0_control_inputs",
    ] {
        assert!(
            out.join("figures").join(format!("{f}.png")).is_file(),
            "{f}"
        );
    }
    let svg = std::fs::read_to_string(out.join("figures/fig12_s0_control_inputs.svg")).unwrap();
    assert!(
        svg.contains("joint panda_joint1"),
        "Fig 12 shows the deadzone joint"
    );
    let settings: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("settings.json")).unwrap()).unwrap();
    assert_eq!(settings["format"], "admittance-run-settings");
    assert_eq!(
        settings["variants"][1]["deadzones"][0],
        serde_json::json!({"joint": "panda_joint1", "d_left": -0.49, "d_right": 0.49, "slope_left": 1.0, "slope_right": 1.0})
    );
    assert_eq!(settings["variants"][1]["deadzone_compensation"], false);
    assert_eq!(settings["variants"][2]["controller"], "pd");

    // The same folder without settings.json (written by an earlier build): still the
    // deadzone report, read from scenario.toml, and the report says so.
    std::fs::remove_file(out.join("settings.json")).unwrap();
    let (code, _, err) =
        admittance(&["report", out.to_str().unwrap(), "--no-recording", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.starts_with("# Experiment A"), "{md}");
    assert!(md.contains("has no `settings.json`"), "{md}");
    // A malformed one is refused with the file named (exit 3), never a panic.
    std::fs::write(
        out.join("settings.json"),
        "{\"format\": \"admittance-run-settings\", \"format_version\": 7}",
    )
    .unwrap();
    let (code, _, err) = admittance(&["report", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("settings.json") && err.contains("format_version 7"),
        "{err}"
    );
}

#[test]
fn list_shows_every_scenario_with_its_description() {
    let (code, out, err) = admittance(&["list"]);
    assert_eq!(code, 0, "{err}");
    let files: Vec<String> = std::fs::read_dir(root().join("scenarios"))
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    assert_eq!(out.lines().count(), files.len(), "{out}");
    let deadzone = out
        .lines()
        .find(|l| l.starts_with("deadzone.toml"))
        .expect("deadzone listed");
    assert!(deadzone.contains("Experiment A"), "{deadzone}");

    let tmp = tempdir("list");
    let dir = tmp.path();
    std::fs::write(
        dir.join("ok.toml"),
        "name = \"x\"\ndescription = \"a test\"\n",
    )
    .unwrap();
    std::fs::write(dir.join("bad.toml"), "name = \n").unwrap();
    let (code, out, err) = admittance(&["list", "--dir", dir.to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
    assert!(out.contains("ok.toml") && out.contains("a test"), "{out}");
    assert!(
        err.contains("bad.toml") && err.trim_end().lines().count() == 1,
        "{err}"
    );
}
