//! How the false torque's spread changes with the motion: the factor that scales a joint's
//! contact and collision levels (docs/method.md section 5, "Contact").
//!
//! On free motion the model error is not stationary. It grows with speed and acceleration
//! (a viscous or inertia misfit), often faster beyond some speed (a friction curve fitted
//! on slower motion), and it peaks where a joint reverses: the friction model's smooth sign,
//! the signals' filtering and the plant's stiction disagree most near zero velocity, and the
//! sharper the reversal (the larger `|a|` there) the higher the peak. The spread is fitted as
//!
//! ```text
//!   s(v, a) = s_0 + s_v |v| + s_a |a| + s_k (|v| - k)+ + (s_r + s_ra |a|) exp(-(v / w)^2)
//! ```
//!
//! (least squares of `|estimate|`, every slope >= 0, the width `w` and the knee `k` chosen
//! among a few by the fit's residual), and stored relative to the standstill value
//! `S = s(0, 0) = s_0 + s_r`: the level factor is
//! `s(v, a) / S = 1 + g_v |v| + g_a |a| + g_k (|v| - k)+ + g_ra |a| r - d (1 - r)` with
//! `r = exp(-(v / w)^2)`, every `g = s / S` and the drop away from rest `d = s_r / S` in
//! `[0, 1)`.

/// Widths of the rest term tried (rad/s).
const REST_WIDTHS: [f64; 4] = [0.02, 0.05, 0.1, 0.2];
/// Knees tried, as fractions of the calibration's largest `|v|`.
const KNEE_FRACTIONS: [f64; 3] = [0.25, 0.5, 0.75];
/// Columns besides the intercept: `|v|`, `|a|`, `r`, `(|v| - k)+`, `r |a|`.
const COLUMNS: usize = 5;

/// The shape of one joint's level factor (the module's formula).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LevelShape {
    /// `g_v` (1 per rad/s).
    pub speed_gain: f64,
    /// `g_a` (1 per rad/s^2).
    pub acceleration_gain: f64,
    /// `d`, the fraction the levels drop by once the joint moves beyond `rest_width`.
    pub moving_drop: f64,
    /// `w` (rad/s; unused when `moving_drop` and `reversal_gain` are 0).
    pub rest_width: f64,
    /// `g_ra` (1 per rad/s^2 at a reversal).
    pub reversal_gain: f64,
    /// `k` (rad/s).
    pub knee_speed: f64,
    /// `g_k` (1 per rad/s beyond the knee).
    pub knee_gain: f64,
}

impl LevelShape {
    /// The level factor at velocity `v` and acceleration `a` (1 at standstill).
    #[inline]
    pub fn factor(&self, v: f64, a: f64) -> f64 {
        let rest = if self.moving_drop > 0.0 || self.reversal_gain > 0.0 {
            let x = v / self.rest_width;
            (-x * x).exp()
        } else {
            1.0
        };
        1.0 + self.speed_gain * v.abs()
            + self.acceleration_gain * a.abs()
            + self.knee_gain * (v.abs() - self.knee_speed).max(0.0)
            + self.reversal_gain * a.abs() * rest
            - self.moving_drop * (1.0 - rest)
    }
}

/// The fitted spread of one joint's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spread {
    /// `S`, the spread at standstill (N m).
    pub standstill: f64,
    /// How it changes with the motion.
    pub shape: LevelShape,
}

/// The spread of estimate `e` over velocities `v` and accelerations `a`. With `motion` false,
/// the mean `|e|` at every speed. `s_0` is kept at least a quarter of the mean `|e|`, so that
/// the levels away from rest stay above the noise.
pub(crate) fn fit_spread(e: &[f64], v: &[f64], a: &[f64], motion: bool) -> Spread {
    let y: Vec<f64> = e.iter().map(|x| x.abs()).collect();
    let mean = (y.iter().sum::<f64>() / y.len().max(1) as f64).max(1e-9);
    let constant = Spread {
        standstill: mean,
        shape: LevelShape {
            rest_width: REST_WIDTHS[0],
            ..LevelShape::default()
        },
    };
    if !motion {
        return constant;
    }
    let top = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let mut best: Option<(f64, [f64; COLUMNS + 1], f64, f64)> = None;
    for width in REST_WIDTHS {
        for fraction in KNEE_FRACTIONS {
            let knee = fraction * top;
            let row = |k: usize| {
                let (va, aa) = (v[k].abs(), a[k].abs());
                let r = (-(v[k] / width) * (v[k] / width)).exp();
                [1.0, va, aa, r, (va - knee).max(0.0), r * aa]
            };
            let (beta, residual) = nonnegative_slopes(&y, row);
            if best.as_ref().is_none_or(|(r, ..)| residual < *r) {
                best = Some((residual, beta, width, knee));
            }
        }
    }
    let Some((_, [s0, sv, sa, sr, sk, sra], width, knee)) = best else {
        return constant;
    };
    let s0 = s0.max(0.25 * mean).max(1e-9);
    let standstill = s0 + sr;
    Spread {
        standstill,
        shape: LevelShape {
            speed_gain: sv / standstill,
            acceleration_gain: sa / standstill,
            moving_drop: sr / standstill,
            rest_width: width,
            reversal_gain: sra / standstill,
            knee_speed: knee,
            knee_gain: sk / standstill,
        },
    }
}

/// Least squares of `y` on the rows `row(k)` (intercept first) with every slope kept >= 0
/// (active set: the most negative slope is dropped and the rest refitted, from one Gram
/// matrix); the coefficients (0 for a dropped column) and the residual sum of squares.
#[allow(clippy::needless_range_loop)] // index loops over a small symmetric matrix read best
fn nonnegative_slopes(
    y: &[f64],
    row: impl Fn(usize) -> [f64; COLUMNS + 1],
) -> ([f64; COLUMNS + 1], f64) {
    const P: usize = COLUMNS + 1;
    let mut gram = [[0.0; P]; P];
    let mut xty = [0.0; P];
    let mut yty = 0.0;
    for (k, yk) in y.iter().enumerate() {
        let x = row(k);
        for r in 0..P {
            xty[r] += x[r] * yk;
            for c in r..P {
                gram[r][c] += x[r] * x[c];
            }
        }
        yty += yk * yk;
    }
    for r in 0..P {
        for c in 0..r {
            gram[r][c] = gram[c][r];
        }
    }
    let mut used = [true; P];
    let mut beta = [0.0; P];
    for _ in 0..P {
        beta = solve_subset(&gram, &xty, &used);
        let worst = (1..P)
            .filter(|&j| used[j] && beta[j] < 0.0)
            .min_by(|&i, &j| beta[i].total_cmp(&beta[j]));
        match worst {
            Some(j) => used[j] = false,
            None => break,
        }
    }
    for b in &mut beta[1..] {
        *b = b.max(0.0);
    }
    // |y - X b|^2 = y'y - 2 b'X'y + b'G b.
    let mut residual = yty;
    for r in 0..P {
        residual -= 2.0 * beta[r] * xty[r];
        for c in 0..P {
            residual += beta[r] * gram[r][c] * beta[c];
        }
    }
    (beta, residual)
}

/// The normal equations restricted to the `used` columns (others 0); the intercept alone
/// (the mean) when they are singular.
fn solve_subset<const P: usize>(
    gram: &[[f64; P]; P],
    xty: &[f64; P],
    used: &[bool; P],
) -> [f64; P] {
    let idx: Vec<usize> = (0..P).filter(|&j| used[j]).collect();
    let m = idx.len();
    let g = nalgebra::DMatrix::<f64>::from_fn(m, m, |r, c| {
        gram[idx[r]][idx[c]]
            + if r == c {
                1e-12 * (1.0 + gram[idx[r]][idx[r]])
            } else {
                0.0
            }
    });
    let b = nalgebra::DVector::<f64>::from_fn(m, |r, _| xty[idx[r]]);
    let mut out = [0.0; P];
    match g.cholesky() {
        Some(ch) => {
            for (j, v) in idx.iter().zip(ch.solve(&b).iter()) {
                out[*j] = *v;
            }
        }
        None => out[0] = xty[0] / gram[0][0].max(1.0),
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A false torque that peaks at reversals and grows with speed: the fit finds both (to
    /// 1e-4: `|a|` and the reversal term are nearly collinear on one sine), and the factor
    /// is 1 at standstill.
    #[test]
    fn finds_the_rest_peak_and_the_speed_growth() {
        let n = 20_000;
        let v: Vec<f64> = (0..n).map(|k| (k as f64 * 1e-3).sin()).collect();
        let a: Vec<f64> = (0..n).map(|k| (k as f64 * 1e-3).cos()).collect();
        let e: Vec<f64> = v
            .iter()
            .map(|x| 0.1 + 0.2 * x.abs() + 0.5 * (-(x / 0.05) * (x / 0.05)).exp())
            .collect();
        let fit = fit_spread(&e, &v, &a, true);
        let s = fit.shape;
        assert_eq!(s.rest_width, 0.05);
        assert!((fit.standstill - 0.6).abs() < 1e-4, "{fit:?}");
        assert!((s.moving_drop - 0.5 / 0.6).abs() < 1e-4, "{fit:?}");
        assert!((s.speed_gain - 0.2 / 0.6).abs() < 1e-4, "{fit:?}");
        assert!(s.acceleration_gain.abs() < 1e-4, "{fit:?}");
        assert!(
            s.knee_gain.abs() < 1e-4 && s.reversal_gain.abs() < 1e-4,
            "{fit:?}"
        );
        assert!((s.factor(0.0, 0.0) - 1.0).abs() < 1e-12);
        assert!((s.factor(1.0, 0.0) * fit.standstill - 0.3).abs() < 1e-4);
    }

    /// A spread that falls with speed keeps no negative slope.
    #[test]
    fn slopes_stay_non_negative() {
        let v: Vec<f64> = (0..5000).map(|k| k as f64 * 1e-3).collect();
        let a = vec![0.0; v.len()];
        let e: Vec<f64> = v.iter().map(|x| 2.0 - x).collect();
        let s = fit_spread(&e, &v, &a, true).shape;
        assert!(s.speed_gain >= 0.0 && s.acceleration_gain >= 0.0 && s.moving_drop >= 0.0);
        assert!(s.knee_gain >= 0.0 && s.reversal_gain >= 0.0 && s.moving_drop < 1.0);
    }
}

#[cfg(test)]
mod more_tests {
    use super::*;

    /// A spread that rises beyond a speed and whose reversal peaks grow with the reversal's
    /// acceleration: the knee and the reversal gain are found.
    #[test]
    fn finds_the_knee_and_the_sharper_reversals() {
        let n = 40_000;
        // Two sines of other periods: reversals at several accelerations.
        let v: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 * 1e-3;
                t.sin() + 0.5 * (2.3 * t).sin()
            })
            .collect();
        let a: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 * 1e-3;
                t.cos() + 1.15 * (2.3 * t).cos()
            })
            .collect();
        let top = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let knee = 0.5 * top;
        let e: Vec<f64> = v
            .iter()
            .zip(&a)
            .map(|(x, y)| {
                let r = (-(x / 0.1) * (x / 0.1)).exp();
                0.1 + 0.4 * (x.abs() - knee).max(0.0) + 0.3 * r * y.abs()
            })
            .collect();
        let fit = fit_spread(&e, &v, &a, true);
        let s = fit.shape;
        assert_eq!(s.rest_width, 0.1, "{fit:?}");
        assert!((s.knee_speed - knee).abs() < 1e-12, "{fit:?}");
        assert!((s.knee_gain * fit.standstill - 0.4).abs() < 1e-6, "{fit:?}");
        assert!(
            (s.reversal_gain * fit.standstill - 0.3).abs() < 1e-6,
            "{fit:?}"
        );
        for k in (0..n).step_by(997) {
            let model = fit.standstill * s.factor(v[k], a[k]);
            assert!((model - e[k]).abs() < 1e-6, "{k}: {model} against {}", e[k]);
        }
    }
}
