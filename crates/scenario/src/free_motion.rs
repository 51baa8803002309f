//! Free-motion data (METHOD.md section 5): what the sensors saw while the arm moved without
//! contact, the training data of the learned observer. The format is the one the runner
//! writes with `[record] free_motion_csv = true` and the one a user exports from a real arm
//! (docs/outputs.md, "free_motion.csv"):
//!
//! ```text
//! t,q.J1,...,q.Jn,qdot.J1,...,qdot.Jn,qddot.J1,...,qddot.Jn,tau.J1,...,tau.Jn
//! ```
//!
//! one row per control sample, comma separated, a header naming the columns (any order;
//! extra columns are ignored). [`FreeMotionData::parse`] validates every row and reports
//! the first problem with its 1-based line number: a missing column, a row with the wrong
//! number of fields, a field that is not a number, a non-finite value, a time that does not
//! increase strictly.

use std::path::Path;

/// A problem with a free-motion file. `line` is 1-based (the header is line 1).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FreeMotionError {
    /// The file could not be read.
    #[error("{source_name}: {message}")]
    Io {
        /// The file.
        source_name: String,
        /// The I/O error.
        message: String,
    },
    /// No header, or no data rows.
    #[error("{source_name}: {message}")]
    Empty {
        /// The file.
        source_name: String,
        /// What is missing.
        message: String,
    },
    /// A required column is absent from the header.
    #[error("{source_name}:{line}: missing column `{column}` (need t, q.J, qdot.J, qddot.J, tau.J for every joint J named by a q.J column)")]
    MissingColumn {
        /// The file.
        source_name: String,
        /// The header line.
        line: usize,
        /// The column.
        column: String,
    },
    /// A row has fewer or more fields than the header.
    #[error("{source_name}:{line}: {found} fields, the header has {expected}")]
    FieldCount {
        /// The file.
        source_name: String,
        /// The line.
        line: usize,
        /// Fields in the header.
        expected: usize,
        /// Fields in the row.
        found: usize,
    },
    /// A field is not a number.
    #[error("{source_name}:{line}: column `{column}`: `{text}` is not a number")]
    NotANumber {
        /// The file.
        source_name: String,
        /// The line.
        line: usize,
        /// The column.
        column: String,
        /// The field.
        text: String,
    },
    /// A field is NaN or infinite.
    #[error("{source_name}:{line}: column `{column}`: {value} is not finite")]
    NonFinite {
        /// The file.
        source_name: String,
        /// The line.
        line: usize,
        /// The column.
        column: String,
        /// The value.
        value: f64,
    },
    /// The time does not increase strictly.
    #[error("{source_name}:{line}: time {time} does not increase (previous row: {previous})")]
    NonMonotonicTime {
        /// The file.
        source_name: String,
        /// The line.
        line: usize,
        /// This row's time.
        time: f64,
        /// The previous row's time.
        previous: f64,
    },
}

impl FreeMotionError {
    /// The 1-based line of the problem, when it has one.
    pub fn line(&self) -> Option<usize> {
        match self {
            FreeMotionError::MissingColumn { line, .. }
            | FreeMotionError::FieldCount { line, .. }
            | FreeMotionError::NotANumber { line, .. }
            | FreeMotionError::NonFinite { line, .. }
            | FreeMotionError::NonMonotonicTime { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// Validated free-motion samples; every per-joint signal is row-major, `samples x joints`.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeMotionData {
    /// Joint names, in the order of the `q.*` columns.
    pub joints: Vec<String>,
    /// Sample times (s), strictly increasing.
    pub t: Vec<f64>,
    /// Positions.
    pub q: Vec<f64>,
    /// Velocities.
    pub qdot: Vec<f64>,
    /// Accelerations.
    pub qddot: Vec<f64>,
    /// Joint torques (the commanded torque, filtered as the run-time observer sees it).
    pub tau: Vec<f64>,
}

impl FreeMotionData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Reads and validates a file.
    pub fn load(path: &Path) -> Result<Self, FreeMotionError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| FreeMotionError::Io {
            source_name: name.clone(),
            message: e.to_string(),
        })?;
        Self::parse(&text, &name)
    }

    /// Validates CSV text; `source_name` names it in errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, FreeMotionError> {
        let src = || source_name.to_string();
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (header_idx, header) = lines.next().ok_or_else(|| FreeMotionError::Empty {
            source_name: src(),
            message: "empty file (no header)".into(),
        })?;
        let header_line = header_idx + 1;
        let columns: Vec<&str> = header.split(',').map(str::trim).collect();
        let find = |name: &str| -> Result<usize, FreeMotionError> {
            columns
                .iter()
                .position(|c| *c == name)
                .ok_or_else(|| FreeMotionError::MissingColumn {
                    source_name: src(),
                    line: header_line,
                    column: name.to_string(),
                })
        };
        let t_col = find("t")?;
        let joints: Vec<String> = columns
            .iter()
            .filter_map(|c| c.strip_prefix("q."))
            .map(String::from)
            .collect();
        if joints.is_empty() {
            return Err(FreeMotionError::MissingColumn {
                source_name: src(),
                line: header_line,
                column: "q.<joint>".into(),
            });
        }
        let n = joints.len();
        // Column index per (signal, joint).
        let mut idx = Vec::with_capacity(4 * n);
        for prefix in ["q", "qdot", "qddot", "tau"] {
            for j in &joints {
                idx.push(find(&format!("{prefix}.{j}"))?);
            }
        }
        let mut data = FreeMotionData {
            joints,
            t: Vec::new(),
            q: Vec::new(),
            qdot: Vec::new(),
            qddot: Vec::new(),
            tau: Vec::new(),
        };
        let mut fields: Vec<f64> = vec![0.0; columns.len()];
        for (k, line) in lines {
            let line_no = k + 1;
            let parts: Vec<&str> = line.split(',').collect();
            if parts.len() != columns.len() {
                return Err(FreeMotionError::FieldCount {
                    source_name: src(),
                    line: line_no,
                    expected: columns.len(),
                    found: parts.len(),
                });
            }
            for (c, part) in parts.iter().enumerate() {
                let text = part.trim();
                let v: f64 = text.parse().map_err(|_| FreeMotionError::NotANumber {
                    source_name: src(),
                    line: line_no,
                    column: columns[c].to_string(),
                    text: text.to_string(),
                })?;
                if !v.is_finite() {
                    return Err(FreeMotionError::NonFinite {
                        source_name: src(),
                        line: line_no,
                        column: columns[c].to_string(),
                        value: v,
                    });
                }
                fields[c] = v;
            }
            let t = fields[t_col];
            if let Some(&previous) = data.t.last() {
                if t <= previous {
                    return Err(FreeMotionError::NonMonotonicTime {
                        source_name: src(),
                        line: line_no,
                        time: t,
                        previous,
                    });
                }
            }
            data.t.push(t);
            for (s, out) in [&mut data.q, &mut data.qdot, &mut data.qddot, &mut data.tau]
                .into_iter()
                .enumerate()
            {
                out.extend(idx[s * n..(s + 1) * n].iter().map(|&c| fields[c]));
            }
        }
        if data.t.is_empty() {
            return Err(FreeMotionError::Empty {
                source_name: src(),
                message: "no data rows after the header".into(),
            });
        }
        Ok(data)
    }
}

/// The training arrays of a learned observer from free-motion data: inputs `[q, qdot,
/// qddot]` (row-major, `3n` per row) and torques (`n` per row), through the conditioning
/// stage when `input_filter_hz > 0` (exactly as the scenario runner feeds the observer at
/// run time), else as recorded. The sample rate is the data's mean rate.
pub fn observer_training_arrays(
    data: &FreeMotionData,
    input_filter_hz: f64,
) -> Result<(Vec<f64>, Vec<f64>), admittance_sim::SimError> {
    let n = data.dof();
    let mut x = Vec::with_capacity(data.len() * 3 * n);
    let mut y = Vec::with_capacity(data.len() * n);
    if input_filter_hz > 0.0 {
        let span = data.t.last().copied().unwrap_or(0.0) - data.t.first().copied().unwrap_or(0.0);
        let rate = if data.len() > 1 && span > 0.0 {
            (data.len() - 1) as f64 / span
        } else {
            0.0
        };
        let mut c = admittance_sim::InputConditioner::new(n, input_filter_hz, rate)?;
        for k in 0..data.len() {
            let r = k * n..(k + 1) * n;
            c.update(&data.q[r.clone()], &data.tau[r]);
            for s in [&c.q, &c.qdot, &c.qddot] {
                x.extend_from_slice(s);
            }
            y.extend_from_slice(&c.tau);
        }
    } else {
        for k in 0..data.len() {
            for s in [&data.q, &data.qdot, &data.qddot] {
                x.extend_from_slice(&s[k * n..(k + 1) * n]);
            }
        }
        y.extend_from_slice(&data.tau);
    }
    Ok((x, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "t,q.a,q.b,qdot.a,qdot.b,qddot.a,qddot.b,tau.a,tau.b";

    fn parse(body: &str) -> Result<FreeMotionData, FreeMotionError> {
        FreeMotionData::parse(body, "x.csv")
    }

    #[test]
    fn reads_a_valid_file() {
        let text = format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0.001,1.5,2,3,4,5,6,7,-8e-1\n");
        let d = parse(&text).unwrap();
        assert_eq!(d.joints, ["a", "b"]);
        assert_eq!(d.len(), 2);
        assert_eq!(d.q, [1.0, 2.0, 1.5, 2.0]);
        assert_eq!(d.tau, [7.0, 8.0, 7.0, -0.8]);
        // Column order does not matter, extra columns are ignored.
        let text = "tau.a,q.a,qddot.a,extra,t,qdot.a\n1,2,3,4,0,5\n";
        let d = parse(text).unwrap();
        assert_eq!(
            (d.q[0], d.qdot[0], d.qddot[0], d.tau[0]),
            (2.0, 5.0, 3.0, 1.0)
        );
    }

    #[test]
    fn missing_column_names_it_and_the_header_line() {
        let err = parse("t,q.a,qdot.a,qddot.a\n0,1,2,3\n").unwrap_err();
        assert!(
            matches!(&err, FreeMotionError::MissingColumn { column, line: 1, .. } if column == "tau.a"),
            "{err}"
        );
        assert!(
            err.to_string().contains("x.csv:1: missing column `tau.a`"),
            "{err}"
        );
        let err = parse("q.a,qdot.a,qddot.a,tau.a\n1,2,3,4\n").unwrap_err();
        assert!(matches!(&err, FreeMotionError::MissingColumn { column, .. } if column == "t"));
        let err = parse("t,tau.a\n0,1\n").unwrap_err();
        assert!(matches!(&err, FreeMotionError::MissingColumn { .. }));
    }

    #[test]
    fn non_number_names_line_and_column() {
        let text = format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0.001,1,2,3,abc,5,6,7,8\n");
        let err = parse(&text).unwrap_err();
        assert_eq!(err.line(), Some(3));
        assert!(
            err.to_string()
                .contains("x.csv:3: column `qdot.b`: `abc` is not a number"),
            "{err}"
        );
        let text = format!("{HEADER}\n0,1,2,3,4,5,6,7,\n");
        assert!(matches!(
            parse(&text).unwrap_err(),
            FreeMotionError::NotANumber { line: 2, .. }
        ));
    }

    #[test]
    fn non_finite_is_rejected() {
        for bad in ["NaN", "inf", "-inf", "1e400"] {
            let text = format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0.001,1,2,3,4,{bad},6,7,8\n");
            let err = parse(&text).unwrap_err();
            assert!(
                matches!(&err, FreeMotionError::NonFinite { line: 3, column, .. } if column == "qddot.a"),
                "{bad}: {err}"
            );
        }
    }

    #[test]
    fn non_monotonic_time_is_rejected() {
        let text =
            format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0.002,1,2,3,4,5,6,7,8\n0.001,1,2,3,4,5,6,7,8\n");
        let err = parse(&text).unwrap_err();
        assert!(
            matches!(err, FreeMotionError::NonMonotonicTime { line: 4, .. }),
            "{err}"
        );
        let text = format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0,1,2,3,4,5,6,7,8\n");
        assert!(matches!(
            parse(&text).unwrap_err(),
            FreeMotionError::NonMonotonicTime { line: 3, .. }
        ));
    }

    #[test]
    fn wrong_field_count_and_empty_files() {
        let text = format!("{HEADER}\n0,1,2,3,4,5,6,7\n");
        assert!(matches!(
            parse(&text).unwrap_err(),
            FreeMotionError::FieldCount {
                line: 2,
                expected: 9,
                found: 8,
                ..
            }
        ));
        assert!(matches!(
            parse("").unwrap_err(),
            FreeMotionError::Empty { .. }
        ));
        assert!(matches!(
            parse(HEADER).unwrap_err(),
            FreeMotionError::Empty { .. }
        ));
        assert!(matches!(
            FreeMotionData::load(Path::new("/nonexistent/x.csv")).unwrap_err(),
            FreeMotionError::Io { .. }
        ));
    }
}
