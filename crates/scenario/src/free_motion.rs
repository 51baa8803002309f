//! Free-motion data (docs/method.md section 5): what the sensors saw while the arm moved without
//! contact, the training data of the learned observer. The format is the one the runner
//! writes with `[record] free_motion_csv = true` and the one a user exports from a real arm
//! (docs/outputs.md, "free_motion.csv"):
//!
//! ```text
//! t,q.J1,...,q.Jn,qdot.J1,...,qdot.Jn,qddot.J1,...,qddot.Jn,tau.J1,...,tau.Jn
//! ```
//!
//! one row per control sample, comma separated (no quoting), a header naming the columns.
//! The columns may come in any order and extra columns (of any content, text included)
//! are ignored: only `t` and the `q`, `qdot`, `qddot`, `tau` columns of the joints are
//! read. A file may leave out `qdot` or `qddot` for every joint: they are then taken by
//! backward differences ([`DERIVED_NOTE`], `FreeMotionData::derived`).
//! [`FreeMotionData::parse`] takes the joints in the order of the `q.*` columns;
//! [`FreeMotionData::parse_joints`] / [`FreeMotionData::load_joints`] take the joints the
//! caller names (an arm's chain order), so that a file whose columns are shuffled gives
//! the same data. Every row is validated and the first problem is reported with its
//! 1-based line number and the column: a missing or repeated column, a row with the wrong
//! number of fields, a field that is not a number, a non-finite value, a signal beyond
//! +-[`MAX_ABS_VALUE`], a time that does not increase strictly.

use std::path::Path;

mod derivatives;
mod layout;
mod wrapped;

use layout::Layout;

/// Largest magnitude of a `q`, `qdot`, `qddot` or `tau` value: 10^12 (the bound of the
/// learning crate's data sets, `admittance_learning::broad::MAX_ABS_DATA_VALUE`). No joint
/// signal in SI units comes near it: a value beyond is a unit error or a corrupted field,
/// and it would overflow the sums of squares of a fit.
pub const MAX_ABS_VALUE: f64 = 1e12;

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
    /// The signals' units disagree (the time column against the velocities).
    #[error("{source_name}: {message}")]
    Units {
        /// The file.
        source_name: String,
        /// What disagrees, by how much, and the fix.
        message: String,
    },
    /// The header is not a comma-separated list of names.
    #[error("{source_name}:{line}: {message}")]
    Header {
        /// The file.
        source_name: String,
        /// The header line.
        line: usize,
        /// What is wrong, and the fix.
        message: String,
    },
    /// A required column is absent from the header.
    #[error("{source_name}:{line}: missing column `{column}` (need t, and q.J, tau.J and qdot.J, qddot.J for every joint J: the arm's joints, or those of the q.J columns; qdot or qddot left out for every joint is taken by differences)")]
    MissingColumn {
        /// The file.
        source_name: String,
        /// The header line.
        line: usize,
        /// The column.
        column: String,
    },
    /// A column the loader reads appears more than once in the header.
    #[error("{source_name}:{line}: column `{column}` appears more than once (fields {first} and {second})")]
    RepeatedColumn {
        /// The file.
        source_name: String,
        /// The header line.
        line: usize,
        /// The column.
        column: String,
        /// 1-based field number of its first occurrence.
        first: usize,
        /// 1-based field number of the repetition.
        second: usize,
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
    #[error("{source_name}:{line}: column `{column}`: {value} is not finite (repair the row or leave it out)")]
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
    /// A joint signal beyond +-[`MAX_ABS_VALUE`].
    #[error("{source_name}:{line}: column `{column}`: {value:e} is beyond +-{limit:e} (a unit error or a corrupted value?)")]
    OutOfRange {
        /// The file.
        source_name: String,
        /// The line.
        line: usize,
        /// The column.
        column: String,
        /// The value.
        value: f64,
        /// The limit, [`MAX_ABS_VALUE`].
        limit: f64,
    },
    /// The time does not increase strictly.
    #[error("{source_name}:{line}: time {time} does not increase (previous row: {previous}): each row needs a later time than the one before (remove a repeated row)")]
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
            | FreeMotionError::RepeatedColumn { line, .. }
            | FreeMotionError::OutOfRange { line, .. }
            | FreeMotionError::FieldCount { line, .. }
            | FreeMotionError::NotANumber { line, .. }
            | FreeMotionError::NonFinite { line, .. }
            | FreeMotionError::NonMonotonicTime { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// Validated free-motion samples; every per-joint signal is row-major, `samples x joints`.
#[derive(Clone, Debug, Default, PartialEq)]
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
    /// The derivatives the file left out for every joint (`"qdot"`, `"qddot"`), taken as
    /// backward differences over the time column ([`DERIVED_NOTE`]); empty when it has them.
    pub derived: Vec<String>,
    /// Joints whose angle the file gave wrapped within one turn, put back on one branch
    /// (the loader's `unwrap_turns`; the caller may say so); empty when none.
    pub unwrapped: Vec<String>,
}

/// How the loader fills the derivatives a file leaves out: as the conditioning stage and
/// `admittance import` take them. The first rows, with no earlier sample, are dropped.
pub const DERIVED_NOTE: &str =
    "taken as backward differences (qdot of q, qddot of qdot) over the time column, the first rows dropped";

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

    /// Reads and validates a file; the joints are those of the `q.*` columns, in their
    /// order.
    pub fn load(path: &Path) -> Result<Self, FreeMotionError> {
        Self::load_impl(path, None)
    }

    /// Reads and validates a file for the given joints, in the given order (an arm's
    /// chain order): the file's column order does not matter, columns of other joints are
    /// ignored, a missing one is named.
    pub fn load_joints<S: AsRef<str>>(path: &Path, joints: &[S]) -> Result<Self, FreeMotionError> {
        let joints: Vec<&str> = joints.iter().map(AsRef::as_ref).collect();
        Self::load_impl(path, Some(&joints))
    }

    fn load_impl(path: &Path, joints: Option<&[&str]>) -> Result<Self, FreeMotionError> {
        let name = path.display().to_string();
        let text = admittance_files::read_regular_text(path, admittance_files::DATA_LIMIT)
            .map_err(|e| FreeMotionError::Io {
                source_name: name.clone(),
                message: e.to_string(),
            })?;
        Self::parse_impl(&text, &name, joints)
    }

    /// The derivatives (`"qdot"`, `"qddot"`) the header of the file at `path` leaves out for
    /// `joints` (the `q.*` columns' joints when `None`): those the loader will take by
    /// differences. Reads the header alone, of a regular file only (a FIFO never blocks it);
    /// empty when it cannot be read or has a problem, which loading the file then names.
    pub fn derivatives_left_out<S: AsRef<str>>(path: &Path, joints: Option<&[S]>) -> Vec<String> {
        use std::io::BufRead;
        let Ok(file) = admittance_files::open_regular(path, admittance_files::DATA_LIMIT) else {
            return Vec::new();
        };
        let header = std::io::BufReader::new(std::io::Read::take(file, 1 << 20))
            .lines()
            .map_while(Result::ok)
            .find(|l| !l.trim().is_empty());
        let joints: Option<Vec<&str>> = joints.map(|j| j.iter().map(AsRef::as_ref).collect());
        header
            .and_then(|h| {
                Layout::from_header(&h, 1, "", joints.as_deref())
                    .ok()
                    .map(|l| l.derived.iter().map(|d| d.to_string()).collect())
            })
            .unwrap_or_default()
    }

    /// Validates CSV text; `source_name` names it in errors. The joints are those of the
    /// `q.*` columns, in their order.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, FreeMotionError> {
        Self::parse_impl(text, source_name, None)
    }

    /// Validates CSV text for the given joints, in the given order (as
    /// [`load_joints`](Self::load_joints)).
    pub fn parse_joints<S: AsRef<str>>(
        text: &str,
        source_name: &str,
        joints: &[S],
    ) -> Result<Self, FreeMotionError> {
        let joints: Vec<&str> = joints.iter().map(AsRef::as_ref).collect();
        Self::parse_impl(text, source_name, Some(&joints))
    }

    fn parse_impl(
        text: &str,
        source_name: &str,
        joints: Option<&[&str]>,
    ) -> Result<Self, FreeMotionError> {
        let src = || source_name.to_string();
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (header_idx, header) = lines.next().ok_or_else(|| FreeMotionError::Empty {
            source_name: src(),
            message: "empty file (no header)".into(),
        })?;
        let layout = Layout::from_header(header, header_idx + 1, source_name, joints)?;
        let mut data = FreeMotionData {
            joints: layout.joints.clone(),
            t: Vec::new(),
            q: Vec::new(),
            qdot: Vec::new(),
            qddot: Vec::new(),
            tau: Vec::new(),
            derived: layout.derived.iter().map(|d| d.to_string()).collect(),
            unwrapped: Vec::new(),
        };
        // The rows parsed in two contiguous stretches side by side (a 60 s recording at 1 kHz
        // is 35 MB of text), joined in order.
        let rows: Vec<(usize, &str)> = lines.collect();
        let stretches = admittance_dynamics::parallel_map(
            &[0, 1].map(|part| (part * rows.len() / 2, (part + 1) * rows.len() / 2)),
            |&(from, to)| layout.parse_rows(&rows[from..to], source_name),
        );
        // In the file's order: the seam before a stretch's own first problem.
        for stretch in stretches {
            if let (Some(&previous), Some(&t)) = (data.t.last(), stretch.t.first()) {
                if t <= previous {
                    return Err(FreeMotionError::NonMonotonicTime {
                        source_name: src(),
                        line: stretch.first_line,
                        time: t,
                        previous,
                    });
                }
            }
            if let Some(problem) = stretch.problem {
                return Err(problem);
            }
            data.t.extend(stretch.t);
            data.q.extend(stretch.q);
            data.qdot.extend(stretch.qdot);
            data.qddot.extend(stretch.qddot);
            data.tau.extend(stretch.tau);
        }
        if data.t.is_empty() {
            return Err(FreeMotionError::Empty {
                source_name: src(),
                message: "no data rows after the header".into(),
            });
        }
        data.unwrap_turns();
        data.take_differences();
        data.check_velocities(source_name)?;
        if data.t.is_empty() {
            return Err(FreeMotionError::Empty {
                source_name: src(),
                message: format!(
                    "no {} columns and too few rows to take them by differences (3 rows at least)",
                    data.derived.join(" and ")
                ),
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
) -> Result<(Vec<f64>, Vec<f64>), admittance_loop::LoopError> {
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
        let mut c = admittance_loop::InputConditioner::new(n, input_filter_hz, rate)?;
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

    pub(super) const HEADER: &str = "t,q.a,q.b,qdot.a,qdot.b,qddot.a,qddot.b,tau.a,tau.b";

    pub(super) fn parse(body: &str) -> Result<FreeMotionData, FreeMotionError> {
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

    /// Rebuilds `text` with its columns in the order `order` (indices of the header).
    fn reorder(text: &str, order: &[usize]) -> String {
        text.lines()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                order.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",")
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn shuffled_columns_give_the_same_data() {
        let text =
            format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0.001,1.5,2.5,3.5,4.5,5.5,6.5,7.5,-8e-1\n");
        let straight = parse(&text).unwrap();
        // Every column reversed: the joints' own columns too (q.b before q.a).
        let shuffled = reorder(&text, &[8, 7, 6, 5, 4, 3, 2, 1, 0]);
        assert!(shuffled.starts_with("tau.b,tau.a,"), "{shuffled}");
        let by_name = FreeMotionData::parse_joints(&shuffled, "x.csv", &["a", "b"]).unwrap();
        assert_eq!(by_name, straight);
        // Without names the q columns set the order: b before a.
        assert_eq!(parse(&shuffled).unwrap().joints, ["b", "a"]);
        // Naming the joints also selects them (a file holding both arms).
        let only_b = FreeMotionData::parse_joints(&text, "x.csv", &["b"]).unwrap();
        assert_eq!(
            (only_b.q.as_slice(), only_b.tau.as_slice()),
            (&[2.0, 2.5][..], &[8.0, -0.8][..])
        );
    }

    #[test]
    fn extra_columns_of_any_content_are_ignored() {
        let text = format!(
            "note,{HEADER},index\nstart,0,1,2,3,4,5,6,7,8,0x1\n,0.001,1,2,3,4,5,6,7,8,NaN\n"
        );
        let d = parse(&text).unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(d.tau, [7.0, 8.0, 7.0, 8.0]);
        // A repeated column that is read is ambiguous: an error naming both fields.
        let err = parse(&format!("{HEADER},q.b\n0,1,2,3,4,5,6,7,8,9\n")).unwrap_err();
        assert!(
            err.to_string()
                .contains("x.csv:1: column `q.b` appears more than once (fields 3 and 10)"),
            "{err}"
        );
        // A named joint that the file lacks is a missing column.
        let err = FreeMotionData::parse_joints(&text, "x.csv", &["a", "c"]).unwrap_err();
        assert!(
            err.to_string().contains("x.csv:1: missing column `q.c`"),
            "{err}"
        );
    }

    #[test]
    fn values_beyond_the_limit_name_line_and_column() {
        let text = format!("{HEADER}\n0,1,2,3,4,5,6,7,8\n0.001,1,2,3,4,5,6,7,1e300\n");
        let err = parse(&text).unwrap_err();
        assert!(
            matches!(&err, FreeMotionError::OutOfRange { line: 3, column, .. } if column == "tau.b"),
            "{err}"
        );
        assert!(
            err.to_string().contains("x.csv:3: column `tau.b`: 1e300"),
            "{err}"
        );
        // At the limit is accepted; the time is not limited.
        let text = format!("{HEADER}\n1e15,1,2,3,4,5,6,7,1e12\n");
        assert_eq!(parse(&text).unwrap().tau[1], 1e12);
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
    fn a_long_file_keeps_its_order_and_names_the_line_of_an_error_in_either_stretch() {
        // The rows are parsed in two stretches side by side: they come back in the file's
        // order, and an error names its line before, after and at the seam (row 50 of 101).
        let row = |k: usize| format!("{},{k},1,2,3,4,5,6,7", k as f64 * 0.001);
        let mut lines: Vec<String> = (0..101).map(row).collect();
        // A blank line is skipped but counted: `lines[i]` is line i + 2 (after the header).
        lines.insert(30, String::new());
        let text = |lines: &[String]| format!("{HEADER}\n{}\n", lines.join("\n"));
        let data = parse(&text(&lines)).unwrap();
        assert_eq!(data.len(), 101);
        assert!(data.q.chunks(2).enumerate().all(|(k, q)| q[0] == k as f64));
        assert!(data.t.windows(2).all(|w| w[0] < w[1]));
        for index in [11, 51, 101] {
            let mut broken = lines.clone();
            broken[index] = broken[index].replace(",1,2,3,", ",x,2,3,");
            let err = parse(&text(&broken)).unwrap_err();
            assert!(
                matches!(&err, FreeMotionError::NotANumber { line, column, .. } if *line == index + 2 && column == "q.b"),
                "{index}: {err}"
            );
        }
        // Row 50 (`lines[51]`) opens the second stretch: its time equal to row 49's.
        let mut seam = lines.clone();
        seam[51] = seam[51].replacen("0.05,", "0.049,", 1);
        let err = parse(&text(&seam)).unwrap_err();
        assert!(
            matches!(err, FreeMotionError::NonMonotonicTime { line: 53, .. }),
            "{err}"
        );
        // The seam is told before a later problem of the second stretch: the file's first.
        seam[80] = seam[80].replace(",1,2,3,", ",x,2,3,");
        let err = parse(&text(&seam)).unwrap_err();
        assert!(
            matches!(err, FreeMotionError::NonMonotonicTime { line: 53, .. }),
            "{err}"
        );
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
