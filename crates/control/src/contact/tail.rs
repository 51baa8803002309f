//! Events of a normalised false-torque series and the tail of their peaks: the level whose
//! event rate is a given one (docs/method.md section 5, "Contact").
//!
//! An event is one excursion of `|z|` above a level `u`: it starts when `|z| > u` and ends when
//! `|z| < release u` (the detector's hysteresis), so neighbouring, correlated samples of one
//! excursion count once. Above a base level `u0` with enough events, the excesses of the
//! per-event peaks are taken as generalised-Pareto (the peaks-over-threshold model of extreme
//! value theory), with shape `0 <= xi <= 0.25` (a bounded tail, which a fit may suggest from
//! few events, is not trusted; with fewer than 50 events, `xi = 0`, the exponential tail), fitted by probability-weighted moments (Hosking and Wallis 1987).
//! The rate of events above `u >= u0` is then
//! `lambda(u) = lambda0 (1 + xi (u - u0) / sigma)^(-1/xi)` (`lambda0 exp(-(u - u0) / sigma)`
//! at `xi = 0`), solved for the requested rate.

/// The events of `z` above `level` with release at `release * level`: their peaks of `|z|`.
pub(crate) fn event_peaks(z: &[f64], level: f64, release: f64) -> Vec<f64> {
    let mut peaks = Vec::new();
    let mut peak: Option<f64> = None;
    for &x in z {
        let a = x.abs();
        peak = match peak {
            None if a > level => Some(a),
            Some(p) if a >= release * level => Some(p.max(a)),
            Some(p) => {
                peaks.push(p);
                None
            }
            None => None,
        };
    }
    peaks.extend(peak);
    peaks
}

/// The level for a rate and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TailLevel {
    /// The level of `|z|`.
    pub level: f64,
    /// Events above the base level (the tail fit's sample size).
    pub base_events: usize,
    /// The generalised-Pareto shape used (0 when the level was read from the data).
    pub shape: f64,
}

/// Fewest events above the base level for a tail fit.
pub(crate) const MIN_TAIL_EVENTS: usize = 20;
/// Fewest events above the base level to fit a shape other than the exponential's.
const MIN_SHAPE_EVENTS: usize = 50;
/// The largest shape used: a heavier tail fitted on a minute of data would put the level
/// for one event per hour at hundreds of spreads.
const MAX_SHAPE: f64 = 0.25;

/// The level of `|z|` whose events occur `rate` times per hour on `z`, of length `hours`.
pub(crate) fn level_for_rate(z: &[f64], hours: f64, release: f64, rate: f64) -> TailLevel {
    let mut sorted: Vec<f64> = z
        .iter()
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let top = sorted.last().copied().unwrap_or(0.0);
    if top <= 0.0 {
        return TailLevel {
            level: f64::MIN_POSITIVE,
            base_events: 0,
            shape: 0.0,
        };
    }
    // Base level: the highest upper quantile with enough events for a fit (else the
    // lowest tried), scanned from the 99.9 % quantile down to the median.
    let quantile =
        |p: f64| sorted[((p * (sorted.len() - 1) as f64) as usize).min(sorted.len() - 1)];
    // Base level: the highest upper quantile with enough events for a fit, else the one
    // with the most events, scanned from the 99.9 % quantile down to the 60 % one.
    let mut base: Option<(f64, Vec<f64>)> = None;
    for p in [0.999, 0.998, 0.995, 0.99, 0.98, 0.95, 0.9, 0.8, 0.7, 0.6] {
        let u0 = quantile(p);
        if u0 <= 0.0 {
            continue;
        }
        let peaks = event_peaks(z, u0, release);
        let enough = peaks.len() >= MIN_TAIL_EVENTS;
        if base.as_ref().is_none_or(|(_, b)| peaks.len() > b.len()) {
            base = Some((u0, peaks));
        }
        if enough {
            break;
        }
    }
    let base = base.unwrap_or_else(|| (top, vec![top]));
    let (u0, peaks) = base;
    let wanted = rate * hours;
    if peaks.len() as f64 <= wanted || peaks.len() < 2 {
        // Within the data: the lowest level whose events are no more than wanted.
        return TailLevel {
            level: empirical_level(z, release, wanted, u0, top),
            base_events: peaks.len(),
            shape: 0.0,
        };
    }
    let excess: Vec<f64> = peaks.iter().map(|p| p - u0).collect();
    let (mut shape, mut scale) = pareto_pwm(&excess);
    if peaks.len() < MIN_SHAPE_EVENTS {
        // Too few events to tell a heavier tail: the exponential one.
        (shape, scale) = (0.0, excess.iter().sum::<f64>() / excess.len() as f64);
    }
    let ratio = peaks.len() as f64 / wanted;
    let level = if shape > 1e-9 {
        u0 + scale / shape * (ratio.powf(shape) - 1.0)
    } else {
        u0 + scale * ratio.ln()
    };
    TailLevel {
        level: level.max(u0),
        base_events: peaks.len(),
        shape,
    }
}

/// The lowest level in `[low, high]` with at most `wanted` events (bisection; the count
/// falls with the level up to the hysteresis's splitting of excursions).
fn empirical_level(z: &[f64], release: f64, wanted: f64, low: f64, high: f64) -> f64 {
    let (mut lo, mut hi) = (low.min(high), high);
    if event_peaks(z, lo, release).len() as f64 <= wanted {
        return lo;
    }
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if event_peaks(z, mid, release).len() as f64 <= wanted {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Generalised-Pareto shape (kept in `[0, MAX_SHAPE]`) and scale of excesses `y >= 0` by
/// probability-weighted moments; at shape 0 the scale is the exponential's (the mean).
pub(crate) fn pareto_pwm(excess: &[f64]) -> (f64, f64) {
    let n = excess.len();
    let mean = excess.iter().sum::<f64>() / n.max(1) as f64;
    if n < 3 {
        return (0.0, mean.max(f64::MIN_POSITIVE));
    }
    let mut y = excess.to_vec();
    y.sort_by(f64::total_cmp);
    // a1 = E[Y (1 - F(Y))], estimated from the ascending order statistics.
    let a1 = y
        .iter()
        .enumerate()
        .map(|(j, v)| v * (n - 1 - j) as f64 / (n - 1) as f64)
        .sum::<f64>()
        / n as f64;
    let d = mean - 2.0 * a1;
    if d <= 0.0 {
        return (MAX_SHAPE, (mean * (1.0 - MAX_SHAPE)).max(f64::MIN_POSITIVE));
    }
    let shape = 2.0 - mean / d;
    if shape <= 0.0 {
        (0.0, mean.max(f64::MIN_POSITIVE))
    } else {
        let shape = shape.min(MAX_SHAPE);
        // Scale from the mean of a GPD: E[Y] = sigma / (1 - xi).
        (shape, (mean * (1.0 - shape)).max(f64::MIN_POSITIVE))
    }
}
