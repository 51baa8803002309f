//! What the bridge and the fake arm report: counts, skips by reason, latency percentiles.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Percentiles of a set of durations (microseconds).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    /// How many.
    pub count: usize,
    /// Median (us).
    pub median_us: f64,
    /// 99th percentile (us).
    pub p99_us: f64,
    /// Largest (us).
    pub max_us: f64,
}

impl Percentiles {
    /// Of `ns` (nanoseconds; reordered). Nearest-rank percentiles; zeros when empty.
    pub fn of(ns: &mut [i64]) -> Self {
        if ns.is_empty() {
            return Self::default();
        }
        ns.sort_unstable();
        let rank = |p: f64| {
            let k = ((p * ns.len() as f64).ceil() as usize).clamp(1, ns.len());
            ns[k - 1] as f64 * 1e-3
        };
        Self {
            count: ns.len(),
            median_us: rank(0.5),
            p99_us: rank(0.99),
            max_us: ns[ns.len() - 1] as f64 * 1e-3,
        }
    }
}

/// The skipped messages of one reason.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SkipCount {
    /// How many.
    pub count: u64,
    /// The first one's details (topic, field, joint, values).
    pub first: String,
}

/// The bridge's statistics, printed at exit and written with `--stats FILE`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BridgeStats {
    /// The input topic.
    pub topic: String,
    /// Messages taken from the topic (decoded or not).
    pub received: u64,
    /// Messages stepped and answered (estimate published).
    pub stepped: u64,
    /// Messages skipped, by reason.
    pub skipped: BTreeMap<String, SkipCount>,
    /// Publish calls that failed.
    pub publish_errors: u64,
    /// From the DDS layer's receipt of a message (its reception time stamp) to the return of
    /// the last publish call of its answer.
    pub receipt_to_publish: Percentiles,
    /// From the bridge taking the message from its reader to the same point (decoding not
    /// included: the reader decodes on take).
    pub take_to_publish: Percentiles,
    /// The rate of the stepped messages' stamps (median period), Hz.
    pub stamp_rate_hz: f64,
    /// The scenario's control rate, Hz: the observer assumes the messages come at it.
    pub loop_rate_hz: f64,
}

impl BridgeStats {
    /// Counts a skipped message.
    pub fn skip(&mut self, reason: &str, detail: &str) {
        let e = self.skipped.entry(reason.to_string()).or_default();
        if e.count == 0 {
            e.first = detail.to_string();
        }
        e.count += 1;
    }

    /// A few lines for a person.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{}: {} messages received, {} stepped (estimate published), stamps at {:.1} Hz (loop {:.1} Hz)\n",
            self.topic, self.received, self.stepped, self.stamp_rate_hz, self.loop_rate_hz
        );
        for (reason, c) in &self.skipped {
            s += &format!("  skipped {} ({reason}), the first: {}\n", c.count, c.first);
        }
        if self.publish_errors > 0 {
            s += &format!("  {} publish calls failed\n", self.publish_errors);
        }
        let p = &self.receipt_to_publish;
        let t = &self.take_to_publish;
        s += &format!(
            "  latency receipt -> publish: median {:.0} us, 99th percentile {:.0} us, max {:.0} us (take -> publish: {:.0} / {:.0} us)\n",
            p.median_us, p.p99_us, p.max_us, t.median_us, t.p99_us
        );
        s
    }
}

/// The median period of increasing stamps (ns) as a rate (Hz); 0 with fewer than 2.
pub fn stamp_rate(stamps: &[i64]) -> f64 {
    let mut d: Vec<i64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return 0.0;
    }
    d.sort_unstable();
    let m = d[d.len() / 2];
    if m > 0 {
        1e9 / m as f64
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_nearest_rank() {
        let mut v: Vec<i64> = (1..=200).rev().map(|k| k * 1000).collect();
        let p = Percentiles::of(&mut v);
        assert_eq!(p.count, 200);
        assert_eq!(p.median_us, 100.0);
        assert_eq!(p.p99_us, 198.0);
        assert_eq!(p.max_us, 200.0);
        assert_eq!(Percentiles::of(&mut []), Percentiles::default());
    }

    #[test]
    fn rate_from_stamps() {
        let s: Vec<i64> = (0..11).map(|k| k * 2_000_000).collect();
        assert_eq!(stamp_rate(&s), 500.0);
        assert_eq!(stamp_rate(&s[..1]), 0.0);
    }
}
