//! `admittance calibrate-contact` and `admittance evaluate --contact-floor` (issue 31): a
//! floor from free motion the identification did not fit, its false alarms on other free
//! motion, and the refusal to overwrite a file that is not a floor.

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

/// Free motion of the Baxter model (multi-sine, 200 Hz) with viscous friction and white
/// torque noise of 0.3 N m (what no identification fits), as a CSV.
fn free_motion_csv(dir: &Path, seed: f64, seconds: f64) -> PathBuf {
    let names = crate::free_motion::names(&crate::free_motion::baxter());
    let mut state = (seed * 1e6) as u64 | 1;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    crate::free_motion::multisine_csv(
        dir.join(format!("free_{seed}.csv")),
        seed,
        seconds,
        &names,
        |_, i, qd| {
            // Irwin-Hall: the sum of 12 uniforms less 6 is close to a unit normal.
            let noise = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
            1.5 * qd[i] + 0.3 * noise
        },
    )
}

/// The Baxter model identified on 30 s of free motion (`admittance identify`), in `dir`.
fn identified(dir: &Path) -> PathBuf {
    let urdf = root().join("models/baxter_left_arm.urdf");
    let train = free_motion_csv(dir, 0.3, 30.0);
    let ident = dir.join("baxter.ident.json");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let o = admittance(&[
        "identify",
        "--data",
        &s(&train),
        "--urdf",
        &s(&urdf),
        "--out",
        &s(&ident),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    ident
}

/// `admittance calibrate-contact` on `recordings` with the identification `ident`, to `out`.
fn calibrate(recordings: &[&Path], ident: &Path, out: &Path) -> Output {
    let mut args = vec!["calibrate-contact"];
    args.extend(recordings.iter().map(|p| p.to_str().unwrap()));
    args.extend([
        "--identification",
        ident.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    admittance(&args)
}

/// `admittance evaluate` of `data` (the Baxter arm) with the identification `ident` and the
/// contact floor `floor`.
fn evaluate_with_floor(data: &Path, ident: &Path, floor: &Path) -> Output {
    let urdf = root().join("models/baxter_left_arm.urdf");
    admittance(&[
        "evaluate",
        "--data",
        data.to_str().unwrap(),
        "--urdf",
        urdf.to_str().unwrap(),
        "--identification",
        ident.to_str().unwrap(),
        "--contact-floor",
        floor.to_str().unwrap(),
    ])
}

#[test]
fn a_floor_from_held_out_motion_is_quiet_on_other_motion() {
    let dir = tempfile::tempdir().unwrap();
    let ident = identified(dir.path());
    let held_out = free_motion_csv(dir.path(), 1.9, 120.0);
    let other = free_motion_csv(dir.path(), 2.7, 120.0);
    let floor = dir.path().join("floor.json");
    let o = calibrate(&[&held_out], &ident, &floor);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("guarantee"), "{}", text(&o));
    let written = std::fs::read_to_string(&floor).unwrap();
    assert!(written.contains("\"format\": \"admittance-contact-floor\""));
    let o = evaluate_with_floor(&other, &ident, &floor);
    assert!(o.status.success(), "{}", text(&o));
    let table = text(&o);
    let events: usize = table
        .lines()
        .filter(|l| l.starts_with("contact "))
        .find_map(|l| l.split_whitespace().nth(1)?.parse().ok())
        .unwrap_or_else(|| panic!("no contact row in\n{table}"));
    // Promised 1 per hour: in 2 min of the same kind of motion, at most one.
    assert!(events <= 1, "{table}");
    // A file that is not a floor is not overwritten.
    let mine = dir.path().join("mine.json");
    std::fs::write(&mine, "{}").unwrap();
    let o = calibrate(&[&held_out], &ident, &mine);
    assert!(!o.status.success());
    assert!(text(&o).contains("not overwritten"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "{}");
}

/// `evaluate --contact-floor` says how many contact events start where the motion leaves the
/// identification's training range or speeds: on a task three times faster than the
/// training every event does, on the training recording none.
#[test]
fn false_alarms_are_attributed_to_motion_faster_than_trained() {
    let dir = tempfile::tempdir().unwrap();
    let ident = identified(dir.path());
    let held_out = free_motion_csv(dir.path(), 1.9, 60.0);
    let other = free_motion_csv(dir.path(), 2.7, 30.0);
    let faster = dir.path().join("faster.csv");
    crate::free_motion::played_faster(&other, &faster, 3.0);
    let floor = dir.path().join("floor.json");
    let o = calibrate(&[&held_out], &ident, &floor);
    assert!(o.status.success(), "{}", text(&o));
    let counts = |data: &Path| {
        let o = evaluate_with_floor(data, &ident, &floor);
        assert!(o.status.success(), "{}", text(&o));
        let table = text(&o);
        let line = table
            .lines()
            .find(|l| l.starts_with("contact events starting where"))
            .unwrap_or_else(|| panic!("no attribution in\n{table}"))
            .to_string();
        let words: Vec<&str> = line.split_whitespace().collect();
        let at = |w: &str| words.iter().position(|x| *x == w).unwrap();
        let there: usize = words[at("of") - 1].parse().unwrap();
        let events: usize = words[at("of") + 1].parse().unwrap();
        let share: f64 = words[at("(there:") + 1].parse().unwrap();
        (there, events, share, table)
    };
    // Three times as fast, the arm's dynamics no longer match its torques: the floor
    // flags, and more than half the samples lie beyond the training speeds (the velocity
    // crosses zero on the rest).
    let (there, events, share, table) = counts(&faster);
    assert!(events > 0, "{table}");
    assert_eq!(there, events, "{table}");
    assert!(share > 50.0, "{table}");
    // The recording the identification was fitted on lies within its range and speeds.
    let (there, _, share, table) = counts(&dir.path().join("free_0.3.csv"));
    assert_eq!((there, share), (0, 0.0), "{table}");
    let (there, events, _, table) = counts(&other);
    assert!(there <= events, "{table}");
}

/// Several recordings are pooled into one floor (each after its own warm-up); a recording
/// of another arm is refused, naming it.
#[test]
fn several_recordings_make_one_floor() {
    let dir = tempfile::tempdir().unwrap();
    let ident = identified(dir.path());
    let first = free_motion_csv(dir.path(), 1.9, 40.0);
    let second = free_motion_csv(dir.path(), 2.7, 40.0);
    let floor = dir.path().join("floor.json");
    let o = calibrate(&[&first, &second], &ident, &floor);
    assert!(o.status.success(), "{}", text(&o));
    let f = admittance_control::ContactFloor::load(&floor).unwrap();
    assert_eq!(f.source["recordings"], 2);
    assert_eq!(f.source["data"].as_array().map(Vec::len), Some(2));
    // Two recordings of 40 s, each less its first second.
    assert!(
        (f.calibration.duration_s - 78.0).abs() < 0.1,
        "{}",
        f.calibration.duration_s
    );

    // A recording whose joints are other than the arm's is refused, naming it.
    let other = dir.path().join("other.csv");
    let mine = std::fs::read_to_string(&second).unwrap();
    std::fs::write(&other, mine.replacen("left_s0", "right_s0", 1)).unwrap();
    let o = calibrate(&[&first, &other], &ident, &dir.path().join("refused.json"));
    assert!(!o.status.success());
    assert!(text(&o).contains("other.csv"), "{}", text(&o));
    assert!(!dir.path().join("refused.json").exists());
}
