//! Settings travel with the files (issue 30 item 6) and `evaluate` refuses what was made for
//! another arm or identification (issue 34 item 6): the conditioning comes from the
//! identification and network files, a contradicting flag is refused, a residual network
//! given as `--network` is recognised, and a residual without a recording of other motion
//! is all zeros (issue 30 item 5).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn admittance(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn ok(args: &[&str]) -> String {
    let o = admittance(args);
    assert!(o.status.success(), "{args:?}\n{}", text(&o));
    text(&o)
}

/// The rms column of the row of `evaluate`'s table named `name`.
fn rms(table: &str, name: &str) -> f64 {
    let line = table
        .lines()
        .find(|l| l.starts_with(name))
        .unwrap_or_else(|| panic!("no row {name} in\n{table}"));
    line[name.len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// Free motion of the Baxter model with friction it does not know and sensor noise, as a
/// CSV whose columns name the joints `names` (the Baxter's, or another arm's of 7 joints).
fn free_motion_csv(dir: &Path, seed: f64, seconds: f64, names: &[String]) -> PathBuf {
    crate::free_motion::multisine_csv(
        dir.join(format!("free_{seed}_{}.csv", names[0])),
        seed,
        seconds,
        names,
        |k, i, qd| {
            // Deterministic "noise": what no model of q, q', q'' explains.
            let noise = 0.3 * ((k * (i + 3)) as f64 * 1.618).sin();
            1.5 * qd[i] + 0.8 * (qd[i] / 0.01).tanh() + noise
        },
    )
}

fn joints(urdf: &str) -> Vec<String> {
    admittance_dynamics::Model::from_urdf_file(&root().join(urdf), None, None)
        .unwrap()
        .joint_names()
        .map(String::from)
        .collect()
}

struct Files {
    _dir: tempfile::TempDir,
    urdf: String,
    train: String,
    other: String,
    ident10: String,
}

/// Two recordings and a 10 Hz identification of the first.
fn files() -> Files {
    let dir = tempfile::tempdir().unwrap();
    let names: Vec<String> = crate::free_motion::baxter()
        .joint_names()
        .map(String::from)
        .collect();
    let train = free_motion_csv(dir.path(), 0.3, 30.0, &names);
    let other = free_motion_csv(dir.path(), 1.9, 12.0, &names);
    let urdf = root().join("models/baxter_left_arm.urdf");
    let ident10 = dir.path().join("ten.ident.json");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    ok(&[
        "identify",
        "--data",
        &s(&train),
        "--urdf",
        &s(&urdf),
        "--input-filter-hz",
        "10",
        "--out",
        &s(&ident10),
    ]);
    Files {
        urdf: s(&urdf),
        train: s(&train),
        other: s(&other),
        ident10: s(&ident10),
        _dir: dir,
    }
}

impl Files {
    fn path(&self, name: &str) -> String {
        self._dir.path().join(name).to_str().unwrap().to_string()
    }

    /// `admittance evaluate` of `data` with the 10 Hz identification.
    fn evaluate(&self, data: &str) -> String {
        ok(&[
            "evaluate",
            "--data",
            data,
            "--urdf",
            &self.urdf,
            "--identification",
            &self.ident10,
        ])
    }

    /// `admittance calibrate-contact` on `data` with the 10 Hz identification.
    fn calibrate(&self, data: &str) -> String {
        ok(&[
            "calibrate-contact",
            data,
            "--identification",
            &self.ident10,
            "--out",
            &self.path("floor.json"),
        ])
    }
}

/// The indented lines of `printed` below the line starting with `heading`.
fn listed_under<'a>(printed: &'a str, heading: &str) -> Vec<&'a str> {
    printed
        .lines()
        .skip_while(|l| !l.starts_with(heading))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .collect()
}

#[test]
fn evaluate_conditions_as_the_identification_was_fitted() {
    let f = files();
    let eval = |extra: &[&str]| {
        let mut args = vec![
            "evaluate",
            "--data",
            &f.other,
            "--urdf",
            &f.urdf,
            "--identification",
            &f.ident10,
        ];
        args.extend_from_slice(extra);
        admittance(&args)
    };
    let default = eval(&[]);
    assert!(default.status.success(), "{}", text(&default));
    let table = text(&default);
    assert!(table.contains("input filter: 10 Hz"), "{table}");
    let explicit = text(&eval(&["--input-filter-hz", "10"]));
    let name = "identified + joint terms";
    assert_eq!(
        rms(&table, name),
        rms(&explicit, name),
        "{table}\n{explicit}"
    );
    // The raw signals would score it differently: the default is not the raw columns.
    let wrong = eval(&["--input-filter-hz", "0"]);
    assert_eq!(wrong.status.code(), Some(2), "{}", text(&wrong));
    let message = text(&wrong);
    assert!(
        message.contains("--input-filter-hz 0") && message.contains(&f.ident10),
        "{message}"
    );
}

#[test]
fn a_residual_is_recognised_and_checked_against_its_identification() {
    let f = files();
    let residual = f.path("residual.bin");
    // With a recording of other motion: a residual is fitted (outputs that gain on it kept).
    ok(&[
        "train",
        "--data",
        &f.train,
        "--urdf",
        &f.urdf,
        "--nominal",
        &f.ident10,
        "--validation",
        &f.other,
        "--nodes",
        "40",
        "--out",
        &residual,
        "--quiet",
    ]);
    // Given as --network, it is scored as the identification + residual.
    let table = ok(&[
        "evaluate",
        "--data",
        &f.other,
        "--urdf",
        &f.urdf,
        "--identification",
        &f.ident10,
        "--network",
        &residual,
    ]);
    assert!(table.contains("identified + residual network"), "{table}");
    assert!(table.contains("hybrid (identified + residual)"), "{table}");
    assert!(!table.contains(&format!("network {residual}")), "{table}");
    // Without its identification: refused, naming the flag.
    let o = admittance(&[
        "evaluate",
        "--data",
        &f.other,
        "--urdf",
        &f.urdf,
        "--network",
        &residual,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--identification"), "{}", text(&o));
    // With another identification (another checksum): refused, naming both files.
    let raw = f.path("raw.ident.json");
    ok(&[
        "identify", "--data", &f.train, "--urdf", &f.urdf, "--out", &raw,
    ]);
    for flag in ["--network", "--residual"] {
        let o = admittance(&[
            "evaluate",
            "--data",
            &f.other,
            "--urdf",
            &f.urdf,
            "--identification",
            &raw,
            flag,
            &residual,
        ]);
        assert_eq!(o.status.code(), Some(3), "{}", text(&o));
        let m = text(&o);
        assert!(
            m.contains("checksum") && m.contains(&raw) && m.contains(&residual),
            "{m}"
        );
    }
    // train --nominal takes the identification's conditioning; a flag against it is refused.
    let o = admittance(&[
        "train",
        "--data",
        &f.train,
        "--urdf",
        &f.urdf,
        "--nominal",
        &f.ident10,
        "--input-filter-hz",
        "4",
        "--nodes",
        "40",
        "--out",
        &f.path("refused.bin"),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!Path::new(&f.path("refused.bin")).exists());
}

#[test]
fn a_residual_without_other_motion_is_the_identification_alone() {
    let f = files();
    let residual = f.path("cv.bin");
    let out = ok(&[
        "train",
        "--data",
        &f.train,
        "--urdf",
        &f.urdf,
        "--nominal",
        &f.ident10,
        "--nodes",
        "40",
        "--out",
        &residual,
        "--quiet",
    ]);
    assert!(out.contains("zeroed (every output)"), "{out}");
    let table = ok(&[
        "evaluate",
        "--data",
        &f.other,
        "--urdf",
        &f.urdf,
        "--identification",
        &f.ident10,
        "--residual",
        &residual,
    ]);
    assert_eq!(
        rms(&table, "hybrid (identified + residual)"),
        rms(&table, "momentum (identified)"),
        "{table}"
    );
    assert_eq!(
        rms(&table, "identified + residual network"),
        rms(&table, "identified + joint terms"),
        "{table}"
    );
}

#[test]
fn a_network_of_another_arm_is_refused() {
    let f = files();
    let net = f.path("baxter.bin");
    ok(&[
        "train", "--data", &f.train, "--urdf", &f.urdf, "--nodes", "40", "--out", &net, "--quiet",
    ]);
    // The same motion under the Panda's joint names: sizes agree, the arm does not.
    let panda = root().join("models/franka_panda.urdf");
    let names = joints("models/franka_panda.urdf");
    assert_eq!(names.len(), 7);
    let data = free_motion_csv(Path::new(&f.path("")), 1.9, 3.0, &names);
    let o = admittance(&[
        "evaluate",
        "--data",
        data.to_str().unwrap(),
        "--urdf",
        panda.to_str().unwrap(),
        "--network",
        &net,
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let m = text(&o);
    assert!(m.contains(&net) && m.contains("joints"), "{m}");
    // A torque network given as the residual: refused, naming the right flag.
    let o = admittance(&[
        "evaluate",
        "--data",
        &f.other,
        "--urdf",
        &f.urdf,
        "--identification",
        &f.ident10,
        "--residual",
        &net,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--network"), "{}", text(&o));
}

#[test]
fn evaluate_and_calibrate_name_the_joints_that_leave_the_training_range() {
    let f = files();
    let eval = |data: &str| f.evaluate(data);
    let heading = "outside the identification's training range";
    // The training recording itself stays inside.
    let inside = eval(&f.train);
    assert!(!inside.contains(heading), "{inside}");
    // The same motion with the first joint 0.5 rad further: that joint, and only it.
    let text = std::fs::read_to_string(&f.train).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let column = header.split(',').position(|c| c == "q.left_s0").unwrap();
    let mut shifted = format!("{header}\n");
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        cells[column] = (cells[column].parse::<f64>().unwrap() + 0.5).to_string();
        shifted += &(cells.join(",") + "\n");
    }
    let path = f.path("shifted.csv");
    std::fs::write(&path, shifted).unwrap();
    let outside = eval(&path);
    assert!(outside.contains(heading), "{outside}");
    let listed = listed_under(&outside, heading);
    assert_eq!(listed.len(), 1, "{outside}");
    assert!(listed[0].starts_with("  left_s0: "), "{outside}");
    // About 0.5 rad beyond (the conditioning's edges aside).
    let beyond: f64 = listed[0]
        .rsplit('(')
        .next()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((beyond - 0.5).abs() < 0.05, "{outside}");
    // A contact floor calibrated there is warned about, naming the file and the joint.
    let calibrate = |data: &str| f.calibrate(data);
    let warning = "outside the identification's training range";
    assert!(!calibrate(&f.train).contains(warning));
    let warned = calibrate(&path);
    let lines: Vec<&str> = warned.lines().filter(|l| l.contains(warning)).collect();
    assert_eq!(lines.len(), 1, "{warned}");
    assert!(
        lines[0].contains("shifted.csv") && lines[0].contains("left_s0: "),
        "{warned}"
    );
}

#[test]
fn evaluate_names_the_joints_that_move_faster_than_trained() {
    let f = files();
    let eval = |data: &str| f.evaluate(data);
    let heading = "faster than the identification's training speeds";
    // The training recording itself stays within them.
    let within = eval(&f.train);
    assert!(!within.contains(heading), "{within}");
    // The same motion played twice as fast: the same positions, every joint faster than
    // trained.
    let path = f.path("faster.csv");
    crate::free_motion::played_faster(Path::new(&f.train), Path::new(&path), 2.0);
    let printed = eval(&path);
    assert!(printed.contains(heading), "{printed}");
    assert!(
        !printed.contains("outside the identification's training range"),
        "{printed}"
    );
    let listed = listed_under(&printed, heading);
    assert_eq!(listed.len(), 7, "{printed}");
    // Each joint's fastest sample about twice its training speed.
    for line in listed {
        let words: Vec<&str> = line.split_whitespace().collect();
        let at = |w: &str| words.iter().position(|x| *x == w).unwrap();
        let fastest: f64 = words[at("to") + 1].parse().unwrap();
        let trained: f64 = words[at("against") + 1].parse().unwrap();
        let ratio = fastest / trained;
        assert!((ratio - 2.0).abs() < 0.15, "{line}");
    }
    // A contact floor calibrated there is warned about, naming the file and each joint.
    let calibrate = |data: &str| f.calibrate(data);
    let warning = "faster than the identification's training speeds";
    assert!(!calibrate(&f.train).contains(warning));
    let warned = calibrate(&path);
    let lines: Vec<&str> = warned.lines().filter(|l| l.contains(warning)).collect();
    assert_eq!(lines.len(), 7, "{warned}");
    assert!(lines.iter().all(|l| l.contains("faster.csv")), "{warned}");
}
