//! Decoding the profile's topics into time series, stamped by the header (or the
//! message's own stamp fields), with every skipped message counted by reason.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::container::RawMessage;
use crate::error::BagError;
use crate::flat::FlatSchema;
use crate::msgs::{self, Float64MultiArray, JointState, WrenchStamped};
use crate::profile::{Profile, SignalSource, FLOAT64_MULTI_ARRAY, JOINT_STATE, WRENCH_STAMPED};
use crate::report::{Skip, TimeBase, TopicCount};

mod assemble;

/// One decoded message of a signal, before the joints are put in order.
struct RawSample {
    stamp_ns: i64,
    log_ns: u64,
    /// JointState names (shared by the messages that repeat them).
    names: Option<Rc<[String]>>,
    values: Vec<f64>,
}

struct SignalState {
    role: &'static str,
    source: SignalSource,
    samples: Vec<RawSample>,
    time: TimeBase,
}

/// A signal's samples in the output's joint (or wrench component) order.
#[derive(Clone, Debug)]
pub struct Series {
    /// `q`, `qdot`, `tau` or `label`.
    pub role: &'static str,
    /// Topic.
    pub topic: String,
    /// Field.
    pub field: String,
    /// Column suffixes: the joint names, or `fx` ... `tz` for a wrench.
    pub columns: Vec<String>,
    /// Stamps, ns since the epoch, strictly increasing.
    pub stamps: Vec<i64>,
    /// Values, row-major `stamps x columns`.
    pub values: Vec<f64>,
    /// Which time the stamps are.
    pub time: TimeBase,
}

/// Collects the messages of the profile's topics while the bag is streamed.
pub struct Collector<'p> {
    bag: PathBuf,
    profile: &'p Profile,
    signals: Vec<SignalState>,
    topics: BTreeMap<String, TopicCount>,
    flat: HashMap<String, FlatSchema>,
    skips: BTreeMap<(String, String), Skip>,
    /// Values kept so far, against the memory budget.
    values: u128,
    messages: usize,
}

/// The decoded series and what was seen on the way.
pub struct Extracted {
    /// Joint names, in output order.
    pub joints: Vec<String>,
    /// The profile's signals.
    pub series: Vec<Series>,
    /// Every topic of the bag with its type and count.
    pub topics: Vec<TopicCount>,
    /// Skipped messages, by topic and reason.
    pub skips: Vec<Skip>,
    /// What the report should say besides (an optional label topic absent from the bag).
    pub notes: Vec<String>,
}

impl<'p> Collector<'p> {
    /// For a bag (named in errors) and a profile.
    pub fn new(bag: &Path, profile: &'p Profile) -> Self {
        let signals = profile
            .signals()
            .into_iter()
            .map(|(role, s)| SignalState {
                role,
                source: s.clone(),
                samples: Vec::new(),
                time: TimeBase {
                    has_stamp: matches!(s.type_name.as_str(), JOINT_STATE | WRENCH_STAMPED)
                        || s.stamp.is_some(),
                    ..TimeBase::default()
                },
            })
            .collect();
        Self {
            bag: bag.to_path_buf(),
            profile,
            signals,
            topics: BTreeMap::new(),
            flat: HashMap::new(),
            skips: BTreeMap::new(),
            values: 0,
            messages: 0,
        }
    }

    fn skip(&mut self, topic: &str, reason: &str, log_ns: u64, detail: String) {
        let entry = self
            .skips
            .entry((topic.to_string(), reason.to_string()))
            .or_insert_with(|| Skip {
                topic: topic.to_string(),
                reason: reason.to_string(),
                count: 0,
                first_log_time: log_ns as f64 * 1e-9,
                example: detail,
            });
        entry.count += 1;
    }

    /// Takes one message of the bag.
    pub fn visit(&mut self, m: &RawMessage) -> Result<(), BagError> {
        let count = self
            .topics
            .entry(m.topic.to_string())
            .or_insert_with(|| TopicCount {
                topic: m.topic.to_string(),
                type_name: m.type_name.to_string(),
                messages: 0,
            });
        count.messages += 1;
        self.messages += 1;
        let wanted: Vec<usize> = (0..self.signals.len())
            .filter(|i| self.signals[*i].source.topic == m.topic)
            .collect();
        if wanted.is_empty() {
            return Ok(());
        }
        for i in &wanted {
            self.check_type(*i, m)?;
        }
        match self.decode(m, &wanted)? {
            Ok(samples) => {
                for (i, (stamp, names, values)) in wanted.into_iter().zip(samples) {
                    self.values += values.len() as u128;
                    let s = &mut self.signals[i];
                    let stamp_ns = s.time.choose(stamp, m.log_time);
                    s.samples.push(RawSample {
                        stamp_ns,
                        log_ns: m.log_time,
                        names,
                        values,
                    });
                }
            }
            Err((reason, detail)) => self.skip(m.topic, reason, m.log_time, detail),
        }
        if self.values > crate::budget::MAX_TABLE_VALUES {
            return Err(BagError::Data {
                bag: self.bag.clone(),
                message: format!(
                    "the profile's topics hold more than {} values by message {} (log time {:.3} s): above the import's memory budget; import a shorter recording (record with `ros2 bag record --max-bag-duration SECONDS` and import each .mcap file on its own)",
                    crate::budget::MAX_TABLE_VALUES,
                    self.messages,
                    m.log_time as f64 * 1e-9
                ),
            });
        }
        Ok(())
    }

    fn check_type(&self, i: usize, m: &RawMessage) -> Result<(), BagError> {
        let s = &self.signals[i];
        let wrong = |expected: &str, found: &str| BagError::WrongType {
            bag: self.bag.clone(),
            topic: m.topic.to_string(),
            field: s.source.field.clone(),
            signal: s.role.to_string(),
            expected: expected.to_string(),
            found: found.to_string(),
        };
        if m.type_name != s.source.type_name {
            return Err(wrong(&s.source.type_name, m.type_name));
        }
        if m.encoding != "cdr" {
            return Err(wrong("cdr message encoding", m.encoding));
        }
        Ok(())
    }
}

/// Per wanted signal: the message's own stamp (None: none or zero), JointState names,
/// and the field's values. The error is a skip: its reason and detail.
type Decoded = Result<Vec<(Option<i64>, Option<Rc<[String]>>, Vec<f64>)>, (&'static str, String)>;

fn header_stamp(t: &msgs::Time) -> Option<i64> {
    (!t.is_zero()).then(|| t.nanos())
}

impl Collector<'_> {
    fn decode(&mut self, m: &RawMessage, wanted: &[usize]) -> Result<Decoded, BagError> {
        let fields: Vec<&SignalSource> = wanted.iter().map(|i| &self.signals[*i].source).collect();
        let undecodable = |e: String| Err(("undecodable payload", e));
        Ok(match m.type_name {
            JOINT_STATE => match msgs::decode::<JointState>(m.data) {
                Err(e) => undecodable(e),
                Ok(js) => {
                    let stamp = header_stamp(&js.header.stamp);
                    let names: Rc<[String]> = self.shared_names(m.topic, js.name.clone());
                    Ok(fields
                        .iter()
                        .map(|f| {
                            let v = match f.field.as_str() {
                                "position" => &js.position,
                                "velocity" => &js.velocity,
                                _ => &js.effort,
                            };
                            (stamp, Some(names.clone()), v.clone())
                        })
                        .collect())
                }
            },
            WRENCH_STAMPED => match msgs::decode::<WrenchStamped>(m.data) {
                Err(e) => undecodable(e),
                Ok(w) => {
                    let (f, t) = (w.wrench.force, w.wrench.torque);
                    let v = vec![f.x, f.y, f.z, t.x, t.y, t.z];
                    Ok(vec![(header_stamp(&w.header.stamp), None, v); fields.len()])
                }
            },
            FLOAT64_MULTI_ARRAY => match msgs::decode::<Float64MultiArray>(m.data) {
                Err(e) => undecodable(e),
                Ok(a) => match a.values() {
                    Err(e) => Err(("bad layout", e)),
                    Ok(v) => Ok(vec![(None, None, v.to_vec()); fields.len()]),
                },
            },
            _ => self.decode_flat(m, wanted)?,
        })
    }

    /// JointState name lists repeat: the previous list of the topic is reused when equal.
    fn shared_names(&self, topic: &str, names: Vec<String>) -> Rc<[String]> {
        for s in self.signals.iter().filter(|s| s.source.topic == topic) {
            if let Some(prev) = s.samples.last().and_then(|x| x.names.as_ref()) {
                if **prev == *names {
                    return prev.clone();
                }
            }
        }
        names.into()
    }

    fn decode_flat(&mut self, m: &RawMessage, wanted: &[usize]) -> Result<Decoded, BagError> {
        let first = &self.signals[wanted[0]];
        let field_err = |message: String| BagError::Field {
            bag: self.bag.clone(),
            topic: m.topic.to_string(),
            field: first.source.field.clone(),
            signal: first.role.to_string(),
            message,
        };
        if !self.flat.contains_key(m.topic) {
            let schema = match m.schema {
                Some(("ros2msg", text)) => FlatSchema::parse(&String::from_utf8_lossy(text)),
                Some((enc, _)) => Err(format!(
                    "the embedded schema is `{enc}`, only ros2msg definitions are read"
                )),
                None => Err("the bag embeds no message definition for it".into()),
            }
            .map_err(field_err)?;
            for i in wanted {
                let s = &self.signals[*i].source;
                let names = std::iter::once(&s.field).chain(s.stamp.iter().flatten());
                if let Some(missing) = names.clone().find(|n| !schema.has_field(n)) {
                    return Err(field_err(format!(
                        "the message definition has no field `{missing}`"
                    )));
                }
            }
            self.flat.insert(m.topic.to_string(), schema);
        }
        let mut names: Vec<&str> = Vec::new();
        for i in wanted {
            let s = &self.signals[*i].source;
            names.push(&s.field);
            names.extend(s.stamp.iter().flatten().map(String::as_str));
        }
        let values = match self.flat[m.topic].read(m.data, &names) {
            Ok(v) => v,
            Err(e) => return Ok(Err(("undecodable payload", e))),
        };
        let mut it = values.into_iter();
        let mut out = Vec::new();
        for i in wanted {
            let v = it.next().unwrap_or_default();
            let stamp = if self.signals[*i].source.stamp.is_some() {
                let sec = it.next().and_then(|x| x.first().copied()).unwrap_or(0.0);
                let nsec = it.next().and_then(|x| x.first().copied()).unwrap_or(0.0);
                let ns = (sec as i64)
                    .saturating_mul(1_000_000_000)
                    .saturating_add(nsec as i64);
                (ns != 0).then_some(ns)
            } else {
                None
            };
            out.push((stamp, None, v));
        }
        Ok(Ok(out))
    }
}
