//! What can go wrong while importing a bag: every error names the bag (or the profile or
//! output file), and where it applies the topic, the field and the time.

use std::path::PathBuf;

/// The command that converts a sqlite3 bag to MCAP (the `rosbags` Python package, no ROS
/// needed: `pip install rosbags`).
pub const CONVERT_COMMAND: &str = "rosbags-convert --src BAG --dst OUT --dst-storage mcap";

/// A failed import.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// A file or folder could not be read.
    #[error("{path}: {message}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        message: String,
    },
    /// A sqlite3 bag (`.db3`): only MCAP is read.
    #[error("{path}: a sqlite3 bag (.db3); only MCAP bags are read: convert it with `{CONVERT_COMMAND}` (pip install rosbags), or record with `ros2 bag record -s mcap`")]
    Sqlite {
        /// The bag.
        path: PathBuf,
    },
    /// Neither an MCAP file nor a folder holding one.
    #[error("{path}: not a rosbag2 MCAP bag: {reason}")]
    NotABag {
        /// The path given.
        path: PathBuf,
        /// What is there instead.
        reason: String,
    },
    /// The MCAP file uses a feature not read here (lz4 chunks).
    #[error("{path}: {message}")]
    Unsupported {
        /// The `.mcap` file.
        path: PathBuf,
        /// What and how to convert.
        message: String,
    },
    /// The MCAP container is damaged (truncated, a chunk whose CRC or compression fails).
    #[error("{path}: damaged MCAP data after {messages_read} messages (last log time {last_log_time}): {message}; {hint}")]
    Damaged {
        /// The `.mcap` file.
        path: PathBuf,
        /// Messages read before the damage.
        messages_read: usize,
        /// The log time (s since the epoch) of the last message read, or "none".
        last_log_time: String,
        /// The MCAP reader's error.
        message: String,
        /// What to do.
        hint: String,
    },
    /// The profile is not valid.
    #[error("profile {profile}: {message}")]
    Profile {
        /// The profile's name or file.
        profile: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// A topic the profile needs is not in the bag.
    #[error("{bag}: topic `{topic}` (for {signal}) is not in the bag; its topics: {present}")]
    MissingTopic {
        /// The bag.
        bag: PathBuf,
        /// The topic.
        topic: String,
        /// The signal that needs it (`q`, `qdot`, `tau`, `label`).
        signal: String,
        /// The topics of the bag, with their types.
        present: String,
    },
    /// A topic has another message type than the profile expects.
    #[error("{bag}: topic `{topic}` (field `{field}` for {signal}) has type `{found}`, the profile expects `{expected}`")]
    WrongType {
        /// The bag.
        bag: PathBuf,
        /// The topic.
        topic: String,
        /// The field.
        field: String,
        /// The signal.
        signal: String,
        /// The type the profile names.
        expected: String,
        /// The type in the bag.
        found: String,
    },
    /// A field or joint the profile names cannot be read from the messages of a topic.
    #[error("{bag}: topic `{topic}` field `{field}` (for {signal}): {message}")]
    Field {
        /// The bag.
        bag: PathBuf,
        /// The topic.
        topic: String,
        /// The field.
        field: String,
        /// The signal.
        signal: String,
        /// What is wrong.
        message: String,
    },
    /// The stamps of a topic do not increase strictly.
    #[error("{bag}: topic `{topic}`: sample {index} has stamp {} s, not after the previous sample's {} s (stamps must increase strictly; was the clock reset or are two publishers on the topic?)", fmt_ns(*time_ns), fmt_ns(*previous_ns))]
    NonMonotonic {
        /// The bag.
        bag: PathBuf,
        /// The topic.
        topic: String,
        /// 0-based index of the sample among the topic's usable messages.
        index: usize,
        /// Its stamp (ns since the epoch).
        time_ns: i64,
        /// The previous sample's stamp.
        previous_ns: i64,
    },
    /// The data cannot give a table (too few samples, no common time span, a bad rate).
    #[error("{bag}: {message}")]
    Data {
        /// The bag.
        bag: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Writing the output failed (disk full, permissions); the old file is untouched.
    #[error("--out {path}: writing failed: {message}")]
    Write {
        /// The output file.
        path: PathBuf,
        /// The I/O error.
        message: String,
    },
    /// The output file may not be written there.
    #[error("--out {path}: {reason}")]
    Destination {
        /// The output file.
        path: PathBuf,
        /// Why not.
        reason: String,
    },
}

/// A stamp in ns as seconds with all nine decimals (exact, unlike an f64).
pub fn fmt_ns(ns: i64) -> String {
    let sign = if ns < 0 { "-" } else { "" };
    let a = ns.unsigned_abs();
    format!("{sign}{}.{:09}", a / 1_000_000_000, a % 1_000_000_000)
}

impl BagError {
    /// The `admittance` exit code: 2 for a refused `--out` (usage), 1 for
    /// a failed write, 3 for the input (bag, profile).
    pub fn exit_code(&self) -> u8 {
        match self {
            BagError::Destination { .. } => 2,
            BagError::Write { .. } => 1,
            _ => 3,
        }
    }
}
