//! `recording.mcap`: the time series of every variant as an MCAP file that Foxglove opens.
//!
//! One set of channels per variant, topics `/VARIANT/GROUP`, JSON messages (message encoding
//! `json`) with JSON-Schema schemas (schema encoding `jsonschema`). Each message holds one
//! row of the CSV: `t` and, per signal, an object keyed by joint name (e.g.
//! `/nn_compensated/joint_state` `.q.left_s0`). The log time is the row's `t` in
//! nanoseconds from the start of the run. A metadata record `admittance` carries
//! `format_version` (`RECORDING_FORMAT_VERSION`).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::{Seek, Write};

use admittance_runfolder::columns;

use crate::folder::RunFolder;
use crate::table::Table;

/// Version of the recording's layout (topics, message fields), in its metadata record.
pub const RECORDING_FORMAT_VERSION: u32 = 1;

/// A channel group: topic suffix, schema name, and the column prefixes it carries with
/// what they are.
pub type Group = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// The channel groups.
pub const GROUPS: &[Group] = &[
    (
        "joint_state",
        "admittance.JointState",
        &[
            (columns::POSITION, "true joint angle (rad)"),
            (columns::VELOCITY, "true joint velocity (rad/s)"),
            (columns::MEASURED_POSITION, "encoder reading (rad)"),
        ],
    ),
    (
        "reference",
        "admittance.Reference",
        &[
            (columns::DESIRED, "desired trajectory (rad)"),
            (
                columns::REFERENCE,
                "compliant reference, admittance output (rad)",
            ),
        ],
    ),
    (
        "torque",
        "admittance.Torque",
        &[
            (columns::COMMAND, "commanded torque (N m)"),
            (
                columns::APPLIED,
                "applied torque after deadzone and limits (N m)",
            ),
        ],
    ),
    (
        "external_torque",
        "admittance.ExternalTorque",
        &[
            (columns::EXTERNAL, "true external torque (N m)"),
            (
                columns::EXTERNAL_ESTIMATE,
                "estimated external torque (N m)",
            ),
        ],
    ),
    (
        "approximation",
        "admittance.Approximation",
        &[
            (
                columns::F_TRUE,
                "f = M alpha' + C alpha + G of the true arm (N m)",
            ),
            (columns::F_ESTIMATE, "the network's f (N m)"),
        ],
    ),
    (
        "nodes",
        "admittance.NodeCounts",
        &[(columns::NODES, "node count per network")],
    ),
    (
        "hand",
        "admittance.Hand",
        &[
            (columns::HAND_FORCE, "true force on the hand (N, base axes)"),
            (
                columns::HAND_FORCE_ESTIMATE,
                "estimated hand force J^+T tau_ext_hat (N)",
            ),
            (columns::HAND_POSITION, "hand position (m, base frame)"),
            (
                columns::HAND_REFERENCE,
                "hand position of the compliant reference (m)",
            ),
            (columns::HAND_DESIRED, "desired hand position (m)"),
        ],
    ),
];

/// A message field: name, description, and its members as (member name, column index);
/// a single member with an empty name is a plain number.
type Field = (String, String, Vec<(String, usize)>);

/// One channel to write: topic, schema, and for each field its member columns.
struct Channel {
    topic: String,
    schema_name: String,
    schema: String,
    fields: Vec<Field>,
}

fn json_string(s: &str) -> String {
    serde_json::Value::String(s.to_string()).to_string()
}

fn channels(variant: &str, table: &Table) -> Vec<Channel> {
    // Group columns `PREFIX.MEMBER` by prefix; plain columns (other than t) go to `scalars`.
    let mut by_prefix: BTreeMap<&str, Vec<(String, usize)>> = BTreeMap::new();
    let mut scalars = Vec::new();
    for (k, c) in table.columns.iter().enumerate() {
        match c.split_once('.') {
            Some((p, m)) => by_prefix.entry(p).or_default().push((m.to_string(), k)),
            None if c != columns::TIME => scalars.push((c.clone(), k)),
            None => {}
        }
    }
    let mut out = Vec::new();
    let mut make = |suffix: &str, schema_name: &str, fields: Vec<Field>| {
        if fields.is_empty() {
            return;
        }
        let mut props = String::from(
            "\"t\":{\"type\":\"number\",\"description\":\"time since the start of the run (s)\"}",
        );
        for (name, desc, members) in &fields {
            if members.len() == 1 && members[0].0.is_empty() {
                let _ = write!(
                    props,
                    ",{}:{{\"type\":[\"number\",\"null\"],\"description\":{}}}",
                    json_string(name),
                    json_string(desc)
                );
            } else {
                let inner: Vec<String> = members
                    .iter()
                    .map(|(m, _)| format!("{}:{{\"type\":[\"number\",\"null\"]}}", json_string(m)))
                    .collect();
                let _ = write!(
                    props,
                    ",{}:{{\"type\":\"object\",\"description\":{},\"properties\":{{{}}}}}",
                    json_string(name),
                    json_string(desc),
                    inner.join(",")
                );
            }
        }
        out.push(Channel {
            topic: format!("/{variant}/{suffix}"),
            schema_name: schema_name.to_string(),
            schema: format!("{{\"$schema\":\"https://json-schema.org/draft/2020-12/schema\",\"title\":{},\"type\":\"object\",\"properties\":{{{props}}}}}", json_string(schema_name)),
            fields,
        });
    };
    for (suffix, schema, prefixes) in GROUPS {
        let fields: Vec<_> = prefixes
            .iter()
            .filter_map(|(p, d)| {
                by_prefix
                    .remove(p)
                    .map(|m| (p.to_string(), d.to_string(), m))
            })
            .collect();
        make(suffix, schema, fields);
    }
    for (p, members) in std::mem::take(&mut by_prefix) {
        make(
            p,
            &format!("admittance.{p}"),
            vec![(p.to_string(), format!("columns {p}.*"), members)],
        );
    }
    if !scalars.is_empty() {
        let fields = scalars
            .into_iter()
            .map(|(name, k)| {
                let desc = if name == columns::HAND_ERROR {
                    "hand position error (m)".to_string()
                } else {
                    format!("column {name}")
                };
                (name, desc, vec![(String::new(), k)])
            })
            .collect();
        make("scalars", "admittance.Scalars", fields);
    }
    out
}

fn push_number(out: &mut String, v: f64) {
    if v.is_finite() {
        let _ = write!(out, "{v}");
    } else {
        out.push_str("null");
    }
}

fn message(channel: &Channel, table: &Table, row: usize, t: f64, out: &mut String) {
    out.clear();
    out.push_str("{\"t\":");
    push_number(out, t);
    for (name, _, members) in &channel.fields {
        let _ = write!(out, ",\"{name}\":");
        if members.len() == 1 && members[0].0.is_empty() {
            push_number(out, table.data[members[0].1][row]);
        } else {
            out.push('{');
            for (i, (m, k)) in members.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                let _ = write!(out, "\"{m}\":");
                push_number(out, table.data[*k][row]);
            }
            out.push('}');
        }
    }
    out.push('}');
}

/// Writes the recording of every variant of `folder` to `w`; returns the number of
/// messages written.
pub fn write<W: Write + Seek>(folder: &RunFolder, w: W) -> Result<u64, String> {
    let err = |e: mcap::McapError| format!("writing the MCAP recording: {e}");
    let options = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile("")
        .library(concat!("admittance-report ", env!("CARGO_PKG_VERSION")));
    let mut writer = options.create(w).map_err(err)?;
    let mut meta = BTreeMap::new();
    meta.insert("format".to_string(), "admittance-recording".to_string());
    meta.insert(
        "format_version".to_string(),
        RECORDING_FORMAT_VERSION.to_string(),
    );
    meta.insert("scenario".to_string(), folder.scenario.clone());
    meta.insert("joints".to_string(), folder.joints.join(","));
    meta.insert(
        "variants".to_string(),
        folder
            .variants
            .iter()
            .map(|v| v.name.as_str())
            .collect::<Vec<_>>()
            .join(","),
    );
    meta.insert(
        "log_time".to_string(),
        "the CSV's t column in nanoseconds since the start of the run".to_string(),
    );
    writer
        .write_metadata(&mcap::records::Metadata {
            name: "admittance".into(),
            metadata: meta,
        })
        .map_err(err)?;
    let mut count = 0u64;
    let mut buf = String::new();
    for v in &folder.variants {
        let Some(t) = v.table.col(columns::TIME) else {
            continue;
        };
        let chans = channels(&v.name, &v.table);
        let mut ids = Vec::new();
        for c in &chans {
            let schema = writer
                .add_schema(&c.schema_name, "jsonschema", c.schema.as_bytes())
                .map_err(err)?;
            ids.push(
                writer
                    .add_channel(schema, &c.topic, "json", &BTreeMap::new())
                    .map_err(err)?,
            );
        }
        for (row, &time) in t.iter().enumerate() {
            if !(time.is_finite() && time >= 0.0) {
                continue;
            }
            let ns = (time * 1e9).round() as u64;
            for (c, &id) in chans.iter().zip(&ids) {
                message(c, &v.table, row, time, &mut buf);
                let header = mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: row as u32,
                    log_time: ns,
                    publish_time: ns,
                };
                writer
                    .write_to_known_channel(&header, buf.as_bytes())
                    .map_err(err)?;
                count += 1;
            }
        }
    }
    writer.finish().map_err(err)?;
    Ok(count)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_columns_into_channels() {
        let t = Table::from_columns(
            [
                "t",
                "q.a",
                "q.b",
                "q_d.a",
                "q_d.b",
                "ee_error",
                "nodes.f",
                "zeta.a",
                "f_hand.x",
                "f_hand_hat.x",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect(),
            vec![vec![0.0, 0.5]; 10],
        );
        let ch = channels("v", &t);
        let topics: Vec<&str> = ch.iter().map(|c| c.topic.as_str()).collect();
        assert_eq!(
            topics,
            [
                "/v/joint_state",
                "/v/reference",
                "/v/nodes",
                "/v/hand",
                "/v/zeta",
                "/v/scalars"
            ]
        );
        let mut s = String::new();
        message(&ch[0], &t, 1, 0.5, &mut s);
        let v: serde_json::Value = serde_json::from_str(&s).unwrap();
        assert_eq!(v["q"]["b"], 0.5);
        message(&ch[3], &t, 1, 0.5, &mut s);
        let v: serde_json::Value = serde_json::from_str(&s).unwrap();
        assert_eq!(v["f_hand_hat"]["x"], 0.5);
        message(&ch[5], &t, 0, 0.0, &mut s);
        let v: serde_json::Value = serde_json::from_str(&s).unwrap();
        assert_eq!(v["ee_error"], 0.0);
        for c in &ch {
            let schema: serde_json::Value = serde_json::from_str(&c.schema).unwrap();
            assert_eq!(schema["type"], "object");
        }
    }
}
