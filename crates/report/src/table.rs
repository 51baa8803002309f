//! A time-series table read from a run folder's CSV (`VARIANT.csv`, `free_motion.csv`):
//! named columns of numbers, stored column by column.

use std::path::Path;

use crate::ReportError;

/// Named numeric columns of equal length, in file order.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// Column names (the CSV header).
    pub columns: Vec<String>,
    /// The values, one vector per column, each `rows()` long.
    pub data: Vec<Vec<f64>>,
}

impl Table {
    /// Builds a table from names and column vectors (all the same length).
    pub fn from_columns(columns: Vec<String>, data: Vec<Vec<f64>>) -> Self {
        debug_assert_eq!(columns.len(), data.len());
        Self { columns, data }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }

    /// The column called `name`, if present.
    pub fn col(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c == name)
            .map(|k| self.data[k].as_slice())
    }

    /// Whether a column called `name` exists.
    pub fn has(&self, name: &str) -> bool {
        self.columns.iter().any(|c| c == name)
    }

    /// Parses CSV text (a header row, then rows of numbers); `source` names the file in
    /// errors. Every row must have the header's number of fields and every field must be a
    /// number (`NaN` and `inf` are accepted: the runner writes them as such).
    pub fn parse(text: &str, source: &str) -> Result<Self, ReportError> {
        Self::parse_columns(text, source, &|_| true)
    }

    /// Like [`parse`](Self::parse), keeping only the columns whose name passes `keep` (the
    /// others are checked for count, not parsed).
    pub fn parse_columns(
        text: &str,
        source: &str,
        keep: &dyn Fn(&str) -> bool,
    ) -> Result<Self, ReportError> {
        let bad = |message: String| ReportError::Input {
            path: source.to_string(),
            message,
        };
        let mut lines = text.lines();
        let header = lines
            .next()
            .filter(|h| !h.trim().is_empty())
            .ok_or_else(|| {
                bad("empty file: expected a header row such as `t,q.JOINT,...`".into())
            })?;
        let columns: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        if let Some(k) = columns.iter().position(String::is_empty) {
            return Err(bad(format!("line 1: column {} has an empty name", k + 1)));
        }
        let kept: Vec<bool> = columns.iter().map(|c| keep(c)).collect();
        let mut data: Vec<Vec<f64>> = vec![Vec::new(); columns.len()];
        for (k, line) in lines.enumerate() {
            let line_no = k + 2;
            if line.trim().is_empty() {
                continue;
            }
            let mut count = 0;
            for (c, field) in line.split(',').enumerate() {
                if c >= columns.len() || !kept[c] {
                    count = c + 1;
                    continue;
                }
                let v: f64 = field.trim().parse().map_err(|_| {
                    bad(format!(
                        "line {line_no}, column {} (`{}`): '{}' is not a number",
                        c + 1,
                        columns[c],
                        field.trim()
                    ))
                })?;
                data[c].push(v);
                count = c + 1;
            }
            if count != columns.len() {
                return Err(bad(format!(
                    "line {line_no}: {count} fields, the header has {}; the file is truncated or corrupted (regenerate it with `admittance run`)",
                    columns.len()
                )));
            }
        }
        let (columns, data) = columns
            .into_iter()
            .zip(data)
            .zip(kept)
            .filter_map(|(cd, k)| k.then_some(cd))
            .unzip();
        Ok(Self { columns, data })
    }

    /// Reads and parses a CSV file.
    pub fn load(path: &Path) -> Result<Self, ReportError> {
        Self::load_columns(path, &|_| true)
    }

    /// Reads a CSV file, keeping the columns that pass `keep`.
    pub fn load_columns(path: &Path, keep: &dyn Fn(&str) -> bool) -> Result<Self, ReportError> {
        let text = admittance_files::read_regular_text(path, admittance_files::DATA_LIMIT)
            .map_err(|e| ReportError::Input {
                path: path.display().to_string(),
                message: format!("cannot read: {e}"),
            })?;
        Self::parse_columns(&text, &path.display().to_string(), keep)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_columns() {
        let t = Table::parse("t,q.a\n0,1.5\n0.1,NaN\n", "x.csv").unwrap();
        assert_eq!(t.rows(), 2);
        assert_eq!(t.col("t").unwrap(), &[0.0, 0.1]);
        assert!(t.col("q.a").unwrap()[1].is_nan());
        assert!(t.col("q.b").is_none());
    }

    #[test]
    fn rejects_short_rows_and_text() {
        let e = Table::parse("t,q.a\n0,1\n0.1\n", "x.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.csv") && e.contains("line 3"), "{e}");
        let e = Table::parse("t,q.a\n0,abc\n", "x.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 2") && e.contains("q.a") && e.contains("abc"),
            "{e}"
        );
        let e = Table::parse("t,q.a\n0,1,2\n", "x.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 fields"), "{e}");
        assert!(Table::parse("", "x.csv").is_err());
        let t = Table::parse_columns("t,q.a,tau.a\n0,1,x\n", "x.csv", &|c| c != "tau.a").unwrap();
        assert_eq!(t.columns, ["t", "q.a"]);
        assert!(Table::parse_columns("t,q.a,tau.a\n0,1\n", "x.csv", &|c| c != "tau.a").is_err());
    }
}
