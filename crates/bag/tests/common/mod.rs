//! Shared by the integration tests: the analytic truth of tests/make_bags.py, the test
//! bags' paths, and a small MCAP writer for bags the tests damage on purpose.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use admittance_bag::msgs::{self, Header, JointState, Time};

/// The stamp of the first message of every test bag (ns since the epoch).
pub const T0_NS: i64 = 1_700_000_000 * 1_000_000_000;

pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// (q, qdot, qddot, tau) of joint `i` at `s` seconds after T0 (make_bags.py's `truth`).
pub fn truth(i: usize, s: f64) -> (f64, f64, f64, f64) {
    let fi = i as f64;
    let (a, w, p, c) = (
        0.3 + 0.05 * fi,
        2.0 * PI * (0.5 + 0.1 * fi),
        0.2 * fi,
        0.1 * fi,
    );
    let q = a * (w * s + p).sin() + c;
    let qd = a * w * (w * s + p).cos();
    let qdd = -a * w * w * (w * s + p).sin();
    let tau = 5.0 * q.sin() + 0.5 * qd + 0.1 * (fi + 1.0) * qdd;
    (q, qd, qdd, tau)
}

/// The external joint torque label of joint `i`.
pub fn label(i: usize, s: f64) -> f64 {
    0.2 * (i as f64 + 1.0) * (2.0 * PI * s).sin()
}

/// The wrench label.
pub fn wrench(s: f64) -> [f64; 6] {
    let c = (2.0 * PI * s).cos();
    [c, 2.0 * c, 3.0 * c, 0.1 * c, 0.2 * c, 0.3 * c]
}

pub fn secs(stamp_ns: i64) -> f64 {
    (stamp_ns - T0_NS) as f64 / 1e9
}

/// Largest |a - b|.
pub fn max_err(a: impl IntoIterator<Item = f64>, b: impl IntoIterator<Item = f64>) -> f64 {
    a.into_iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// The JointState definition as rosbag2 embeds it (only the name matters to the reader).
pub const JOINT_STATE_DEF: &str = "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n";

/// A JointState of `n` joints `j0..`, stamped `stamp_ns` (0: a zero stamp), with values
/// from the truth at `s`.
pub fn joint_state(n: usize, stamp_ns: i64, s: f64) -> JointState {
    let rows: Vec<_> = (0..n).map(|i| truth(i, s)).collect();
    JointState {
        header: Header {
            stamp: Time {
                sec: (stamp_ns / 1_000_000_000) as i32,
                nanosec: (stamp_ns % 1_000_000_000) as u32,
            },
            frame_id: String::new(),
        },
        name: (0..n).map(|i| format!("j{i}")).collect(),
        position: rows.iter().map(|r| r.0).collect(),
        velocity: rows.iter().map(|r| r.1).collect(),
        effort: rows.iter().map(|r| r.3).collect(),
    }
}

/// One message to write: topic, type, log time, payload.
pub struct Out {
    pub topic: String,
    pub type_name: String,
    pub log_ns: u64,
    pub data: Vec<u8>,
}

pub fn js_message(topic: &str, log_ns: u64, js: &JointState) -> Out {
    Out {
        topic: topic.into(),
        type_name: "sensor_msgs/msg/JointState".into(),
        log_ns,
        data: msgs::encode(js).unwrap(),
    }
}

/// Writes an MCAP file (uncompressed chunks) with the messages in the given order.
pub fn write_mcap(path: &Path, messages: &[Out]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let options = mcap::WriteOptions::new().compression(None).profile("ros2");
    let mut w = mcap::Writer::with_options(file, options).unwrap();
    let mut channels: BTreeMap<String, u16> = BTreeMap::new();
    for (seq, m) in messages.iter().enumerate() {
        let id = match channels.get(&m.topic) {
            Some(id) => *id,
            None => {
                let schema = w
                    .add_schema(&m.type_name, "ros2msg", JOINT_STATE_DEF.as_bytes())
                    .unwrap();
                let id = w
                    .add_channel(schema, &m.topic, "cdr", &BTreeMap::new())
                    .unwrap();
                channels.insert(m.topic.clone(), id);
                id
            }
        };
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: seq as u32,
            log_time: m.log_ns,
            publish_time: m.log_ns,
        };
        w.write_to_known_channel(&header, &m.data).unwrap();
    }
    w.finish().unwrap();
}

/// A profile reading `/js` (JointState) for q, qdot, tau, joints from the messages.
pub fn js_profile(with_qdot: bool) -> admittance_bag::Profile {
    let qdot = if with_qdot {
        "[qdot]\ntopic = \"/js\"\ntype = \"sensor_msgs/msg/JointState\"\nfield = \"velocity\"\n"
    } else {
        ""
    };
    let text = format!(
        "name = \"test\"\ndescription = \"test\"\n[q]\ntopic = \"/js\"\ntype = \"sensor_msgs/msg/JointState\"\nfield = \"position\"\n{qdot}[tau]\ntopic = \"/js\"\ntype = \"sensor_msgs/msg/JointState\"\nfield = \"effort\"\n"
    );
    admittance_bag::Profile::parse(&text, "test.toml").unwrap()
}

/// A message read back: topic, type, schema text, log time, payload.
pub type ReadMessage = (String, String, Vec<u8>, u64, Vec<u8>);

/// The messages of an MCAP file (read with the `mcap` crate).
pub fn messages_of(path: &Path) -> Vec<ReadMessage> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            (
                m.channel.topic.clone(),
                schema.name.clone(),
                schema.data.to_vec(),
                m.log_time,
                m.data.to_vec(),
            )
        })
        .collect()
}

/// Rewrites the messages of `src` for which `keep(topic)` holds into `dst`, in zstd chunks
/// of about `chunk_size` bytes with chunk CRCs (the `mcap` crate's writer).
pub fn rewrite_zstd(src: &Path, dst: &Path, chunk_size: u64, keep: impl Fn(&str) -> bool) {
    let file = std::io::BufWriter::new(std::fs::File::create(dst).unwrap());
    let options = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .chunk_size(Some(chunk_size))
        .profile("ros2");
    let mut w = mcap::Writer::with_options(file, options).unwrap();
    let mut channels: BTreeMap<String, u16> = BTreeMap::new();
    for (seq, (topic, type_name, schema, log, data)) in messages_of(src).into_iter().enumerate() {
        if !keep(&topic) {
            continue;
        }
        let id = match channels.get(&topic) {
            Some(id) => *id,
            None => {
                let s = w.add_schema(&type_name, "ros2msg", &schema).unwrap();
                let id = w.add_channel(s, &topic, "cdr", &BTreeMap::new()).unwrap();
                channels.insert(topic.clone(), id);
                id
            }
        };
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: seq as u32,
            log_time: log,
            publish_time: log,
        };
        w.write_to_known_channel(&header, &data).unwrap();
    }
    w.finish().unwrap();
}

/// Byte offsets of the Chunk records (opcode 0x06) of an MCAP file's data section.
pub fn chunk_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut at = 8;
    let mut out = Vec::new();
    while at + 9 <= bytes.len() {
        let op = bytes[at];
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if op == 0x0f {
            break;
        }
        if op == 0x06 {
            out.push(at);
        }
        at += 9 + len;
    }
    out
}

/// The offset of a chunk's `uncompressed_size` field (after opcode, length, start and end
/// times).
pub fn uncompressed_size_field(chunk: usize) -> usize {
    chunk + 9 + 16
}
