//! `admittance import` end to end on the test bags of crates/bag/tests/data: the CSV it
//! writes is read by the free-motion reader and trains; bad bags, refused outputs and bad
//! arguments give their exit codes and one clear line.

use std::path::{Path, PathBuf};
use std::process::Command;

use admittance_scenario::FreeMotionData;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bag(name: &str) -> String {
    root()
        .join("crates/bag/tests/data")
        .join(name)
        .display()
        .to_string()
}

fn admittance(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admittance"))
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

#[test]
fn import_then_read_and_train() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("franka.csv");
    let (code, out, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 0, "{err}");
    for part in [
        "profile: franka",
        "/franka_robot_state_broadcaster/measured_joint_states (sensor_msgs/msg/JointState): 1000 messages",
        "skipped messages: 0",
        "rate: 1000.000000 Hz",
        "rows: 995",
        "wrote ",
    ] {
        assert!(out.contains(part), "{part} not in\n{out}");
    }
    let data = FreeMotionData::load(&csv).unwrap();
    assert_eq!(data.dof(), 7);
    assert_eq!(data.len(), 995);
    assert_eq!(data.joints[0], "fr3_joint1");
    // The same data under the Panda URDF's joint names trains.
    let panda = dir.path().join("panda.csv");
    let text = std::fs::read_to_string(&csv)
        .unwrap()
        .replace("fr3_joint", "panda_joint");
    std::fs::write(&panda, text).unwrap();
    let model = dir.path().join("m.broad");
    let (code, out, err) = admittance(&[
        "train",
        "--data",
        s(&panda),
        "--urdf",
        "models/franka_panda.urdf",
        "--nodes",
        "20",
        "--out",
        s(&model),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("validation nrmse"), "{out}");
    // A second import over its own CSV is allowed, with a rate.
    let (code, out, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
        "--rate",
        "250",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("rate: 250.000000 Hz (--rate)"), "{out}");
}

#[test]
fn exit_codes_and_messages() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("x.csv");
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_sqlite"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("rosbags-convert --src BAG --dst OUT --dst-storage mcap"),
        "{err}"
    );
    let (code, _, err) = admittance(&[
        "import",
        &bag("ur_plain"),
        "--profile",
        "ur",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("torque_constant"), "{err}");
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "kuka",
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("franka, ur, lbr"), "{err}");
    let user = dir.path().join("mine.csv");
    std::fs::write(&user, "precious\n").unwrap();
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&user),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("refusing to replace"), "{err}");
    assert_eq!(std::fs::read_to_string(&user).unwrap(), "precious\n");
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
        "--rate",
        "-3",
    ]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!csv.exists());
}

/// The shipped zstd bag with its first chunk's `uncompressed_size` plus one (issue 34: it
/// hung the import for ever).
fn bag_with_wrong_chunk_size(dir: &Path) -> PathBuf {
    let mut bytes =
        std::fs::read(root().join("crates/bag/tests/data/franka_zstd/franka_zstd.mcap")).unwrap();
    let mut at = 8;
    while bytes[at] != 0x06 {
        at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
    }
    let field = at + 9 + 16;
    let size = u64::from_le_bytes(bytes[field..field + 8].try_into().unwrap());
    bytes[field..field + 8].copy_from_slice(&(size + 1).to_le_bytes());
    let path = dir.join("wrong_size.mcap");
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The shipped bag's messages on `keep` topics, rewritten (the `mcap` crate's writer).
fn filtered_bag(dir: &Path, name: &str, keep: impl Fn(&str) -> bool) -> PathBuf {
    use std::collections::BTreeMap;
    let bytes =
        std::fs::read(root().join("crates/bag/tests/data/franka_zstd/franka_zstd.mcap")).unwrap();
    let path = dir.join(name);
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut w = mcap::Writer::new(file).unwrap();
    let mut ids: BTreeMap<String, u16> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if !keep(&m.channel.topic) {
            continue;
        }
        let id = match ids.get(&m.channel.topic) {
            Some(id) => *id,
            None => {
                let s = m.channel.schema.as_ref().unwrap();
                let sid = w.add_schema(&s.name, &s.encoding, &s.data).unwrap();
                let id = w
                    .add_channel(sid, &m.channel.topic, "cdr", &BTreeMap::new())
                    .unwrap();
                ids.insert(m.channel.topic.clone(), id);
                id
            }
        };
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: m.sequence,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        w.write_to_known_channel(&header, &m.data).unwrap();
    }
    w.finish().unwrap();
    path
}

#[test]
fn damaged_chunks_budgets_and_special_files_exit_3_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("x.csv");
    let wrong = bag_with_wrong_chunk_size(dir.path());
    for accept in [false, true] {
        let mut args = vec!["import", s(&wrong), "--profile", "franka", "--out", s(&csv)];
        if accept {
            args.push("--accept-damaged");
        }
        let (code, _, err) = admittance(&args);
        assert_eq!(code, 3, "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("wrong_size.mcap") && err.contains("chunk 1"),
            "{err}"
        );
        assert!(err.contains("at byte 43"), "{err}");
    }
    let (code, _, err) = admittance(&[
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
        "--rate",
        "5e7",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("memory budget") && err.contains("--rate"),
        "{err}"
    );
    #[cfg(unix)]
    {
        let fifo = dir.path().join("pipe.mcap");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        let (code, _, err) =
            admittance(&["import", s(&fifo), "--profile", "franka", "--out", s(&csv)]);
        assert_eq!(code, 3, "{err}");
        assert!(err.contains("FIFO"), "{err}");
    }
    assert!(!csv.exists());
}

#[test]
fn joint_states_without_the_label_import_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let only = filtered_bag(dir.path(), "only_q.mcap", |t| {
        t.ends_with("measured_joint_states")
    });
    let csv = dir.path().join("only.csv");
    let (code, out, err) =
        admittance(&["import", s(&only), "--profile", "franka", "--out", s(&csv)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("note: label topic `/franka_robot_state_broadcaster/external_joint_torques` is not in the bag"), "{out}");
    let data = FreeMotionData::load(&csv).unwrap();
    assert_eq!(data.dof(), 7);
    let header = std::fs::read_to_string(&csv).unwrap();
    assert!(!header.lines().next().unwrap().contains("label."));
    // The label without the joint states: q is missing, an error.
    let label = filtered_bag(dir.path(), "label.mcap", |t| {
        t.ends_with("external_joint_torques")
    });
    let (code, _, err) =
        admittance(&["import", s(&label), "--profile", "franka", "--out", s(&csv)]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("(for q) is not in the bag"), "{err}");
}

#[test]
fn a_low_output_rate_is_refused_unless_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("low.csv");
    let args = [
        "import",
        &bag("franka_zstd"),
        "--profile",
        "franka",
        "--out",
        s(&csv),
        "--rate",
        "50",
    ];
    let (code, _, err) = admittance(&args);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("200 Hz") && err.contains("--accept-low-rate"),
        "{err}"
    );
    let mut accepted = args.to_vec();
    accepted.push("--accept-low-rate");
    let (code, _, err) = admittance(&accepted);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("WARNING") && err.contains("--rate 50.000 Hz"),
        "{err}"
    );
}
