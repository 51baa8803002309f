//! What a robot's disk may hold (issue 34): chunks with wrong declared sizes or flipped
//! bits, absurd rates and clock jumps, names and values a CSV cannot carry, special files,
//! and (issue 32) a recording without the optional label or at too low a rate. Each gives a
//! clear error or a counted skip, never a hang or an abort. The damaged bags are made here
//! from the shipped ones.

mod common;

use std::path::{Path, PathBuf};

use admittance_bag::{import, import_to_csv, msgs, BagError, ImportOptions, Profile};
use common::*;

const MS: i64 = 1_000_000;

fn franka() -> Profile {
    Profile::builtin("franka").unwrap().unwrap()
}

fn opts(accept_damage: bool) -> ImportOptions {
    ImportOptions {
        accept_damage,
        ..Default::default()
    }
}

fn shipped_zstd() -> PathBuf {
    data("franka_zstd/franka_zstd.mcap")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn set_size(bytes: &mut [u8], chunk: usize, f: impl Fn(u64) -> u64) {
    let at = uncompressed_size_field(chunk);
    let v = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    bytes[at..at + 8].copy_from_slice(&f(v).to_le_bytes());
}

#[test]
fn a_wrong_uncompressed_size_is_an_error_naming_chunk_and_offset() {
    // The report of issue 34: +1 on the first chunk's size hung the import for ever.
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(shipped_zstd()).unwrap();
    let chunk = chunk_offsets(&bytes)[0];
    type Edit = Box<dyn Fn(u64) -> u64>;
    let mut cases: Vec<(String, Edit)> = vec![
        ("+1".into(), Box::new(|v| v + 1)),
        ("-1".into(), Box::new(|v| v - 1)),
        ("0".into(), Box::new(|_| 0)),
        ("max".into(), Box::new(|_| u64::MAX)),
    ];
    for bit in 0..64 {
        cases.push((format!("bit {bit}"), Box::new(move |v| v ^ (1 << bit))));
    }
    for (what, f) in cases {
        let mut b = bytes.clone();
        set_size(&mut b, chunk, f);
        let path = write(dir.path(), "size.mcap", &b);
        let e = import(&path, &franka(), &opts(false)).unwrap_err();
        assert!(matches!(e, BagError::Damaged { .. }), "{what}: {e}");
        let text = e.to_string();
        assert!(
            text.contains("size.mcap")
                && text.contains(&format!("at byte {chunk}"))
                && text.contains("chunk 1"),
            "{what}: {text}"
        );
        // Accepted, the only chunk is skipped: nothing is left, which is an error too.
        let e = import(&path, &franka(), &opts(true))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("too little is left after skipping the damage") && e.contains("chunk 1"),
            "{what}: {e}"
        );
    }
}

/// The shipped franka bag rewritten in zstd chunks of ~16 kB with CRCs.
fn chunked(dir: &Path) -> (PathBuf, Vec<u8>, Vec<usize>) {
    let path = dir.join("chunked.mcap");
    rewrite_zstd(&shipped_zstd(), &path, 16 << 10, |_| true);
    let bytes = std::fs::read(&path).unwrap();
    let chunks = chunk_offsets(&bytes);
    assert!(chunks.len() >= 4, "{} chunks", chunks.len());
    (path, bytes, chunks)
}

#[test]
fn a_damaged_chunk_is_skipped_and_counted_with_accept_damaged() {
    let dir = tempfile::tempdir().unwrap();
    let (clean_path, bytes, chunks) = chunked(dir.path());
    let clean = import(&clean_path, &franka(), &opts(false)).unwrap();
    assert_eq!(clean.report.skipped_chunks, 0);
    let second = chunks[1];
    let mut b = bytes.clone();
    set_size(&mut b, second, |v| v + 1);
    let path = write(dir.path(), "second.mcap", &b);
    let e = import(&path, &franka(), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("at byte {second}: chunk 2")) && e.contains("second.mcap"),
        "{e}"
    );
    let im = import(&path, &franka(), &opts(true)).unwrap();
    assert_eq!(im.report.skipped_chunks, 1, "{}", im.report);
    assert_eq!(im.report.damage.len(), 1);
    let text = im.report.to_string();
    assert!(
        text.contains("damaged chunks skipped: 1") && text.contains("chunk 2"),
        "{text}"
    );
    // The chunk's messages are lost (a gap), the rest read.
    let lost = clean.report.topics[0].messages - im.report.topics[0].messages;
    assert!(
        lost > 0 && lost < clean.report.topics[0].messages / 2,
        "{lost}"
    );
}

#[test]
fn every_flipped_bit_of_a_compressed_chunk_is_caught() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes, chunks) = chunked(dir.path());
    let start = chunks[1];
    let len = u64::from_le_bytes(bytes[start + 1..start + 9].try_into().unwrap()) as usize;
    let end = start + 9 + len;
    let path = dir.path().join("flip.mcap");
    // Every 53rd byte of the second chunk record (opcode, lengths, sizes, frame, compressed
    // data), each bit.
    for at in (start..end).step_by(53) {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[at] ^= 1 << bit;
            std::fs::write(&path, &b).unwrap();
            // A flip in the chunk's start/end times (not used) may leave a readable bag,
            // or give another clear error: never a hang or a panic.
            if let Err(BagError::Damaged { message, .. }) = import(&path, &franka(), &opts(false)) {
                assert!(message.contains("at byte"), "{at}/{bit}: {message}")
            }
            let _ = import(&path, &franka(), &opts(true));
        }
    }
    // Flips inside the compressed records are always damage (the CRC or zstd).
    let records = start + 9 + 8 + 8 + 8 + 4 + 4 + 4 + 8;
    for at in (records + 10..end).step_by(97) {
        let mut b = bytes.clone();
        b[at] ^= 0x08;
        std::fs::write(&path, &b).unwrap();
        let e = import(&path, &franka(), &opts(false)).unwrap_err();
        assert!(matches!(e, BagError::Damaged { .. }), "{at}: {e}");
        let im = import(&path, &franka(), &opts(true)).unwrap();
        assert_eq!(im.report.skipped_chunks, 1, "{at}");
    }
}

#[test]
fn huge_lengths_are_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes, chunks) = chunked(dir.path());
    // A record length beyond the file: reading stops there (strict: an error).
    let mut b = bytes.clone();
    b[chunks[2] + 1..chunks[2] + 9].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let path = write(dir.path(), "len.mcap", &b);
    let e = import(&path, &franka(), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(e.contains("chunk 3") && e.contains("the file has"), "{e}");
    let im = import(&path, &franka(), &opts(true)).unwrap();
    assert!(
        im.report.to_string().contains("reading stopped"),
        "{}",
        im.report
    );
    // A declared size above the limit (256 MiB) is damage, not an allocation.
    let mut b = bytes.clone();
    set_size(&mut b, chunks[1], |_| 300 << 20);
    let path = write(dir.path(), "big.mcap", &b);
    let e = import(&path, &franka(), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(e.contains("above the reader's limit"), "{e}");
}

/// A bag of `stamps.len()` JointStates of `/js` (3 joints) at the given stamps.
fn js_bag(dir: &Path, stamps: &[i64], edit: impl Fn(usize, &mut msgs::JointState)) -> PathBuf {
    let path = dir.join("js.mcap");
    let messages: Vec<Out> = stamps
        .iter()
        .enumerate()
        .map(|(k, &stamp)| {
            let mut js = joint_state(3, stamp, secs(stamp));
            edit(k, &mut js);
            js_message("/js", (stamp + MS / 5) as u64, &js)
        })
        .collect();
    write_mcap(&path, &messages);
    path
}

fn every_ms(n: usize) -> Vec<i64> {
    (0..n).map(|k| T0_NS + k as i64 * MS).collect()
}

#[test]
fn the_memory_budget_is_checked_before_resampling() {
    let o = ImportOptions {
        rate_hz: Some(5e7),
        ..Default::default()
    };
    let e = import(&data("franka_zstd"), &franka(), &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("memory budget") && e.contains("lower --rate"),
        "{e}"
    );
    // A last stamp a day late, no flag: the span, not the rate, is the problem.
    let dir = tempfile::tempdir().unwrap();
    let mut stamps = every_ms(50);
    *stamps.last_mut().unwrap() += 86_400 * 1_000_000_000;
    let bag = js_bag(dir.path(), &stamps, |_, _| {});
    let e = import(&bag, &js_profile(true), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("memory budget") && e.contains("clock jump"),
        "{e}"
    );
}

#[test]
fn csv_refuses_duplicate_and_malformed_names_and_overflowing_values() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let dup = js_bag(dir.path(), &every_ms(20), |_, js| js.name[1] = "j0".into());
    let e = import(&dup, &js_profile(true), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(e.contains("joint `j0` appears twice"), "{e}");
    for bad in ["j,1", "j\n1", "j\"1", "j\u{0}1", "j\t1"] {
        let bag = js_bag(dir.path(), &every_ms(20), |_, js| js.name[1] = bad.into());
        // The table itself is fine (Python takes it); the CSV is refused.
        assert!(import(&bag, &js_profile(true), &opts(false)).is_ok());
        let e = import_to_csv(&bag, &js_profile(true), &opts(false), &out)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("{bad:?}")) && e.contains("CSV column"),
            "{e}"
        );
        assert!(!out.exists());
    }
    // Velocities near 1e306 alternating in sign: their difference overflows.
    let bag = js_bag(dir.path(), &every_ms(20), |k, js| {
        js.velocity[2] = if k % 2 == 0 { 1e306 } else { -1e306 };
    });
    let e = import_to_csv(&bag, &js_profile(true), &opts(false), &out)
        .unwrap_err()
        .to_string();
    assert!(e.contains("column qddot.j2 is") && e.contains("inf"), "{e}");
    assert!(!out.exists());
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("bag.mcap");
    let ok = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(ok.success());
    // Opening the FIFO for reading would block this test for ever.
    let e = import(&fifo, &franka(), &opts(true))
        .unwrap_err()
        .to_string();
    assert!(e.contains("bag.mcap") && e.contains("FIFO"), "{e}");
    let e = import(dir.path(), &franka(), &opts(true))
        .unwrap_err()
        .to_string();
    assert!(e.contains("FIFO"), "{e}");
    let e = import(Path::new("/dev/zero"), &franka(), &opts(true))
        .unwrap_err()
        .to_string();
    assert!(e.contains("/dev/zero") && e.contains("a device"), "{e}");
    let e = Profile::resolve(fifo.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("FIFO"), "{e}");
}

#[test]
fn a_missing_label_topic_is_a_note_and_the_csv_has_no_label_columns() {
    let dir = tempfile::tempdir().unwrap();
    let only = dir.path().join("only_joint_states.mcap");
    rewrite_zstd(&shipped_zstd(), &only, 1 << 20, |t| {
        t.ends_with("measured_joint_states")
    });
    let im = import(&only, &franka(), &opts(false)).unwrap();
    assert!(im.table.label.is_none());
    // The span is the joint states' own now (the label no longer narrows it).
    assert_eq!(im.table.len(), 999);
    let text = im.report.to_string();
    assert!(
        text.contains("note: label topic `/franka_robot_state_broadcaster/external_joint_torques` is not in the bag"),
        "{text}"
    );
    let out = dir.path().join("only.csv");
    import_to_csv(&only, &franka(), &opts(false), &out).unwrap();
    let header = std::fs::read_to_string(&out).unwrap();
    let header = header.lines().next().unwrap();
    assert!(
        !header.contains("label.") && header.contains("tau.fr3_joint7"),
        "{header}"
    );
    // With the label recorded, both.
    let both = import(&data("franka_zstd"), &franka(), &opts(false)).unwrap();
    assert_eq!(both.table.label.as_ref().unwrap().0.len(), 7);
    assert!(both.report.notes.is_empty(), "{:?}", both.report.notes);
    // Any other topic missing stays an error.
    let tau_only = dir.path().join("torques_only.mcap");
    rewrite_zstd(&shipped_zstd(), &tau_only, 1 << 20, |t| {
        t.ends_with("external_joint_torques")
    });
    let e = import(&tau_only, &franka(), &opts(false)).unwrap_err();
    assert!(
        matches!(&e, BagError::MissingTopic { signal, .. } if signal == "q"),
        "{e}"
    );
}

#[test]
fn a_recording_under_200_hz_is_refused_or_imported_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let stamps: Vec<i64> = (0..40).map(|k| T0_NS + k * 20 * MS).collect(); // 50 Hz
    let bag = js_bag(dir.path(), &stamps, |_, _| {});
    let e = import(&bag, &js_profile(true), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("median rate of 50.000 Hz")
            && e.contains("200 Hz")
            && e.contains("--accept-low-rate"),
        "{e}"
    );
    let o = ImportOptions {
        accept_low_rate: true,
        ..Default::default()
    };
    let im = import(&bag, &js_profile(true), &o).unwrap();
    assert!(
        im.report.notes.iter().any(|n| n.starts_with("WARNING")),
        "{:?}",
        im.report.notes
    );
    // An output rate under 200 Hz from a 1 kHz recording is refused the same way.
    let o = ImportOptions {
        rate_hz: Some(100.0),
        ..Default::default()
    };
    let e = import(&data("franka_zstd"), &franka(), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--rate 100.000 Hz"), "{e}");
}
