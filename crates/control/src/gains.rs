//! The gain rules of an arm, from its model (docs/method.md section 3, "Gains from the
//! arm"): checked when a scenario loads (warnings naming the key, the joint and a suggested
//! value) and used by `admittance gains` to print a starting set.
//!
//! With `I` a joint's inertia (the diagonal of `M(q)` over the poses the motion visits):
//!
//! * **`k2_adaptive_bound`**: `K2 > K1 I_max`. The learned terms act on `e2 = e1' + K1 e1`
//!   like an integral of `e2`, so the loop is a PID with `Kd = K2`, `Kp = K1 K2`,
//!   `Ki = K1 Gamma ||S||^2`; on an inertia `I` it is stable for every adaptation gain only
//!   if `K2 > K1 I`. Below it the heavy joints sit in a slow limit cycle.
//! * **`k2_velocity_bandwidth`**: the velocity loop `I s + b` closed by `K2` through the
//!   velocity estimate crosses over at `omega_c = sqrt(K2^2 - b^2) / I_min` (none when
//!   `K2 <= b`, the viscous friction the plant is known to have), which must stay under
//!   [`BANDWIDTH_FRACTION`] of the velocity filter's bandwidth `2 pi f_v` and under
//!   [`DISCRETE_FRACTION`] of the control rate (`K2 dt / I`). Above it a light wrist
//!   chatters between its effort limits.
//! * **`admittance_bandwidth`**: the admittance model relaxes at `G_d / C_d` (and rings at
//!   `sqrt(G_d / M_d)` with an inertia), which must stay under [`BANDWIDTH_FRACTION`] of the
//!   estimate's bandwidth `2 pi f_est`: a reference that moves faster than the estimate
//!   follows acts on old estimates.
//!
//! The suggested `K2` is `SUGGESTED_MARGIN K1 I_max`, capped by the bandwidth rule.

use admittance_dynamics::{crba, Data, Model};

/// The velocity loop's crossover may use this share of the filter's bandwidth (a half:
/// about 40 degrees of phase margin with a 2nd-order Butterworth and one period of delay).
pub const BANDWIDTH_FRACTION: f64 = 0.5;
/// `K2 dt / I` at most this (the discrete-time bound is about 2).
pub const DISCRETE_FRACTION: f64 = 0.5;
/// A suggested `K2` is this many times the adaptive bound `K1 I_max`.
pub const SUGGESTED_MARGIN: f64 = 2.0;
/// The suggested `K1` (1/s): the paper's.
pub const SUGGESTED_K1: f64 = 12.0;

/// What the loop's velocity estimate and the plant allow.
#[derive(Clone, Debug)]
pub struct LoopLimits {
    /// Control rate (Hz).
    pub control_rate_hz: f64,
    /// Cut-off of the low-pass before the velocity is differentiated (Hz; 0: none).
    pub velocity_filter_hz: f64,
    /// Viscous friction known to act on each joint (N m s/rad), 0 where unknown.
    pub damping: Vec<f64>,
}

impl LoopLimits {
    /// The largest crossover of the velocity loop (rad/s).
    pub fn velocity_bandwidth(&self) -> f64 {
        let discrete = DISCRETE_FRACTION * self.control_rate_hz;
        if self.velocity_filter_hz > 0.0 {
            discrete.min(BANDWIDTH_FRACTION * 2.0 * std::f64::consts::PI * self.velocity_filter_hz)
        } else {
            discrete
        }
    }

    /// The largest `K2` of joint `j` with smallest inertia `i_min`.
    pub fn max_k2(&self, j: usize, i_min: f64) -> f64 {
        let b = self.damping.get(j).copied().unwrap_or(0.0);
        (self.velocity_bandwidth() * i_min).hypot(b)
    }
}

/// Each joint's smallest and largest inertia (diagonal of `M(q)`) over some poses.
#[derive(Clone, Debug, PartialEq)]
pub struct JointInertia {
    /// Smallest, per joint (kg m^2 or kg).
    pub min: Vec<f64>,
    /// Largest, per joint.
    pub max: Vec<f64>,
}

impl JointInertia {
    /// Over `poses` (each of `model.nq()` values; at least one).
    pub fn over<'a>(model: &Model, poses: impl IntoIterator<Item = &'a [f64]>) -> Self {
        let n = model.nq();
        let mut data = Data::new(model);
        let (mut min, mut max) = (vec![f64::INFINITY; n], vec![0.0f64; n]);
        for q in poses {
            if let Ok(m) = crba(model, &mut data, q) {
                for j in 0..n {
                    min[j] = min[j].min(m[(j, j)]);
                    max[j] = max[j].max(m[(j, j)]);
                }
            }
        }
        Self { min, max }
    }
}

/// A gain that breaks a rule, with the value to use instead.
#[derive(Clone, Debug, PartialEq)]
pub struct GainAdvice {
    /// The rule's name.
    pub rule: &'static str,
    /// The setting (`controller.neural.k2`, `admittance.damping`, ...).
    pub key: String,
    /// The joint's name.
    pub joint: String,
    /// Its index in chain order.
    pub index: usize,
    /// The value it has.
    pub value: f64,
    /// The value suggested.
    pub suggested: f64,
    /// One sentence: the rule, the numbers, the fix.
    pub message: String,
}

/// A value rounded up (`up`) or down to 2 significant digits, so that the suggestion reads
/// well and still meets its bound.
pub fn round2(x: f64, up: bool) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let scale = 10f64.powf(x.log10().floor() - 1.0);
    let r = if up {
        (x / scale).ceil()
    } else {
        (x / scale).floor()
    };
    // The nearest double to the 2-digit decimal, so that it prints as written.
    format!("{:.1e}", r * scale).parse().unwrap_or(r * scale)
}

/// The suggested `K2` of a joint: [`SUGGESTED_MARGIN`] times the adaptive bound, capped by
/// the bandwidth rule (then at least the bound plus 10 %, when the two leave room).
pub fn suggested_k2(k1: f64, inertia: &JointInertia, limits: &LoopLimits, j: usize) -> f64 {
    let low = k1 * inertia.max[j];
    let high = limits.max_k2(j, inertia.min[j]);
    let k2 = (SUGGESTED_MARGIN * low).min(high);
    if k2 >= 1.1 * low {
        // Rounding down 2 significant digits loses under 10 %: still above the bound.
        round2(k2, false)
    } else {
        // No room between the rules: the adaptive bound first (the bandwidth warning stays).
        round2(1.1 * low, true)
    }
}

/// The rules on the feedback gains `K1`, `K2` of the neural controller (`key` is where
/// `K2` is written, e.g. `controller.neural.k2`).
pub fn check_feedback(
    key: &str,
    joints: &[String],
    k1: &[f64],
    k2: &[f64],
    inertia: &JointInertia,
    limits: &LoopLimits,
) -> Vec<GainAdvice> {
    let mut out = Vec::new();
    let bandwidth = limits.velocity_bandwidth();
    for (j, name) in joints.iter().enumerate() {
        let (k1j, k2j) = (k1[j], k2[j]);
        let low = k1j * inertia.max[j];
        let high = limits.max_k2(j, inertia.min[j]);
        let suggested = suggested_k2(k1j, inertia, limits, j);
        // A NaN gain is not above the bound either.
        if k2j.partial_cmp(&low).is_none_or(|o| o.is_le()) {
            out.push(GainAdvice {
                rule: "k2_adaptive_bound",
                key: key.to_string(),
                joint: name.clone(),
                index: j,
                value: k2j,
                suggested,
                message: format!(
                    "K2 of {name} is {k2j}, not above K1 I = {k1j} x {:.4} = {low:.3} (its largest inertia over the motion): the adaptive loop is not stable for every adaptation gain (a slow limit cycle, hand error of centimetres); use about {suggested}",
                    inertia.max[j]
                ),
            });
        } else if k2j > high * (1.0 + 1e-9) {
            let b = limits.damping.get(j).copied().unwrap_or(0.0);
            let crossover = (k2j * k2j - b * b).max(0.0).sqrt() / inertia.min[j];
            out.push(GainAdvice {
                rule: "k2_velocity_bandwidth",
                key: key.to_string(),
                joint: name.clone(),
                index: j,
                value: k2j,
                suggested,
                message: format!(
                    "K2 of {name} is {k2j}: on its inertia {:.4} (viscous friction {b} N m s/rad) the velocity loop crosses over at {crossover:.0} rad/s, above {bandwidth:.0} rad/s ({BANDWIDTH_FRACTION:.2} of the velocity filter's bandwidth or {DISCRETE_FRACTION} of the control rate): the joint chatters; use at most {:.3}, e.g. {suggested}",
                    inertia.min[j], high
                ),
            });
        }
    }
    out
}

/// The rule on a joint-space admittance model (`damping` `C_d`, `stiffness` `G_d`,
/// `inertia` `M_d` per joint) against the estimate's low-pass at `estimate_hz`
/// (`prefix` is the table, e.g. `admittance`).
pub fn check_admittance(
    prefix: &str,
    joints: &[String],
    damping: &[f64],
    stiffness: &[f64],
    inertia: Option<&[f64]>,
    estimate_hz: f64,
) -> Vec<GainAdvice> {
    let mut out = Vec::new();
    if estimate_hz.is_nan() || estimate_hz <= 0.0 {
        return out;
    }
    let omega = BANDWIDTH_FRACTION * 2.0 * std::f64::consts::PI * estimate_hz;
    for (j, name) in joints.iter().enumerate() {
        let (c, g) = (damping[j], stiffness[j]);
        if g / c > omega * (1.0 + 1e-9) {
            let suggested = round2(g / omega, true);
            out.push(GainAdvice {
                rule: "admittance_bandwidth",
                key: format!("{prefix}.damping"),
                joint: name.clone(),
                index: j,
                value: c,
                suggested,
                message: format!(
                    "the admittance of {name} relaxes at G_d / C_d = {g} / {c} = {:.1} rad/s, faster than {omega:.1} rad/s ({BANDWIDTH_FRACTION:.2} of the estimate's {estimate_hz} Hz low-pass): the reference acts on estimates it outruns; use C_d of at least {suggested}",
                    g / c
                ),
            });
        }
        if let Some(m) = inertia.map(|m| m[j]).filter(|m| *m > 0.0) {
            let ring = (g / m).sqrt();
            if ring > omega * (1.0 + 1e-9) {
                let suggested = round2(g / (omega * omega), true);
                out.push(GainAdvice {
                    rule: "admittance_bandwidth",
                    key: format!("{prefix}.inertia"),
                    joint: name.clone(),
                    index: j,
                    value: m,
                    suggested,
                    message: format!(
                        "the admittance of {name} rings at sqrt(G_d / M_d) = {ring:.1} rad/s, faster than {omega:.1} rad/s ({BANDWIDTH_FRACTION:.2} of the estimate's {estimate_hz} Hz low-pass); use M_d of at least {suggested}"
                    ),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(damping: f64) -> LoopLimits {
        LoopLimits {
            control_rate_hz: 1000.0,
            velocity_filter_hz: 40.0,
            damping: vec![damping; 2],
        }
    }

    fn inertia() -> JointInertia {
        JointInertia {
            min: vec![1.4, 0.031],
            max: vec![1.46, 0.031],
        }
    }

    #[test]
    fn the_adaptive_bound_names_the_joint_and_a_value_that_passes() {
        let joints = ["s0".to_string(), "w0".to_string()];
        let advice = check_feedback(
            "k2",
            &joints,
            &[12.0; 2],
            &[6.0, 2.0],
            &inertia(),
            &limits(0.0),
        );
        assert_eq!(advice.len(), 1, "{advice:?}");
        assert_eq!(
            (advice[0].rule, advice[0].joint.as_str()),
            ("k2_adaptive_bound", "s0")
        );
        assert!(advice[0].message.contains("s0") && advice[0].message.contains("17.52"));
        let fixed = [advice[0].suggested, 2.0];
        assert!(
            check_feedback("k2", &joints, &[12.0; 2], &fixed, &inertia(), &limits(0.0)).is_empty()
        );
    }

    #[test]
    fn the_bandwidth_rule_counts_the_known_friction() {
        let joints = ["s0".to_string(), "w0".to_string()];
        // w0 at K2 = 6: 194 rad/s against 126 (the wrist that chattered).
        let advice = check_feedback(
            "k2",
            &joints,
            &[12.0; 2],
            &[20.0, 6.0],
            &inertia(),
            &limits(0.0),
        );
        assert_eq!(advice.len(), 1);
        assert_eq!(
            (advice[0].rule, advice[0].joint.as_str()),
            ("k2_velocity_bandwidth", "w0")
        );
        assert!(advice[0].suggested <= limits(0.0).max_k2(1, 0.031));
        assert!(advice[0].suggested > 12.0 * 0.031);
        // K2 below the viscous friction: no crossover at all.
        let light = JointInertia {
            min: vec![1.4, 0.0006],
            max: vec![1.46, 0.0006],
        };
        assert!(check_feedback(
            "k2",
            &joints,
            &[12.0; 2],
            &[20.0, 0.2],
            &light,
            &limits(0.3)
        )
        .is_empty());
        assert_eq!(
            check_feedback(
                "k2",
                &joints,
                &[12.0; 2],
                &[20.0, 0.2],
                &light,
                &limits(0.0)
            )
            .len(),
            1
        );
    }

    #[test]
    fn the_admittance_rule() {
        let joints = ["a".to_string()];
        assert!(check_admittance("admittance", &joints, &[3.0], &[5.0], None, 5.0).is_empty());
        let a = check_admittance("admittance", &joints, &[0.1], &[5.0], None, 5.0);
        assert_eq!(a.len(), 1);
        assert!(
            check_admittance("admittance", &joints, &[a[0].suggested], &[5.0], None, 5.0)
                .is_empty()
        );
        assert!(check_admittance("admittance", &joints, &[0.1], &[5.0], None, 0.0).is_empty());
    }

    #[test]
    fn rounding_keeps_the_side_of_the_bound() {
        assert_eq!(round2(17.52, true), 18.0);
        assert_eq!(round2(0.3721, true), 0.38);
        assert_eq!(round2(0.3721, false), 0.37);
    }
}
