//! From a panel's data to what is drawn: the axis ranges and ticks, the points kept (long
//! series reduced, samples that cannot be drawn left out and counted) and the lines
//! clipped to the axes. Everything here is bounded: any finite or non-finite data give
//! finite ranges, at most a few dozen ticks and a few thousand points per line, so that
//! the plotting library never sees a range it cannot handle (it loops forever on huge or
//! degenerate ranges).

use crate::figures::Panel;

/// Values beyond +-LIMIT are not drawn (said so in the figure): no quantity of a run comes
/// near it, and anything within it maps to pixels exactly enough.
pub const LIMIT: f64 = 1e12;
/// Most points drawn per line: longer lines are reduced to the min and max of each of
/// `MAX_POINTS / 2` time buckets, which keeps every peak.
pub const MAX_POINTS: usize = 2400;
/// Target number of ticks on the x and y axes.
const X_TICKS: usize = 10;
const Y_TICKS: usize = 7;

/// A polyline in data coordinates.
pub type Polyline = Vec<(f64, f64)>;

/// One axis: its range and ticks.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Tick positions, inside the range.
    pub ticks: Vec<f64>,
    /// Distance between ticks (for labels).
    pub step: f64,
}

/// A panel ready to draw: axes, clipped lines and bands, the markers and spans that can be
/// drawn, and notes on what was left out.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The x axis.
    pub x: Axis,
    /// The y axis.
    pub y: Axis,
    /// Per line of the panel, its visible pieces.
    pub lines: Vec<Vec<Polyline>>,
    /// Per band, its polygons (clamped to the axes).
    pub bands: Vec<Vec<Polyline>>,
    /// Per horizontal marker, where it is drawn (`None`: not drawn).
    pub hlines: Vec<Option<f64>>,
    /// Per vertical marker, where it is drawn.
    pub vlines: Vec<Option<f64>>,
    /// Per span, the visible part.
    pub spans: Vec<Option<(f64, f64)>>,
    /// What the figure must say about data it could not show.
    pub notes: Vec<Note>,
}

/// A note of a panel on data it does not show.
#[derive(Clone, Debug, PartialEq)]
pub struct Note {
    /// The sentence.
    pub text: String,
    /// Data were left out because they cannot be drawn (non-finite, huge): a problem of
    /// the data, which the report warns about. Otherwise a choice of the figure (a
    /// transient clipped by an axis sized to the evaluation window).
    pub left_out: bool,
}

fn drawable(v: f64) -> bool {
    v.is_finite() && v.abs() <= LIMIT
}

/// Indices of the points of `x` to draw within `range`: all of them when few, else the
/// first, the last and the minimum and maximum of `y` in each bucket, in order. `x` is
/// expected sorted; unsorted or non-finite times give a valid (if partial) selection.
pub fn decimate(x: &[f64], y: &[f64], range: (f64, f64), max_points: usize) -> Vec<usize> {
    let n = x.len().min(y.len());
    // One point either side of the range so that lines reach the axes.
    let start = x[..n].partition_point(|&v| v < range.0).saturating_sub(1);
    let end = (x[..n].partition_point(|&v| v <= range.1) + 1).min(n);
    if start >= end {
        return Vec::new();
    }
    let count = end - start;
    if count <= max_points {
        return (start..end).collect();
    }
    let buckets = (max_points / 2).max(1);
    let mut out = Vec::with_capacity(buckets * 2 + 2);
    for b in 0..buckets {
        let lo = start + count * b / buckets;
        let hi = (start + count * (b + 1) / buckets).max(lo + 1);
        let (mut imin, mut imax) = (lo, lo);
        for k in lo..hi {
            if y[k] < y[imin] || !y[imin].is_finite() {
                imin = k;
            }
            if y[k] > y[imax] || !y[imax].is_finite() {
                imax = k;
            }
        }
        let (a, b2) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        out.push(a);
        if b2 != a {
            out.push(b2);
        }
    }
    out
}

/// A range that the axis can show: finite, within +-LIMIT, wider than zero and than the
/// rounding of its values.
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = (lo.clamp(-LIMIT, LIMIT), hi.clamp(-LIMIT, LIMIT));
    let magnitude = lo.abs().max(hi.abs());
    let min_width = (1e-9 * magnitude).max(1e-9);
    if hi - lo >= min_width {
        return (lo, hi);
    }
    let mid = 0.5 * (lo + hi);
    let half = (0.5e-3 + 0.05 * magnitude).max(min_width);
    (mid - half, mid + half)
}

/// Tick positions: multiples of a step of 1, 2 or 5 times a power of ten, about `target`
/// of them (never more than `4 * target`).
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> (Vec<f64>, f64) {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return (vec![lo], 1.0);
    }
    let raw = span / target.max(1) as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * power);
    let first = (lo / step).ceil();
    let last = (hi / step).floor();
    let count = (last - first + 1.0).clamp(0.0, 4.0 * target as f64) as usize;
    let ticks = (0..count).map(|k| (first + k as f64) * step).collect();
    (ticks, step)
}

fn axis(lo: f64, hi: f64, target: usize) -> Axis {
    let (ticks, step) = nice_ticks(lo, hi, target);
    Axis {
        lo,
        hi,
        ticks,
        step,
    }
}

/// The x range of a panel: its own when set and drawable, else the data's.
pub fn x_range(p: &Panel) -> (f64, f64) {
    if let Some((a, b)) = p.x_range {
        if drawable(a) && drawable(b) && a <= b {
            return widen(a, b);
        }
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let xs = p
        .lines
        .iter()
        .map(|l| &l.x)
        .chain(p.bands.iter().map(|b| &b.x));
    for &v in xs.flatten().filter(|v| drawable(**v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        (0.0, 1.0)
    } else {
        widen(lo, hi)
    }
}

/// Runs of drawable points (broken where a point cannot be drawn).
fn runs(points: impl Iterator<Item = (f64, f64)>) -> Vec<Polyline> {
    let mut out: Vec<Polyline> = Vec::new();
    let mut current = Vec::new();
    for (x, y) in points {
        if drawable(x) && drawable(y) {
            current.push((x, y));
        } else if !current.is_empty() {
            out.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// The data of a panel before the y range is known.
#[derive(Clone, Debug)]
pub struct Gathered {
    x: (f64, f64),
    lines: Vec<Vec<Polyline>>,
    bands: Vec<Vec<(f64, f64, f64)>>,
    /// The y extent of the data that sizes the axis (lines, bands, markers near them).
    pub extent: Option<(f64, f64)>,
    hlines: Vec<Option<f64>>,
    left_out: (usize, usize),
    markers_left_out: Vec<String>,
}

fn grow(extent: &mut Option<(f64, f64)>, v: f64) {
    *extent = Some(match *extent {
        Some((lo, hi)) => (lo.min(v), hi.max(v)),
        None => (v, v),
    });
}

/// Counts the samples of a series with a drawable time in `xr` whose value cannot be
/// drawn (non-finite, beyond LIMIT), and those whose time cannot be drawn.
fn count_left_out(x: &[f64], y: &[f64], xr: (f64, f64), counts: &mut (usize, usize)) {
    for (&a, &b) in x.iter().zip(y) {
        let in_range = drawable(a) && a >= xr.0 && a <= xr.1;
        let bad_x = !drawable(a);
        if bad_x || (in_range && !drawable(b)) {
            if (bad_x && !a.is_finite()) || (!bad_x && !b.is_finite()) {
                counts.0 += 1;
            } else {
                counts.1 += 1;
            }
        }
    }
}

/// Gathers the drawable data of a panel over its x range.
pub fn gather(p: &Panel) -> Gathered {
    let xr = x_range(p);
    let fit_from = p
        .y_fit_from
        .filter(|v| v.is_finite())
        .unwrap_or(f64::NEG_INFINITY);
    let mut extent = None;
    let mut left_out = (0, 0);
    let mut lines = Vec::new();
    for l in &p.lines {
        count_left_out(&l.x, &l.y, xr, &mut left_out);
        let idx = decimate(&l.x, &l.y, xr, MAX_POINTS);
        let pieces = runs(idx.iter().map(|&k| (l.x[k], l.y[k])));
        for &(x, y) in pieces.iter().flatten() {
            if x >= xr.0 && x <= xr.1 && x >= fit_from {
                grow(&mut extent, y);
            }
        }
        lines.push(pieces);
    }
    let mut bands = Vec::new();
    for b in &p.bands {
        let mut idx = decimate(&b.x, &b.hi, xr, MAX_POINTS);
        idx.extend(decimate(&b.x, &b.lo, xr, MAX_POINTS));
        idx.sort_unstable();
        idx.dedup();
        let points: Vec<(f64, f64, f64)> =
            idx.iter().map(|&k| (b.x[k], b.lo[k], b.hi[k])).collect();
        for &(x, lo, hi) in &points {
            if drawable(x) && drawable(lo) && drawable(hi) && x >= xr.0 && x <= xr.1 {
                grow(&mut extent, lo);
                grow(&mut extent, hi);
            }
        }
        bands.push(points);
    }
    // Markers join the extent when they are near the data (a bound just outside it), not
    // when they would flatten it.
    let data = extent;
    let mut markers_left_out = Vec::new();
    let hlines = p
        .hlines
        .iter()
        .map(|m| {
            let near = match data {
                Some((lo, hi)) => {
                    let reach = 2.0 * (hi - lo).max(0.5 * (lo.abs().max(hi.abs())).max(1e-3));
                    m.at >= lo - reach && m.at <= hi + reach
                }
                None => true,
            };
            if drawable(m.at) && near {
                grow(&mut extent, m.at);
                Some(m.at)
            } else {
                markers_left_out.push(format!("the line at y = {:e}", m.at));
                None
            }
        })
        .collect();
    Gathered {
        x: xr,
        lines,
        bands,
        extent,
        hlines,
        left_out,
        markers_left_out,
    }
}

/// The y range that shows `extent` with a margin.
pub fn y_range(extent: Option<(f64, f64)>) -> (f64, f64) {
    let Some((lo, hi)) = extent else {
        return (-1.0, 1.0);
    };
    let pad = 0.06 * (hi - lo);
    widen(lo - pad, hi + pad)
}

/// Clips the segment `a`-`b` to the rectangle (Liang-Barsky); `None` when outside.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    xr: (f64, f64),
    yr: (f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - xr.0),
        (dx, xr.1 - a.0),
        (-dy, a.1 - yr.0),
        (dy, yr.1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    // The ends themselves when inside (no rounding, so that pieces join), else the
    // crossing, kept inside the rectangle.
    let at = |t: f64| {
        if t == 0.0 {
            a
        } else if t == 1.0 {
            b
        } else {
            (
                (a.0 + t * dx).clamp(xr.0, xr.1),
                (a.1 + t * dy).clamp(yr.0, yr.1),
            )
        }
    };
    (t0 <= t1).then(|| (at(t0), at(t1)))
}

/// The parts of a polyline inside the rectangle.
pub fn clip(line: &[(f64, f64)], xr: (f64, f64), yr: (f64, f64)) -> Vec<Polyline> {
    let inside = |p: (f64, f64)| p.0 >= xr.0 && p.0 <= xr.1 && p.1 >= yr.0 && p.1 <= yr.1;
    let mut out: Vec<Polyline> = Vec::new();
    let mut current: Polyline = Vec::new();
    if let [only] = line {
        if inside(*only) {
            out.push(vec![*only]);
        }
        return out;
    }
    for w in line.windows(2) {
        match clip_segment(w[0], w[1], xr, yr) {
            Some((a, b)) => {
                if current.last() != Some(&a) {
                    if !current.is_empty() {
                        out.push(std::mem::take(&mut current));
                    }
                    current.push(a);
                }
                current.push(b);
            }
            None => {
                if !current.is_empty() {
                    out.push(std::mem::take(&mut current));
                }
            }
        }
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// Band polygons: each run of drawable samples, lower edge forward and upper edge back,
/// clamped to the axes.
fn band_polygons(points: &[(f64, f64, f64)], xr: (f64, f64), yr: (f64, f64)) -> Vec<Polyline> {
    let mut out = Vec::new();
    let mut run: Vec<(f64, f64, f64)> = Vec::new();
    let close = |run: &mut Vec<(f64, f64, f64)>, out: &mut Vec<Polyline>| {
        if run.len() >= 2 {
            let c = |x: f64, y: f64| (x.clamp(xr.0, xr.1), y.clamp(yr.0, yr.1));
            let mut poly: Polyline = run.iter().map(|&(x, lo, _)| c(x, lo)).collect();
            poly.extend(run.iter().rev().map(|&(x, _, hi)| c(x, hi)));
            out.push(poly);
        }
        run.clear();
    };
    for &(x, lo, hi) in points {
        if drawable(x) && drawable(lo) && drawable(hi) {
            run.push((x, lo, hi));
        } else {
            close(&mut run, &mut out);
        }
    }
    close(&mut run, &mut out);
    out
}

/// Finishes a gathered panel with its y range (its own, or one shared by the figure).
pub fn finish(p: &Panel, g: Gathered, yr: (f64, f64)) -> Prepared {
    let xr = g.x;
    let mut notes = Vec::new();
    let (nonfinite, huge) = g.left_out;
    if nonfinite + huge > 0 {
        let mut parts = Vec::new();
        if nonfinite > 0 {
            parts.push(format!("{nonfinite} non-finite samples"));
        }
        if huge > 0 {
            parts.push(format!("{huge} samples beyond ±{LIMIT:.0e}"));
        }
        notes.push(Note {
            text: format!("{}: not drawn", parts.join(" and ")),
            left_out: true,
        });
    }
    if !g.markers_left_out.is_empty() {
        notes.push(Note {
            text: format!(
                "{}: far outside the data, not drawn",
                g.markers_left_out.join(", ")
            ),
            left_out: true,
        });
    }
    let lines: Vec<Vec<Polyline>> = g
        .lines
        .iter()
        .map(|pieces| pieces.iter().flat_map(|l| clip(l, xr, yr)).collect())
        .collect();
    if let Some(from) = p.y_fit_from {
        let beyond = g
            .lines
            .iter()
            .flatten()
            .flatten()
            .filter(|(x, y)| *x >= xr.0 && *x < from && (*y < yr.0 || *y > yr.1));
        if let Some(peak) = beyond.map(|(_, y)| y.abs()).reduce(f64::max) {
            notes.push(Note {
                text: format!(
                    "the y axis fits t ≥ {from} s; earlier samples beyond it (up to |y| = {}) are clipped", crate::number::short(peak)
                ),
                left_out: false,
            });
        }
    }
    let vlines = p
        .vlines
        .iter()
        .map(|m| (m.at >= xr.0 && m.at <= xr.1).then_some(m.at))
        .collect();
    let spans = p
        .spans
        .iter()
        .map(|s| {
            let (a, b) = (s.from.max(xr.0), s.to.min(xr.1));
            (a < b).then_some((a, b))
        })
        .collect();
    let hlines = g
        .hlines
        .iter()
        .map(|h| h.filter(|v| *v >= yr.0 && *v <= yr.1))
        .collect();
    Prepared {
        x: axis(xr.0, xr.1, X_TICKS),
        y: axis(yr.0, yr.1, Y_TICKS),
        lines,
        bands: g.bands.iter().map(|b| band_polygons(b, xr, yr)).collect(),
        hlines,
        vlines,
        spans,
        notes,
    }
}

/// Prepares every panel of a figure; `shared` gives them one y range.
pub fn prepare(panels: &[Panel], shared: bool) -> Vec<Prepared> {
    let gathered: Vec<Gathered> = panels.iter().map(gather).collect();
    let union = gathered
        .iter()
        .filter_map(|g| g.extent)
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
    panels
        .iter()
        .zip(gathered)
        .map(|(p, g)| {
            let yr = y_range(if shared { union } else { g.extent });
            finish(p, g, yr)
        })
        .collect()
}

/// A tick label for a value on an axis whose ticks are `step` apart: enough decimals to
/// tell the ticks apart, scientific notation for very large or small numbers, `0` for
/// zero (never `-0.0`).
pub fn tick_label(v: f64, step: f64) -> String {
    if !(step.is_finite() && step > 0.0) {
        return format!("{v}");
    }
    if v.abs() < 0.5 * step {
        return "0".into();
    }
    let step_power = step.log10().floor();
    if v.abs() >= 1e6 || step < 1e-4 {
        let prec = (v.abs().log10().floor() - step_power).max(0.0) as usize;
        return format!("{v:.prec$e}");
    }
    let decimals = (-step_power).clamp(0.0, 9.0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests;
