//! Free-motion training data from rosbag2 recordings (issue #24).
//!
//! `admittance import BAG --profile NAME|FILE.toml --out FILE.csv [--rate HZ]` reads a
//! rosbag2 bag recorded on a real arm and writes the free-motion CSV that
//! `admittance train --data` reads (`t, q.J..., qdot.J..., qddot.J..., tau.J...`, see
//! `admittance_scenario::FreeMotionData`), plus the optional `label.*` columns (the
//! vendor's external torque or wrench estimate, for evaluation) and `bag_stamp_ns`.
//!
//! # Bags
//!
//! MCAP storage only (the default of rosbag2 since Iron): a bag folder (its
//! `metadata.yaml` is not needed: the schemas are embedded in the MCAP files; a split
//! recording's files are read in name order), its `metadata.yaml`, or a single `.mcap`
//! file. Chunks may be uncompressed or zstd-compressed (`ros2 bag record -s mcap
//! --storage-preset-profile zstd_fast`). A sqlite3 bag (`.db3`) and lz4 chunks are
//! refused with the conversion command [`CONVERT_COMMAND`]. The files are streamed
//! record by record by the crate's own bounded reader (`container`): every declared length
//! is checked against the file and a 256 MiB limit before allocating, a chunk's
//! decompression ends with its input and must give exactly the declared size. Only
//! regular files are opened (a FIFO or a device is refused from its file type).
//!
//! # Tested here
//!
//! Bags written by `rosbags` and the `mcap` Python package (`tests/make_bags.py`, no ROS)
//! from an analytic trajectory on each profile's topic names: imported at the bag's rate
//! the recorded columns come back exactly; resampled, within the interpolation bound; and
//! damaged bags (truncated, flipped bytes, wrong types, missing topics, bad stamps) give an
//! error or a counted skip, never a panic. No bag from a real robot was available: the
//! topic names come from the drivers' documentation (`docs/import.md`, "What needs a real
//! robot").
//!
//! Payloads are CDR. `builtin_interfaces/Time`, `std_msgs/Header`,
//! `sensor_msgs/JointState`, `geometry_msgs/WrenchStamped` and
//! `std_msgs/Float64MultiArray` are decoded into fixed structs ([`msgs`]); any other type
//! (a vendor's message such as `lbr_fri_idl/msg/LBRState`) is read field by field from the
//! `ros2msg` definition embedded in the bag, for flat messages (primitives, strings and
//! their arrays before the wanted fields).
//!
//! # Profiles
//!
//! A [`Profile`] (TOML) maps topic and field to `q`, `qdot` (optional), `tau` and the
//! optional label; the built-in ones are `franka` (franka_ros2), `ur` (ur_robot_driver:
//! effort is motor current, so it needs per-joint torque constants in a copy of the
//! profile) and `lbr` (lbr_fri_ros2_stack's `LBRState`). See `crates/bag/profiles/` and
//! `docs/import.md`.
//!
//! # Processing
//!
//! * Time: the header stamp (for LBRState its FRI time stamp), never the receive time,
//!   except where the stamp is zero or the type has none (Float64MultiArray): then the
//!   log time, and the report says for how many messages.
//! * Stamps of each signal must increase strictly: otherwise an error naming bag, topic
//!   and times (no message is dropped for it).
//! * A message that cannot be used (undecodable payload, a missing joint, wrong array
//!   length, a non-finite value) is skipped and counted by topic and reason in the
//!   [`ImportReport`]; a signal left with no message is an error. Damaged MCAP data
//!   (truncation, a failed CRC, a declared size that does not hold) is an error naming
//!   file, chunk and byte offset unless [`ImportOptions::accept_damage`]: then a damaged
//!   chunk is skipped and counted, and the loss is reported. An absent label topic is a
//!   note; a recording under [`MIN_RATE_HZ`] is refused unless
//!   [`ImportOptions::accept_low_rate`]; the table's size is checked against
//!   [`MAX_TABLE_VALUES`] before the resampling allocates.
//! * The table is sampled on a fixed grid (default: the median rate of the `q` topic) over
//!   the span common to all signals, by linear interpolation; a grid point on a sample's
//!   stamp takes that sample exactly. `qdot`, when the profile has none, is the backward
//!   difference of `q`, and `qddot` the backward difference of `qdot`, as the observers'
//!   input conditioning differentiates; the leading rows without a derivative are dropped.
//! * The CSV is written atomically and only over a CSV that this tool wrote (recognised
//!   by its last column, [`STAMP_COLUMN`]).
#![warn(missing_docs)]
// An import fails at most once, on a cold path: the size of `BagError` (it carries the bag,
// topic, field and types as text) does not matter.
#![allow(clippy::result_large_err)]

mod budget;
mod container;
mod error;
mod extract;
mod flat;
mod import;
pub mod msgs;
mod output;
mod profile;
mod report;
mod resample;
mod source;

pub use budget::MAX_TABLE_VALUES;
pub use error::{fmt_ns, BagError, CONVERT_COMMAND};
pub use import::{import, import_to_csv, ImportOptions, Imported, MIN_RATE_HZ};
pub use output::{check_columns, check_destination, csv_text, write_csv, STAMP_COLUMN};
pub use profile::{Profile, SignalSource, FLOAT64_MULTI_ARRAY, JOINT_STATE, WRENCH_STAMPED};
pub use report::{ImportReport, SignalReport, Skip, TimeBase, TopicCount};
pub use resample::Table;
