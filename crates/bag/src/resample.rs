//! From the decoded series to the table: a common time grid at a fixed rate, linear
//! interpolation, and the derivatives by backward differences (as the observers'
//! conditioning differentiates, `admittance_sim::InputConditioner`).

use std::path::Path;

use crate::error::BagError;
use crate::extract::Series;

/// The free-motion table: per joint signals are row-major `rows x joints`.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Joint names.
    pub joints: Vec<String>,
    /// Absolute stamps of the rows, ns since the epoch.
    pub stamps_ns: Vec<i64>,
    /// Time from the first row (s).
    pub t: Vec<f64>,
    /// Angles.
    pub q: Vec<f64>,
    /// Velocities.
    pub qdot: Vec<f64>,
    /// Accelerations.
    pub qddot: Vec<f64>,
    /// Torques.
    pub tau: Vec<f64>,
    /// Label columns (names without the `label.` prefix) and values, row-major.
    pub label: Option<(Vec<String>, Vec<f64>)>,
}

impl Table {
    /// Rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// The median spacing of increasing stamps (ns), `None` with fewer than two.
pub fn median_period_ns(stamps: &[i64]) -> Option<i64> {
    let mut d: Vec<i64> = stamps
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .collect();
    if d.is_empty() {
        return None;
    }
    d.sort_unstable();
    Some(d[d.len() / 2])
}

/// Gaps longer than 10 median periods: (start ns, length ns).
pub fn gaps(stamps: &[i64]) -> Vec<(i64, i64)> {
    let Some(p) = median_period_ns(stamps) else {
        return Vec::new();
    };
    stamps
        .windows(2)
        .filter(|w| w[1].saturating_sub(w[0]) > p.saturating_mul(10))
        .map(|w| (w[0], w[1].saturating_sub(w[0])))
        .collect()
}

/// The grid period (ns): `1e9 / rate` rounded, or the `q` series' median spacing.
pub fn period_ns(bag: &Path, q: &Series, rate_hz: Option<f64>) -> Result<i64, BagError> {
    let data = |message: String| BagError::Data {
        bag: bag.to_path_buf(),
        message,
    };
    match rate_hz {
        Some(r) if !(r.is_finite() && r > 0.0 && r <= 1e9) => Err(data(format!(
            "rate {r} Hz: give a positive rate up to 1e9 Hz"
        ))),
        Some(r) => Ok((1e9 / r).round() as i64),
        None => median_period_ns(&q.stamps).ok_or_else(|| {
            data(format!(
                "topic `{}` has {} usable message(s): too few for a rate",
                q.topic,
                q.stamps.len()
            ))
        }),
    }
}

/// The series with each column that reads as a wrapped angle (a continuous joint's, kept
/// within one turn by its driver: `admittance_dynamics::unwrap_turns`) put back on its first
/// sample's branch, and those columns' names (`q.J`): interpolated across a wrap, an angle
/// would pass through every value between the two readings.
pub fn unwrapped(s: &Series) -> (Series, Vec<String>) {
    let mut out = s.clone();
    let n = s.columns.len();
    let mut names = Vec::new();
    for (i, column) in s.columns.iter().enumerate() {
        let seconds = |k: usize| s.stamps[k].saturating_sub(s.stamps[k - 1]) as f64 * 1e-9;
        if admittance_dynamics::unwrap_turns(&mut out.values, n, i, seconds) {
            names.push(format!("q.{column}"));
        }
    }
    (out, names)
}

/// Samples a series at the grid stamps (inside its span) by linear interpolation; a grid
/// stamp equal to a sample's stamp gives that sample exactly.
pub fn interpolate(s: &Series, grid: &[i64]) -> Vec<f64> {
    let n = s.columns.len();
    let mut out = Vec::with_capacity(grid.len() * n);
    let mut i = 0;
    for &t in grid {
        while i + 1 < s.stamps.len() && s.stamps[i + 1] <= t {
            i += 1;
        }
        let a = &s.values[i * n..(i + 1) * n];
        if s.stamps[i] == t || i + 1 >= s.stamps.len() {
            out.extend_from_slice(a);
            continue;
        }
        let b = &s.values[(i + 1) * n..(i + 2) * n];
        let span = i128::from(s.stamps[i + 1]) - i128::from(s.stamps[i]);
        let w = (i128::from(t) - i128::from(s.stamps[i])) as f64 / span as f64;
        out.extend(a.iter().zip(b).map(|(a, b)| a + (b - a) * w));
    }
    out
}

/// Backward differences of row-major `rows x n` values: row k is (x[k] - x[k-1]) / dt,
/// row 0 is NaN (no earlier sample; the caller drops it).
pub fn backward_difference(x: &[f64], n: usize, dt: f64) -> Vec<f64> {
    let mut out = vec![f64::NAN; x.len()];
    for k in n..x.len() {
        out[k] = (x[k] - x[k - n]) / dt;
    }
    out
}

/// The first grid point and the number of rows, in i128 (stamps from damaged data may be
/// anywhere in the i64 range); `None` when no grid point falls in the common span.
fn grid_span(bag: &Path, series: &[Series], period: i64) -> Result<Option<(i128, i128)>, BagError> {
    if let Some(s) = series.iter().find(|s| s.stamps.is_empty()) {
        return Err(BagError::Data {
            bag: bag.to_path_buf(),
            message: format!("{} `{}` has no sample", s.role, s.topic),
        });
    }
    let anchor = series.first().map_or(0, |s| s.stamps[0]);
    let start = series.iter().map(|s| s.stamps[0]).max().unwrap_or(0);
    let end = series
        .iter()
        .map(|s| *s.stamps.last().unwrap_or(&0))
        .min()
        .unwrap_or(0);
    if end <= start {
        let spans: Vec<String> = series
            .iter()
            .map(|s| {
                let last = s.stamps.last().copied().unwrap_or(0);
                format!(
                    "{} `{}` covers {:.6} to {:.6} s",
                    s.role,
                    s.topic,
                    s.stamps[0] as f64 * 1e-9,
                    last as f64 * 1e-9
                )
            })
            .collect();
        return Err(BagError::Data {
            bag: bag.to_path_buf(),
            message: format!(
                "the signals share no time span ({}); are their stamps from different clocks?",
                spans.join("; ")
            ),
        });
    }
    // The first grid point at or after `start`.
    let (anchor, start, end, period) = (anchor as i128, start as i128, end as i128, period as i128);
    let first = anchor + (start - anchor + period - 1) / period * period;
    if first > end {
        return Ok(None);
    }
    Ok(Some((first, (end - first) / period + 1)))
}

/// The number of grid rows, computed without building the grid (for the memory budget).
pub fn grid_rows(bag: &Path, series: &[Series], period: i64) -> Result<usize, BagError> {
    Ok(grid_span(bag, series, period)?
        .map_or(0, |(_, rows)| usize::try_from(rows).unwrap_or(usize::MAX)))
}

/// The grid: the first series' (`q`'s) first stamp plus multiples of `period`, inside the
/// span common to all series (so at the `q` topic's own rate the grid is its stamps).
pub fn grid(bag: &Path, series: &[Series], period: i64) -> Result<Vec<i64>, BagError> {
    let Some((first, rows)) = grid_span(bag, series, period)? else {
        return Ok(Vec::new());
    };
    if rows > crate::budget::MAX_TABLE_VALUES as i128 {
        return Err(BagError::Data {
            bag: bag.to_path_buf(),
            message: format!("{rows} rows at this rate: choose a lower --rate"),
        });
    }
    let period = period as i128;
    Ok((0..rows).map(|k| (first + k * period) as i64).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(stamps: Vec<i64>, values: Vec<f64>) -> Series {
        Series {
            role: "q",
            topic: "/t".into(),
            field: "position".into(),
            columns: vec!["a".into()],
            stamps,
            values,
            time: Default::default(),
        }
    }

    #[test]
    fn interpolation_is_exact_on_samples_and_linear_between() {
        let s = series(vec![0, 10, 20], vec![1.0, 3.0, 7.0]);
        assert_eq!(
            interpolate(&s, &[0, 5, 10, 15, 20]),
            vec![1.0, 2.0, 3.0, 5.0, 7.0]
        );
    }

    #[test]
    fn median_gaps_and_differences() {
        assert_eq!(median_period_ns(&[0, 10, 20, 35, 45]), Some(10));
        assert_eq!(median_period_ns(&[5]), None);
        assert_eq!(gaps(&[0, 10, 20, 200, 210]), vec![(20, 180)]);
        let d = backward_difference(&[0.0, 1.0, 1.0, 3.0], 2, 0.5);
        assert!(d[0].is_nan() && d[1].is_nan());
        assert_eq!(&d[2..], &[2.0, 4.0]);
    }

    #[test]
    fn grid_needs_a_common_span() {
        let a = series(vec![0, 10, 20], vec![0.0; 3]);
        let b = series(vec![30, 40], vec![0.0; 2]);
        let e = grid(Path::new("x"), &[a.clone(), b], 10)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("share no time span") && e.contains("`/t`"),
            "{e}"
        );
        assert_eq!(
            grid(Path::new("x"), std::slice::from_ref(&a), 7).unwrap(),
            vec![0, 7, 14]
        );
        // Anchored on the first series: a later start skips to its next grid point.
        let c = series(vec![3, 13, 23], vec![0.0; 3]);
        assert_eq!(grid(Path::new("x"), &[a, c], 10).unwrap(), vec![10, 20]);
    }
}
