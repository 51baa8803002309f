//! The second half of the extraction: the joints in output order, the torque constants,
//! the stamp check.

use std::rc::Rc;

use super::{Collector, Extracted, RawSample, Series, SignalState};
use crate::error::BagError;
use crate::profile::WRENCH_STAMPED;

impl Collector<'_> {
    /// Puts every signal in joint order, applies the torque constants, checks the stamps.
    pub fn finish(mut self) -> Result<Extracted, BagError> {
        let mut notes = Vec::new();
        // The label is optional (training does not use it): absent, it is a note.
        let absent = |s: &SignalState| !self.topics.contains_key(&s.source.topic);
        if let Some(i) = self
            .signals
            .iter()
            .position(|s| s.role == "label" && absent(s))
        {
            let s = self.signals.remove(i);
            notes.push(format!(
                "label topic `{}` is not in the bag: the CSV has no label.* columns (the label is optional; training does not use it)",
                s.source.topic
            ));
        }
        for s in &self.signals {
            if !self.topics.contains_key(&s.source.topic) {
                return Err(BagError::MissingTopic {
                    bag: self.bag.clone(),
                    topic: s.source.topic.clone(),
                    signal: s.role.to_string(),
                    present: self.present_topics(),
                });
            }
        }
        let joints = self.joints()?;
        let signals = std::mem::take(&mut self.signals);
        let mut series = Vec::new();
        for s in signals {
            series.push(self.order(s, &joints)?);
        }
        if let Some(k) = &self.profile.tau.torque_constant {
            self.apply_torque_constant(&mut series, k, joints.len())?;
        }
        for s in &series {
            self.check_monotonic(s)?;
        }
        Ok(Extracted {
            joints,
            series,
            topics: self.topics.into_values().collect(),
            skips: self.skips.into_values().collect(),
            notes,
        })
    }

    fn present_topics(&self) -> String {
        if self.topics.is_empty() {
            return "none (no messages)".into();
        }
        let list: Vec<String> = self
            .topics
            .values()
            .map(|t| format!("{} ({})", t.topic, t.type_name))
            .collect();
        list.join(", ")
    }

    fn field_error(&self, s: &SignalState, message: String) -> BagError {
        BagError::Field {
            bag: self.bag.clone(),
            topic: s.source.topic.clone(),
            field: s.source.field.clone(),
            signal: s.role.to_string(),
            message,
        }
    }

    /// The profile's joints, or the names of the first `q` message.
    fn joints(&self) -> Result<Vec<String>, BagError> {
        if let Some(j) = &self.profile.joints {
            return Ok(j.clone());
        }
        let q = &self.signals[0];
        let first = q.samples.iter().find_map(|s| s.names.as_ref());
        match first {
            Some(n) if !n.is_empty() => Ok(n.to_vec()),
            _ => Err(self.field_error(
                q,
                "no message with joint names: list them in the profile's `joints`".into(),
            )),
        }
    }
}

impl Collector<'_> {
    fn order(&mut self, s: SignalState, joints: &[String]) -> Result<Series, BagError> {
        let columns: Vec<String> = if s.source.type_name == WRENCH_STAMPED {
            ["fx", "fy", "fz", "tx", "ty", "tz"]
                .map(String::from)
                .to_vec()
        } else {
            joints.to_vec()
        };
        let n = columns.len();
        let received = s.samples.len();
        let mut stamps = Vec::with_capacity(received);
        let mut values = Vec::with_capacity(received * n);
        let mut index_cache: Option<(Rc<[String]>, Vec<usize>)> = None;
        let topic = s.source.topic.clone();
        for sample in &s.samples {
            let row = match &sample.names {
                Some(names) => self.by_name(&s, sample, names, joints, &mut index_cache),
                None if sample.values.len() != n => Err((
                    "wrong number of values",
                    format!("{} values for {n} columns", sample.values.len()),
                )),
                None => Ok(sample.values.clone()),
            };
            match row {
                Ok(r) if r.iter().all(|x| x.is_finite()) => {
                    stamps.push(sample.stamp_ns);
                    values.extend(r);
                }
                Ok(_) => self.skip(
                    &topic,
                    "non-finite value",
                    sample.log_ns,
                    format!("field `{}`", s.source.field),
                ),
                Err((reason, detail)) => self.skip(&topic, reason, sample.log_ns, detail),
            }
        }
        if stamps.is_empty() {
            let why = self.skip_summary(&topic);
            return Err(self.field_error(
                &s,
                format!("none of its {received} decoded messages is usable ({why})"),
            ));
        }
        Ok(Series {
            role: s.role,
            topic,
            field: s.source.field.clone(),
            columns,
            stamps,
            values,
            time: s.time,
        })
    }

    fn by_name(
        &self,
        s: &SignalState,
        sample: &RawSample,
        names: &Rc<[String]>,
        joints: &[String],
        cache: &mut Option<(Rc<[String]>, Vec<usize>)>,
    ) -> Result<Vec<f64>, (&'static str, String)> {
        if sample.values.len() != names.len() {
            let field = &s.source.field;
            return Err(if sample.values.is_empty() {
                ("empty field", format!("`{field}` is empty"))
            } else {
                (
                    "wrong number of values",
                    format!(
                        "{} `{field}` values for {} names",
                        sample.values.len(),
                        names.len()
                    ),
                )
            });
        }
        if !cache.as_ref().is_some_and(|(n, _)| Rc::ptr_eq(n, names)) {
            let mut idx = Vec::with_capacity(joints.len());
            for j in joints {
                match names.iter().position(|n| n == j) {
                    Some(i) => idx.push(i),
                    None => {
                        return Err((
                            "joint missing",
                            format!("no joint `{j}` among [{}]", names.join(", ")),
                        ))
                    }
                }
            }
            *cache = Some((names.clone(), idx));
        }
        let idx = &cache.as_ref().map(|c| c.1.clone()).unwrap_or_default();
        Ok(idx.iter().map(|i| sample.values[*i]).collect())
    }

    fn skip_summary(&self, topic: &str) -> String {
        let parts: Vec<String> = self
            .skips
            .values()
            .filter(|k| k.topic == topic)
            .map(|k| format!("{} skipped: {} (first: {})", k.count, k.reason, k.example))
            .collect();
        if parts.is_empty() {
            "no message".into()
        } else {
            parts.join("; ")
        }
    }

    fn apply_torque_constant(
        &self,
        series: &mut [Series],
        k: &[f64],
        n: usize,
    ) -> Result<(), BagError> {
        if k.len() != n {
            return Err(BagError::Profile {
                profile: self.profile.name.clone(),
                message: format!(
                    "[tau] torque_constant has {} values for the {n} joints",
                    k.len()
                ),
            });
        }
        for s in series.iter_mut().filter(|s| s.role == "tau") {
            for row in s.values.chunks_mut(n) {
                row.iter_mut().zip(k).for_each(|(x, k)| *x *= k);
            }
        }
        Ok(())
    }

    fn check_monotonic(&self, s: &Series) -> Result<(), BagError> {
        if let Some(i) = s.stamps.windows(2).position(|w| w[1] <= w[0]) {
            return Err(BagError::NonMonotonic {
                bag: self.bag.clone(),
                topic: s.topic.clone(),
                index: i + 1,
                time_ns: s.stamps[i + 1],
                previous_ns: s.stamps[i],
            });
        }
        Ok(())
    }
}
