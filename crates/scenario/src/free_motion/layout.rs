//! The columns of a free-motion CSV and its rows read through them (`free_motion.rs`).

use super::{FreeMotionError, MAX_ABS_VALUE};

/// Which fields of a row the loader reads.
pub(super) struct Layout<'h> {
    /// Every header column, trimmed.
    pub columns: Vec<&'h str>,
    /// The joints, in the order of the data.
    pub joints: Vec<String>,
    /// Field index of `t`, then of `q`, `qdot`, `qddot`, `tau` for every joint (`None`: a
    /// derivative the file leaves out, taken by differences after reading).
    pub fields: Vec<Option<usize>>,
    /// The derivatives the file leaves out for every joint (`qdot`, `qddot`).
    pub derived: Vec<&'static str>,
}

const SIGNALS: [&str; 4] = ["q", "qdot", "qddot", "tau"];
/// The signals a file may leave out for every joint at once.
const DERIVATIVES: [&str; 2] = ["qdot", "qddot"];

/// The data rows of a contiguous stretch of the file, up to its first problem.
pub(super) struct Stretch {
    /// Line number (1-based) of its first row.
    pub first_line: usize,
    pub t: Vec<f64>,
    pub q: Vec<f64>,
    pub qdot: Vec<f64>,
    pub qddot: Vec<f64>,
    pub tau: Vec<f64>,
    /// The first problem in the stretch, the rows before it kept.
    pub problem: Option<FreeMotionError>,
}

impl Layout<'_> {
    /// `rows` (0-based line index, text) parsed and checked (field count, values, time
    /// increasing within them) up to the first problem, which the stretch carries.
    pub(super) fn parse_rows(&self, rows: &[(usize, &str)], source_name: &str) -> Stretch {
        let n = self.joints.len();
        let mut out = Stretch {
            first_line: rows.first().map_or(0, |(k, _)| k + 1),
            t: Vec::with_capacity(rows.len()),
            q: Vec::with_capacity(rows.len() * n),
            qdot: Vec::with_capacity(rows.len() * n),
            qddot: Vec::with_capacity(rows.len() * n),
            tau: Vec::with_capacity(rows.len() * n),
            problem: None,
        };
        // Field index -> slot in `values` (t, then q, qdot, qddot, tau per joint).
        let mut values = vec![0.0; 1 + 4 * n];
        let mut parts: Vec<&str> = Vec::with_capacity(self.columns.len());
        for &(k, line) in rows {
            if let Err(problem) = self.parse_row(line, k + 1, source_name, &mut parts, &mut values)
            {
                out.problem = Some(problem);
                break;
            }
            let t = values[0];
            if let Some(&previous) = out.t.last() {
                if t <= previous {
                    out.problem = Some(FreeMotionError::NonMonotonicTime {
                        source_name: source_name.to_string(),
                        line: k + 1,
                        time: t,
                        previous,
                    });
                    break;
                }
            }
            out.t.push(t);
            for (s, signal) in [&mut out.q, &mut out.qdot, &mut out.qddot, &mut out.tau]
                .into_iter()
                .enumerate()
            {
                signal.extend_from_slice(&values[1 + s * n..1 + (s + 1) * n]);
            }
        }
        out
    }

    /// One row's fields into `values` (its slots: t, then q, qdot, qddot, tau per joint).
    fn parse_row<'l>(
        &self,
        line: &'l str,
        line_no: usize,
        source_name: &str,
        parts: &mut Vec<&'l str>,
        values: &mut [f64],
    ) -> Result<(), FreeMotionError> {
        parts.clear();
        parts.extend(line.split(','));
        if parts.len() != self.columns.len() {
            return Err(FreeMotionError::FieldCount {
                source_name: source_name.to_string(),
                line: line_no,
                expected: self.columns.len(),
                found: parts.len(),
            });
        }
        for (slot, &field) in self.fields.iter().enumerate() {
            if let Some(field) = field {
                values[slot] = self.value(parts[field], field, slot, line_no, source_name)?;
            }
        }
        Ok(())
    }
}

impl<'h> Layout<'h> {
    pub(super) fn from_header(
        header: &'h str,
        line: usize,
        source_name: &str,
        joints: Option<&[&str]>,
    ) -> Result<Self, FreeMotionError> {
        // A byte-order mark (spreadsheets' UTF-8 export) and quoted names (R's write.csv)
        // are the header's dress, not its names.
        let header = header.strip_prefix('\u{feff}').unwrap_or(header);
        let columns: Vec<&str> = header
            .split(',')
            .map(|c| {
                let c = c.trim();
                c.strip_prefix('"')
                    .and_then(|c| c.strip_suffix('"'))
                    .unwrap_or(c)
            })
            .collect();
        if columns.len() == 1 {
            if let Some(separator) = [';', '\t', '|'].into_iter().find(|s| header.contains(*s)) {
                return Err(FreeMotionError::Header {
                    source_name: source_name.to_string(),
                    line,
                    message: format!(
                        "the header has no commas but {:?}s: the file must be comma-separated \
                         (t,q.J,...); save it with commas as the separator and a point as the \
                         decimal mark",
                        separator
                    ),
                });
            }
        }
        let missing = |column: String| FreeMotionError::MissingColumn {
            source_name: source_name.to_string(),
            line,
            column,
        };
        let find = |name: &str| -> Result<usize, FreeMotionError> {
            let mut hits = columns
                .iter()
                .enumerate()
                .filter(|(_, c)| **c == name)
                .map(|(i, _)| i);
            let first = hits.next().ok_or_else(|| missing(name.to_string()))?;
            match hits.next() {
                Some(second) => Err(FreeMotionError::RepeatedColumn {
                    source_name: source_name.to_string(),
                    line,
                    column: name.to_string(),
                    first: first + 1,
                    second: second + 1,
                }),
                None => Ok(first),
            }
        };
        let joints: Vec<String> = match joints {
            Some(j) => j.iter().map(|s| s.to_string()).collect(),
            None => columns
                .iter()
                .filter_map(|c| c.strip_prefix("q."))
                .map(String::from)
                .collect(),
        };
        let mut fields = vec![Some(find("t")?)];
        if joints.is_empty() {
            return Err(missing("q.<joint>".into()));
        }
        let mut derived = Vec::new();
        for prefix in SIGNALS {
            let names: Vec<String> = joints.iter().map(|j| format!("{prefix}.{j}")).collect();
            // A derivative absent for every joint is taken by differences; one present for
            // some joints only is a missing column.
            if DERIVATIVES.contains(&prefix) && !names.iter().any(|n| columns.contains(&n.as_str()))
            {
                derived.push(prefix);
                fields.extend(names.iter().map(|_| None));
                continue;
            }
            for name in &names {
                fields.push(Some(find(name)?));
            }
        }
        Ok(Self {
            columns,
            joints,
            fields,
            derived,
        })
    }

    /// The value of `text` (field `field`, read into `slot`), validated.
    fn value(
        &self,
        text: &str,
        field: usize,
        slot: usize,
        line: usize,
        source_name: &str,
    ) -> Result<f64, FreeMotionError> {
        let column = || self.columns[field].to_string();
        let text = text.trim();
        let v: f64 = text.parse().map_err(|_| FreeMotionError::NotANumber {
            source_name: source_name.to_string(),
            line,
            column: column(),
            text: text.to_string(),
        })?;
        if !v.is_finite() {
            return Err(FreeMotionError::NonFinite {
                source_name: source_name.to_string(),
                line,
                column: column(),
                value: v,
            });
        }
        // Slot 0 is the time, which only has to increase.
        if slot > 0 && v.abs() > MAX_ABS_VALUE {
            return Err(FreeMotionError::OutOfRange {
                source_name: source_name.to_string(),
                line,
                column: column(),
                value: v,
                limit: MAX_ABS_VALUE,
            });
        }
        Ok(v)
    }
}
