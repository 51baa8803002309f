//! Damaged and wrong input: a clear error naming bag, topic, field and time, or a counted
//! skip in the report; never a panic.

mod common;

use std::path::Path;

use admittance_bag::{import, msgs, BagError, ImportOptions, Profile};
use common::*;

const MS: i64 = 1_000_000;

fn options(accept_damage: bool) -> ImportOptions {
    ImportOptions {
        rate_hz: None,
        accept_damage,
        ..Default::default()
    }
}

fn franka() -> Profile {
    Profile::builtin("franka").unwrap().unwrap()
}

/// A bag of `n` JointStates on `/js` at 1 kHz (3 joints), log time = stamp + 0.2 ms.
fn js_bag(
    dir: &Path,
    n: usize,
    edit: impl Fn(usize, &mut msgs::JointState, &mut Vec<u8>),
) -> std::path::PathBuf {
    let path = dir.join("js.mcap");
    let messages: Vec<Out> = (0..n)
        .map(|k| {
            let stamp = T0_NS + k as i64 * MS;
            let mut js = joint_state(3, stamp, secs(stamp));
            let mut bytes = Vec::new();
            edit(k, &mut js, &mut bytes);
            let mut out = js_message("/js", (stamp + MS / 5) as u64, &js);
            if !bytes.is_empty() {
                out.data = bytes;
            }
            out
        })
        .collect();
    write_mcap(&path, &messages);
    path
}

#[test]
fn truncated_bag_is_an_error_or_with_accept_damage_a_reported_loss() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(data("franka_plain.mcap")).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let e = import(&cut, &franka(), &options(false)).unwrap_err();
    assert!(matches!(e, BagError::Damaged { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("cut.mcap") && text.contains("--accept-damaged"),
        "{text}"
    );
    let im = import(&cut, &franka(), &options(true)).unwrap();
    assert_eq!(im.report.damage.len(), 1, "{:?}", im.report.damage);
    assert!(im.report.to_string().contains("DAMAGED (accepted)"));
    assert!(
        im.table.len() > 10 && im.table.len() < 99,
        "{}",
        im.table.len()
    );
}

#[test]
fn every_truncation_and_flipped_byte_gives_a_result_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.mcap");
    for name in ["franka_plain.mcap", "lbr_zstd/lbr_zstd.mcap"] {
        let bytes = std::fs::read(data(name)).unwrap();
        let profile = if name.starts_with("lbr") {
            Profile::builtin("lbr").unwrap().unwrap()
        } else {
            franka()
        };
        let step = bytes.len() / 60;
        for k in 0..60 {
            let at = k * step + k % 7;
            std::fs::write(&path, &bytes[..at]).unwrap();
            let _ = import(&path, &profile, &options(true));
            let mut flipped = bytes.clone();
            flipped[at] ^= 0x5a;
            std::fs::write(&path, &flipped).unwrap();
            let strict = import(&path, &profile, &options(false));
            let lenient = import(&path, &profile, &options(true));
            // Accepting damage never loses a bag that reads cleanly.
            if strict.is_ok() {
                assert!(lenient.is_ok(), "{name} flipped at {at}");
            }
        }
    }
}

#[test]
fn damaged_zstd_chunk_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    // rosbags writes no chunk CRC (0: not checked) and zstd frames without a checksum, so
    // flipped bytes inside compressed data may decode to other numbers (which the stamp
    // check or the decoding often catches); a damaged frame header fails decompression.
    let mut bytes = std::fs::read(data("lbr_zstd/lbr_zstd.mcap")).unwrap();
    let frame = bytes
        .windows(4)
        .position(|w| w == [0x28, 0xb5, 0x2f, 0xfd])
        .unwrap();
    bytes[frame + 1] ^= 0xff;
    let path = dir.path().join("lbr.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let e = import(
        &path,
        &Profile::builtin("lbr").unwrap().unwrap(),
        &options(false),
    )
    .unwrap_err();
    assert!(matches!(e, BagError::Damaged { .. }), "{e}");
    assert!(e.to_string().contains("lbr.mcap"), "{e}");
}

#[test]
fn wrong_type_names_topic_field_and_both_types() {
    let text = include_str!("../profiles/franka.toml")
        .replace("external_joint_torques", "external_wrench_in_base_frame");
    let profile = Profile::parse(&text, "wrong.toml").unwrap();
    let e = import(&data("franka_zstd"), &profile, &options(false))
        .unwrap_err()
        .to_string();
    for part in [
        "franka_zstd",
        "/franka_robot_state_broadcaster/external_wrench_in_base_frame",
        "`effort`",
        "label",
        "geometry_msgs/msg/WrenchStamped",
        "sensor_msgs/msg/JointState",
    ] {
        assert!(e.contains(part), "{part} not in {e}");
    }
}

#[test]
fn missing_topic_lists_the_bag_topics() {
    let text = include_str!("../profiles/franka.toml").replace(
        "/franka_robot_state_broadcaster/measured_joint_states",
        "/joint_states",
    );
    let profile = Profile::parse(&text, "missing.toml").unwrap();
    let e = import(&data("franka_zstd"), &profile, &options(false)).unwrap_err();
    assert!(matches!(e, BagError::MissingTopic { .. }), "{e}");
    let e = e.to_string();
    assert!(
        e.contains("`/joint_states` (for q)")
            && e.contains("external_joint_torques (sensor_msgs/msg/JointState)"),
        "{e}"
    );
}

#[test]
fn non_monotonic_stamps_are_an_error_with_the_times() {
    let dir = tempfile::tempdir().unwrap();
    let bag = js_bag(dir.path(), 20, |k, js, _| {
        if k == 7 {
            js.header.stamp.nanosec -= 3_000_000; // 4 ms instead of 7 ms
        }
    });
    let e = import(&bag, &js_profile(true), &options(false)).unwrap_err();
    assert!(
        matches!(e, BagError::NonMonotonic { index: 7, time_ns, previous_ns, .. }
        if time_ns == T0_NS + 4 * MS && previous_ns == T0_NS + 6 * MS),
        "{e}"
    );
    let e = e.to_string();
    assert!(
        e.contains("js.mcap")
            && e.contains("`/js`")
            && e.contains("1700000000.004000000")
            && e.contains("1700000000.006000000"),
        "{e}"
    );
}

#[test]
fn zero_stamps_fall_back_to_the_log_time_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let bag = js_bag(dir.path(), 20, |k, js, _| {
        if k >= 10 {
            js.header.stamp = msgs::Time::default();
        }
    });
    let im = import(&bag, &js_profile(true), &options(false)).unwrap();
    let q = &im.report.signals[0];
    assert_eq!((q.time.stamped, q.time.log_time), (10, 10));
    assert!(
        im.report
            .to_string()
            .contains("10 of 20 messages had a zero stamp"),
        "{}",
        im.report
    );
}

#[test]
fn unusable_messages_are_skipped_and_counted_by_reason() {
    let dir = tempfile::tempdir().unwrap();
    let bag = js_bag(dir.path(), 30, |k, js, raw| match k {
        3 => *raw = vec![0, 1, 0, 0, 9, 9],           // undecodable
        5 => js.name[1] = "other".into(),             // joint j1 missing
        8 => js.effort[2] = f64::NAN,                 // non-finite
        11 => js.position.pop().map(|_| ()).unwrap(), // 2 positions for 3 names
        _ => {}
    });
    let im = import(&bag, &js_profile(true), &options(false)).unwrap();
    let reasons: Vec<(String, usize)> = im
        .report
        .skips
        .iter()
        .map(|s| (s.reason.clone(), s.count))
        .collect();
    // Message 5 lacks j1 for every signal of the topic, 11 only for q: counted per signal.
    assert_eq!(
        reasons,
        vec![
            ("joint missing".into(), 3),
            ("non-finite value".into(), 1),
            ("undecodable payload".into(), 1),
            ("wrong number of values".into(), 1),
        ]
    );
    assert_eq!(im.report.skipped(), 6);
    assert!(im.report.to_string().contains("skipped messages: 6"));
    // The interpolation bridges the skipped stamps; the rows are on the 1 ms grid.
    assert_eq!(im.report.rate_hz, 1000.0);
}

#[test]
fn a_field_empty_in_every_message_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let bag = js_bag(dir.path(), 10, |_, js, _| js.velocity.clear());
    let e = import(&bag, &js_profile(true), &options(false))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`/js` field `velocity` (for qdot)") && e.contains("10 skipped: empty field"),
        "{e}"
    );
    // Without [qdot] the velocity is the backward difference of q.
    let im = import(&bag, &js_profile(false), &options(false)).unwrap();
    assert_eq!(im.report.dropped_leading_rows, 2);
}

#[test]
fn not_a_bag_and_empty_folders_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("notes.txt");
    std::fs::write(&text, "hello").unwrap();
    let e = import(&text, &franka(), &options(false))
        .unwrap_err()
        .to_string();
    assert!(e.contains("notes.txt") && e.contains("MCAP magic"), "{e}");
    let e = import(dir.path(), &franka(), &options(false))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no .mcap file") && e.contains("notes.txt"),
        "{e}"
    );
    let e = import(&dir.path().join("absent"), &franka(), &options(false)).unwrap_err();
    assert!(matches!(e, BagError::Io { .. }), "{e}");
}

#[test]
fn a_bad_rate_and_too_short_a_bag_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bag = js_bag(dir.path(), 2, |_, _, _| {});
    let e = import(&bag, &js_profile(false), &options(false))
        .unwrap_err()
        .to_string();
    assert!(e.contains("too few for the derivatives"), "{e}");
    let o = ImportOptions {
        rate_hz: Some(-5.0),
        accept_damage: false,
        ..Default::default()
    };
    let e = import(&bag, &js_profile(true), &o).unwrap_err().to_string();
    assert!(e.contains("rate -5 Hz"), "{e}");
}

#[test]
fn every_signal_of_a_topic_is_type_checked() {
    let dir = tempfile::tempdir().unwrap();
    let bag = js_bag(dir.path(), 5, |_, _, _| {});
    let text = "name = \"mixed\"\ndescription = \"d\"\njoints = [\"j0\", \"j1\", \"j2\"]\n[q]\ntopic = \"/js\"\ntype = \"sensor_msgs/msg/JointState\"\nfield = \"position\"\n[tau]\ntopic = \"/js\"\ntype = \"std_msgs/msg/Float64MultiArray\"\nfield = \"data\"\n";
    let profile = Profile::parse(text, "mixed.toml").unwrap();
    let e = import(&bag, &profile, &options(false)).unwrap_err();
    assert!(
        matches!(&e, BagError::WrongType { signal, .. } if signal == "tau"),
        "{e}"
    );
}

#[test]
fn extreme_stamps_and_log_times_give_errors_or_tables_not_overflows() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("extreme.mcap");
    let cases: [&[(i64, u64)]; 3] = [
        // (header stamp ns, 0 = zero stamp; log time ns)
        &[(0, 0), (0, 1), (0, u64::MAX - 1), (0, u64::MAX)],
        &[
            (i32::MIN as i64 * 1_000_000_000, 5),
            (0, 6),
            (i32::MAX as i64 * 1_000_000_000, 7),
            (i32::MAX as i64 * 1_000_000_000 + 1, 8),
        ],
        &[(1, 0), (2, u64::MAX), (3, 0), (4, u64::MAX)],
    ];
    for case in cases {
        let messages: Vec<Out> = case
            .iter()
            .map(|(stamp, log)| {
                let mut js = joint_state(3, 0, 0.1);
                js.header.stamp = msgs::Time {
                    sec: stamp.div_euclid(1_000_000_000) as i32,
                    nanosec: stamp.rem_euclid(1_000_000_000) as u32,
                };
                js_message("/js", *log, &js)
            })
            .collect();
        write_mcap(&path, &messages);
        for qdot in [true, false] {
            for rate in [None, Some(1e-9), Some(1e9)] {
                let o = ImportOptions {
                    rate_hz: rate,
                    accept_damage: false,
                    ..Default::default()
                };
                let _ = import(&path, &js_profile(qdot), &o);
            }
        }
    }
}

#[test]
fn lz4_chunks_are_refused_with_the_conversion() {
    let e = import(&data("franka_lz4.mcap"), &franka(), &options(true)).unwrap_err();
    assert!(matches!(e, BagError::Unsupported { .. }), "{e}");
    let e = e.to_string();
    assert!(
        e.contains("franka_lz4.mcap") && e.contains("`lz4`") && e.contains("rosbags-convert"),
        "{e}"
    );
}

#[test]
fn chunk_crcs_catch_flipped_bytes_in_compressed_data() {
    // franka_crc_zstd.mcap (written by the mcap package) stores chunk CRCs.
    let im = import(&data("franka_crc_zstd.mcap"), &franka(), &options(false)).unwrap();
    assert!(im.table.len() > 90);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crc.mcap");
    let bytes = std::fs::read(data("franka_crc_zstd.mcap")).unwrap();
    let frame = bytes
        .windows(4)
        .position(|w| w == [0x28, 0xb5, 0x2f, 0xfd])
        .unwrap();
    for offset in [40, 400, 4000] {
        let mut flipped = bytes.clone();
        flipped[frame + offset] ^= 0x10;
        std::fs::write(&path, &flipped).unwrap();
        let e = import(&path, &franka(), &options(false)).unwrap_err();
        assert!(
            matches!(e, BagError::Damaged { .. }),
            "offset {offset}: {e}"
        );
    }
}

#[test]
fn a_joint_read_within_one_turn_is_unwrapped_before_resampling() {
    // j0 turns at 2 rad/s from 3 rad, its driver reporting it in [-pi, pi); resampled at
    // 400 Hz (between the 1 kHz samples), an angle interpolated across a wrap would pass
    // through every value between.
    let dir = tempfile::tempdir().unwrap();
    let wrap = |a: f64| {
        a - std::f64::consts::TAU * ((a + std::f64::consts::PI) / std::f64::consts::TAU).floor()
    };
    let bag = js_bag(dir.path(), 400, |k, js, _| {
        js.position[0] = wrap(3.0 + 2.0 * k as f64 * 1e-3);
    });
    let options = ImportOptions {
        rate_hz: Some(400.0),
        ..options(false)
    };
    let im = import(&bag, &js_profile(true), &options).unwrap();
    let (n, table) = (im.table.joints.len(), &im.table);
    let rows = table.t.len();
    assert!(rows > 100, "{rows}");
    let mut largest_step: f64 = 0.0;
    for k in 1..rows {
        largest_step = largest_step.max((table.q[k * n] - table.q[(k - 1) * n]).abs());
    }
    // 2 rad/s over 2.5 ms: 5 mrad a row, never a turn nor a jump through the others.
    assert!(largest_step < 0.01, "{largest_step}");
    assert!(
        table.q[(rows - 1) * n] > std::f64::consts::PI,
        "past pi on one branch"
    );
    assert!(
        im.report.to_string().contains("q.j0 read within one turn"),
        "{}",
        im.report
    );
}
