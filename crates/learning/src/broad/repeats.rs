//! Does a recording repeat itself? Blocked cross-validation (`cv.rs`) holds out contiguous
//! stretches; when the motion is periodic (an optimised excitation repeats its base period,
//! a multi-sine of commensurate frequencies too) every held-out stretch is motion the fit
//! has already seen, and the "unseen motion" error it reports is optimistic. The front ends
//! ask this before they rely on cross-validation and tell the user to give another
//! recording instead.

/// Rows compared at most (the recording is decimated to about this many).
const DECIMATED_ROWS: usize = 2000;
/// The motion has left its start by this share of its variance before a return counts.
const DECORRELATED: f64 = 0.5;
/// A return closer than this share of the variance is the same motion again.
const SAME_MOTION: f64 = 0.01;

/// The shortest lag, in rows, after which the rows of `positions` (row-major, `width`
/// columns: e.g. the joint angles) come back to within 1 % of their variance, looking at
/// lags up to `max_lag` rows; `None` when they do not repeat (or are too short to tell).
/// Columns that do not move are ignored.
pub fn repeat_period(positions: &[f64], width: usize, max_lag: usize) -> Option<usize> {
    if width == 0 {
        return None;
    }
    let rows = positions.len() / width;
    let step = (rows / DECIMATED_ROWS).max(1);
    let x: Vec<&[f64]> = positions.chunks_exact(width).step_by(step).collect();
    let len = x.len();
    if len < 8 {
        return None;
    }
    // Standardise per column; a column that does not move carries no information.
    let mut mean = vec![0.0; width];
    let mut var = vec![0.0; width];
    for r in &x {
        for (m, v) in mean.iter_mut().zip(*r) {
            *m += v / len as f64;
        }
    }
    for r in &x {
        for ((s, v), m) in var.iter_mut().zip(*r).zip(&mean) {
            *s += (v - m) * (v - m) / len as f64;
        }
    }
    let moving: Vec<usize> = (0..width).filter(|&c| var[c] > 1e-12).collect();
    if moving.is_empty() {
        return None;
    }
    // The moving columns over sqrt(2 var): a squared difference is then already in units of
    // the variance (multiplied here once instead of divided at every lag).
    let scaled: Vec<f64> = x
        .iter()
        .flat_map(|r| moving.iter().map(|&c| r[c] / (2.0 * var[c]).sqrt()))
        .collect();
    let m = moving.len();
    // Mean squared difference at a lag, in units of the variance (1 for unrelated rows).
    let distance = |lag: usize| -> f64 {
        let pairs = len - lag;
        let sum: f64 = scaled[lag * m..]
            .iter()
            .zip(&scaled[..pairs * m])
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        sum / (pairs * m) as f64
    };
    let max_lag = (max_lag / step).min(len - len / 4);
    let mut left = false;
    for lag in 1..=max_lag {
        let d = distance(lag);
        if !left {
            left = d > DECORRELATED;
        } else if d < SAME_MOTION {
            // The closest return nearby is the period.
            let (mut best, mut best_d) = (lag, d);
            while best < max_lag {
                let next = distance(best + 1);
                if next >= best_d {
                    break;
                }
                (best, best_d) = (best + 1, next);
            }
            return Some(best * step);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::repeat_period;

    fn rows(n: usize, f: impl Fn(f64) -> [f64; 2]) -> Vec<f64> {
        (0..n).flat_map(|i| f(i as f64 * 1e-3)).collect()
    }

    #[test]
    fn a_periodic_motion_is_found_with_its_period() {
        // Base period 10 s: 0.1 Hz and 0.3 Hz, 60 s at 1 kHz.
        let p = rows(60_000, |t| {
            let w = std::f64::consts::TAU * 0.1;
            [
                (w * t).sin() + 0.3 * (3.0 * w * t).cos(),
                (2.0 * w * t).sin(),
            ]
        });
        let lag = repeat_period(&p, 2, 48_000).expect("periodic");
        assert!((lag as f64 - 10_000.0).abs() <= 30.0, "{lag}");
    }

    #[test]
    fn motion_that_does_not_repeat_is_not_flagged() {
        // Incommensurate frequencies and a slow drift: never the same motion again.
        let p = rows(60_000, |t| {
            [
                (1.3 * t).sin() + 0.02 * t,
                (std::f64::consts::SQRT_2 * t).cos(),
            ]
        });
        assert_eq!(repeat_period(&p, 2, 48_000), None);
        assert_eq!(repeat_period(&[1.0, 2.0, 3.0, 4.0], 2, 10), None);
        assert_eq!(repeat_period(&vec![0.5; 20_000], 2, 8_000), None);
    }
}
