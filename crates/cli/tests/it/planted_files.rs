//! Files the commands write are never written through a link planted beside or at the
//! destination, and special files named as inputs are refused instead of blocking
//! (issue 34, items 4 and 9).

use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs the binary from the repository root, killed after `seconds` (`None`: it hung).
fn admittance_within(args: &[&str], seconds: u64) -> Option<Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_admittance"))
        .args(args)
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(seconds) {
        if child.try_wait().unwrap().is_some() {
            return Some(child.wait_with_output().unwrap());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(made.success());
}

/// Links named as the temporary files of the next few hundred processes used to be
/// (`.NAME.tmp-PID`, `.NAME.tmpPID`), all pointing at `victim`.
fn plant_predictable_links(dir: &Path, name: &str, victim: &Path) {
    let last: u32 = std::fs::read_to_string("/proc/sys/kernel/ns_last_pid")
        .ok()
        .and_then(|t| t.trim().parse().ok())
        .unwrap_or(0);
    for pid in last + 1..last + 400 {
        let _ = symlink(victim, dir.join(format!(".{name}.tmp-{pid}")));
        let _ = symlink(victim, dir.join(format!(".{name}.tmp{pid}")));
    }
}

#[test]
fn excite_never_writes_through_a_planted_link() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "another user's file").unwrap();
    plant_predictable_links(dir.path(), "panda.csv", &victim);
    let out = dir.path().join("panda.csv");
    let args = [
        "excite",
        "--urdf",
        "models/franka_panda.urdf",
        "--duration",
        "10",
        "--iterations",
        "20",
        "--rate",
        "50",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = admittance_within(&args, 120).expect("excite finishes");
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(&victim).unwrap(),
        "another user's file"
    );
    assert!(std::fs::read_to_string(&out).unwrap().starts_with("t,q."));
    // A link at the destination itself to a file `excite` wrote: refused, left as it was.
    let link = dir.path().join("link.csv");
    symlink(&out, &link).unwrap();
    let before = std::fs::read_to_string(&out).unwrap();
    let mut args = args;
    let link_arg = link.to_str().unwrap().to_string();
    args[10] = &link_arg;
    let o = admittance_within(&args, 120).expect("excite finishes");
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("symbolic link"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), before);
}

/// The file format's checksum (docs/outputs.md): FNV-1a 64 of the payload's JSON text.
fn checksum(payload: &serde_json::Value) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in payload.to_string().bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// An identification file of the Baxter model (its URDF's own inertias) naming `urdf`.
fn identification_naming(path: &Path, urdf: &str) {
    use admittance_dynamics::{Identification, Model};
    let model = Model::from_urdf_file(
        &root().join("models/baxter_left_arm.urdf"),
        Some("base"),
        Some("left_hand"),
    )
    .unwrap();
    Identification::from_model(model.clone())
        .save(path, &model, Default::default())
        .unwrap();
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    fn zero_nulls(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Null => *v = 0.0.into(),
            serde_json::Value::Array(a) => a.iter_mut().for_each(zero_nulls),
            serde_json::Value::Object(o) => o.values_mut().for_each(zero_nulls),
            _ => {}
        }
    }
    zero_nulls(&mut v["payload"]["summary"]);
    v["payload"]["urdf"] = urdf.into();
    v["checksum"] = checksum(&v["payload"]).into();
    std::fs::write(path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

#[test]
fn identify_out_naming_a_fifo_as_its_urdf_does_not_hang() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("arm.urdf");
    mkfifo(&fifo);
    let out = dir.path().join("fifo.ident.json");
    identification_naming(&out, fifo.to_str().unwrap());
    let o = admittance_within(
        &[
            "identify",
            "--data",
            dir.path().join("missing.csv").to_str().unwrap(),
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--base",
            "base",
            "--tip",
            "left_hand",
            "--out",
            out.to_str().unwrap(),
        ],
        60,
    )
    .expect("identify must not block on a FIFO");
    assert!(!o.status.success(), "{}", text(&o));
}

#[test]
fn identify_out_through_a_link_to_an_identification_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("theirs.ident.json");
    identification_naming(
        &victim,
        root().join("models/baxter_left_arm.urdf").to_str().unwrap(),
    );
    let before = std::fs::read(&victim).unwrap();
    let link = dir.path().join("mine.ident.json");
    symlink(&victim, &link).unwrap();
    let data = dir.path().join("still.csv");
    // Any data: the destination is refused before or after the fit, never written through.
    let names = [
        "left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2",
    ];
    let mut csv = String::from("t");
    for k in ["q", "qdot", "qddot", "tau"] {
        names.iter().for_each(|j| csv += &format!(",{k}.{j}"));
    }
    csv.push('\n');
    for r in 0..2000 {
        let t = r as f64 * 0.005;
        csv += &format!("{t}");
        for k in 0..28 {
            csv += &format!(",{}", (t * (1.0 + k as f64 * 0.37)).sin());
        }
        csv.push('\n');
    }
    std::fs::write(&data, csv).unwrap();
    let o = admittance_within(
        &[
            "identify",
            "--data",
            data.to_str().unwrap(),
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--base",
            "base",
            "--tip",
            "left_hand",
            "--out",
            link.to_str().unwrap(),
        ],
        300,
    )
    .expect("identify finishes");
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("symbolic link"), "{}", text(&o));
    assert_eq!(std::fs::read(&victim).unwrap(), before);
}

#[test]
fn a_fifo_or_device_as_an_input_file_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("data.csv");
    mkfifo(&fifo);
    let run_out = dir.path().join("out");
    let run_out = run_out.to_str().unwrap();
    for args in [
        vec!["run", fifo.to_str().unwrap(), "--out", run_out, "--quiet"],
        vec!["run", "/dev/zero", "--out", run_out, "--quiet"],
        vec![
            "train",
            "--data",
            fifo.to_str().unwrap(),
            "--urdf",
            "models/franka_panda.urdf",
            "--out",
            dir.path().join("net.bin").to_str().unwrap(),
        ],
    ] {
        let o = admittance_within(&args, 60).unwrap_or_else(|| panic!("{args:?} hung"));
        assert!(!o.status.success(), "{args:?}: {}", text(&o));
        let t = text(&o);
        assert!(t.contains("not a regular file"), "{args:?}: {t}");
    }
}

#[test]
fn report_never_writes_through_a_planted_link() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let o = admittance_within(
        &[
            "run",
            "scenarios/deadzone.toml",
            "--set",
            "duration=3",
            "--set",
            "evaluation_start=1",
            "--out",
            run.to_str().unwrap(),
            "--quiet",
        ],
        300,
    )
    .expect("run finishes");
    assert!(o.status.success(), "{}", text(&o));
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "another user's file").unwrap();
    for name in ["report.md", "report.html", "recording.mcap", "figures"] {
        plant_predictable_links(&run, name, &victim);
    }
    let args = ["report", run.to_str().unwrap(), "--quiet"];
    let o = admittance_within(&args, 300).expect("report finishes");
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(&victim).unwrap(),
        "another user's file"
    );
    // A link at a destination: refused, its target untouched.
    std::fs::remove_file(run.join("report.md")).unwrap();
    symlink(&victim, run.join("report.md")).unwrap();
    let o = admittance_within(&args, 300).expect("report finishes");
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("symbolic link"), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(&victim).unwrap(),
        "another user's file"
    );
}

#[test]
fn a_fifo_as_the_identification_of_evaluate_or_train_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("arm.ident.json");
    mkfifo(&fifo);
    let data = dir.path().join("data.csv");
    let o = admittance_within(
        &[
            "excite",
            "--urdf",
            "models/baxter_left_arm.urdf",
            "--duration",
            "4",
            "--iterations",
            "20",
            "--out",
            data.to_str().unwrap(),
        ],
        120,
    )
    .expect("excite finishes");
    assert!(o.status.success(), "{}", text(&o));
    let (fifo, data) = (fifo.to_str().unwrap(), data.to_str().unwrap());
    let net = dir.path().join("net.broad");
    let urdf = "models/baxter_left_arm.urdf";
    for args in [
        vec![
            "evaluate",
            "--data",
            data,
            "--urdf",
            urdf,
            "--identification",
            fifo,
        ],
        vec![
            "train",
            "--data",
            data,
            "--urdf",
            urdf,
            "--nominal",
            fifo,
            "--out",
            net.to_str().unwrap(),
        ],
    ] {
        let o = admittance_within(&args, 60).unwrap_or_else(|| panic!("{args:?} hung"));
        assert!(!o.status.success(), "{args:?}: {}", text(&o));
        let t = text(&o);
        assert!(
            t.contains("FIFO") && t.contains("arm.ident.json"),
            "{args:?}: {t}"
        );
    }
}
