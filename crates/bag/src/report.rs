//! What an import read, skipped and wrote, for the user to check.

use std::fmt;

/// A topic of the bag with its type and message count.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicCount {
    /// Topic.
    pub topic: String,
    /// Type (the schema's name).
    pub type_name: String,
    /// Messages read.
    pub messages: usize,
}

/// Messages of a topic skipped for one reason.
#[derive(Clone, Debug, PartialEq)]
pub struct Skip {
    /// Topic.
    pub topic: String,
    /// The reason (`undecodable payload`, `joint missing`, `non-finite value`, ...).
    pub reason: String,
    /// How many.
    pub count: usize,
    /// Log time (s since the epoch) of the first.
    pub first_log_time: f64,
    /// The first one's details.
    pub example: String,
}

/// Which time a signal's samples carry.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeBase {
    /// Whether the type carries a stamp (header, or the profile's `stamp` fields).
    pub has_stamp: bool,
    /// Samples stamped by the message's stamp.
    pub stamped: usize,
    /// Samples stamped by the log (receive) time: the type has no stamp, or it was zero.
    pub log_time: usize,
}

impl TimeBase {
    /// The stamp of a sample: the message's own when it has a non-zero one, else the log
    /// time (counted).
    pub fn choose(&mut self, stamp: Option<i64>, log_ns: u64) -> i64 {
        match stamp {
            Some(t) => {
                self.stamped += 1;
                t
            }
            None => {
                self.log_time += 1;
                i64::try_from(log_ns).unwrap_or(i64::MAX)
            }
        }
    }

    /// In words, for the report.
    pub fn describe(&self) -> String {
        match (self.has_stamp, self.log_time) {
            (true, 0) => "message stamps".into(),
            (false, _) => "log (receive) time: the type has no stamp".into(),
            (true, n) => format!(
                "message stamps; {n} of {} messages had a zero stamp and got their log (receive) time",
                n + self.stamped
            ),
        }
    }
}

/// One signal of the import.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalReport {
    /// `q`, `qdot`, `tau`, `label`.
    pub role: String,
    /// Topic and field.
    pub topic: String,
    /// Field.
    pub field: String,
    /// Samples used.
    pub samples: usize,
    /// Median rate of its stamps (Hz).
    pub median_rate_hz: f64,
    /// Its time base.
    pub time: TimeBase,
}

/// The summary of an import.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportReport {
    /// The `.mcap` files read.
    pub files: Vec<String>,
    /// Every topic in the bag.
    pub topics: Vec<TopicCount>,
    /// The profile's signals.
    pub signals: Vec<SignalReport>,
    /// Skipped messages.
    pub skips: Vec<Skip>,
    /// Damage accepted with `accept_damage`: skipped chunks, where reading stopped.
    pub damage: Vec<String>,
    /// Damaged chunks (or other records) skipped with `accept_damage`.
    pub skipped_chunks: usize,
    /// Notes and warnings: an absent optional label topic, a low rate accepted.
    pub notes: Vec<String>,
    /// Joint names.
    pub joints: Vec<String>,
    /// Output rate (Hz) and whether it was the joint topic's median rate.
    pub rate_hz: f64,
    /// Whether the rate was the default.
    pub rate_is_median: bool,
    /// Rows of the table.
    pub rows: usize,
    /// Leading rows dropped because their derivatives need earlier samples.
    pub dropped_leading_rows: usize,
    /// Duration of the table (s).
    pub duration_s: f64,
    /// Gaps longer than 10 periods of a signal: (topic, start time s, length s).
    pub gaps: Vec<(String, f64, f64)>,
    /// How qdot and qddot were obtained.
    pub derivatives: String,
}

impl ImportReport {
    /// Total skipped messages.
    pub fn skipped(&self) -> usize {
        self.skips.iter().map(|s| s.count).sum()
    }
}

impl fmt::Display for ImportReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "read: {}", self.files.join(", "))?;
        writeln!(f, "topics:")?;
        for t in &self.topics {
            writeln!(
                f,
                "  {} ({}): {} messages",
                t.topic, t.type_name, t.messages
            )?;
        }
        writeln!(f, "signals:")?;
        for s in &self.signals {
            writeln!(
                f,
                "  {:<5} {} [{}]: {} samples, median {:.3} Hz, time: {}",
                s.role,
                s.topic,
                s.field,
                s.samples,
                s.median_rate_hz,
                s.time.describe()
            )?;
        }
        writeln!(f, "skipped messages: {}", self.skipped())?;
        for s in &self.skips {
            writeln!(
                f,
                "  {}: {} x {} (first at log time {:.6} s: {})",
                s.topic, s.count, s.reason, s.first_log_time, s.example
            )?;
        }
        for d in &self.damage {
            writeln!(f, "DAMAGED (accepted): {d}")?;
        }
        if !self.damage.is_empty() {
            writeln!(f, "damaged chunks skipped: {}", self.skipped_chunks)?;
        }
        for n in &self.notes {
            writeln!(f, "note: {n}")?;
        }
        for (topic, start, len) in &self.gaps {
            writeln!(f, "gap: {topic}: no message for {len:.3} s from t = {start:.3} s (interpolated across)")?;
        }
        writeln!(f, "joints: {}", self.joints.join(", "))?;
        let how = if self.rate_is_median {
            "the median rate of the q topic"
        } else {
            "--rate"
        };
        writeln!(f, "rate: {:.6} Hz ({how})", self.rate_hz)?;
        writeln!(f, "derivatives: {}", self.derivatives)?;
        write!(
            f,
            "rows: {} ({:.3} s; {} leading rows dropped for the derivatives)",
            self.rows, self.duration_s, self.dropped_leading_rows
        )
    }
}
