//! What the controller sees (docs/method.md sections 1 and 7): encoder angles with
//! quantisation and Gaussian noise, and velocities and accelerations only by numerical
//! differentiation of the low-pass-filtered angles. The commanded torque passes through
//! the same filter, so that an observer can pair signals with matching delays.
//!
//! Per sample (one per control period) and joint:
//!
//! 1. `q = quantise(q_true + noise)`, noise `N(0, noise_std^2)` from a seeded ChaCha8
//!    stream (one draw per joint per sample whatever the faults, so the stream does not
//!    depend on them); quantisation rounds to the nearest multiple of the resolution.
//! 2. `q_filtered = LP(q)`, with `LP` a causal 2nd-order Butterworth low-pass (bilinear
//!    transform with pre-warping) at `filter_cutoff_hz`, started at steady state on the
//!    first sample. `qdot = (q_filtered[k] - q_filtered[k-1]) / dt`,
//!    `qddot = (qdot[k] - qdot[k-1]) / dt` (zero until there are enough samples).
//! 3. `tau_filtered = LP(tau_commanded)` with the same filter.
//!
//! Delays at low frequency: `q_filtered` and `tau_filtered` lag by the filter's group
//! delay ([`LowPass::dc_group_delay`]); `qdot` by half a sample more, `qddot` by one
//! sample more. An observer that pairs `qddot` with torque should delay `tau_filtered`
//! by one sample.
//!
//! Fault injection (for tests of the safe behaviour): in a time window, selected joints
//! deliver a NaN sample, or a stale sample (the previous raw value repeated, with its old
//! [`Measurement::sample_time`]). A NaN reaches [`Measurement::q`] as NaN; the joint's
//! filter, velocity and acceleration hold their previous values, so the derived signals
//! stay finite. The injected faults are reported in the measurement as ground truth.

use admittance_dynamics::Model;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::plant::config::{joint_index, non_negative, window};
use crate::plant::error::{check_len, SimError};

fn infinity() -> f64 {
    f64::INFINITY
}

/// Encoders, noise and the differentiation filter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// Encoder resolution (rad per count); 0 for none. Exclusive with `counts_per_rev`.
    pub resolution_rad: f64,
    /// Encoder counts per revolution; 0 for none. Exclusive with `resolution_rad`.
    pub counts_per_rev: f64,
    /// Standard deviation of the Gaussian angle noise (rad), >= 0.
    pub noise_std: f64,
    /// Seed of the noise stream.
    pub seed: u64,
    /// Cut-off of the 2nd-order Butterworth low-pass applied to q and tau before
    /// differentiating (Hz); 0 disables it; must be below half the sample rate. Default 20.
    pub filter_cutoff_hz: f64,
    /// Injected faults.
    pub faults: Vec<FaultConfig>,
}

impl Default for SensorConfig {
    fn default() -> Self {
        Self {
            resolution_rad: 0.0,
            counts_per_rev: 0.0,
            noise_std: 0.0,
            seed: 0,
            filter_cutoff_hz: 20.0,
            faults: Vec::new(),
        }
    }
}

/// Kind of an injected sensor fault.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// The sample is NaN.
    #[default]
    Nan,
    /// The sample repeats the previous one (old timestamp).
    Stale,
}

/// A sensor fault injected on `joints` (all when empty) for samples taken in
/// `[t_start, t_end)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FaultConfig {
    /// What goes wrong.
    pub kind: FaultKind,
    /// Joint names; empty for every joint.
    pub joints: Vec<String>,
    /// Window start (s).
    pub t_start: f64,
    /// Window end (s), exclusive. Default `inf`.
    #[serde(default = "infinity")]
    pub t_end: f64,
}

impl Default for FaultConfig {
    fn default() -> Self {
        Self {
            kind: FaultKind::Nan,
            joints: Vec::new(),
            t_start: 0.0,
            t_end: f64::INFINITY,
        }
    }
}

impl SensorConfig {
    /// Checks values and names for sampling at `sample_rate_hz`; `prefix` is the key of
    /// this table (e.g. `"sensors"`).
    pub fn validate(
        &self,
        model: &Model,
        sample_rate_hz: f64,
        prefix: &str,
    ) -> Result<(), SimError> {
        non_negative(|| format!("{prefix}.resolution_rad"), self.resolution_rad)?;
        non_negative(|| format!("{prefix}.counts_per_rev"), self.counts_per_rev)?;
        if self.resolution_rad > 0.0 && self.counts_per_rev > 0.0 {
            return Err(SimError::config(
                format!("{prefix}.counts_per_rev"),
                "give either resolution_rad or counts_per_rev, not both",
            ));
        }
        non_negative(|| format!("{prefix}.noise_std"), self.noise_std)?;
        non_negative(
            || format!("{prefix}.filter_cutoff_hz"),
            self.filter_cutoff_hz,
        )?;
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(SimError::config(
                format!("{prefix}.sample_rate"),
                format!("must be > 0, got {sample_rate_hz}"),
            ));
        }
        if self.filter_cutoff_hz >= 0.5 * sample_rate_hz {
            return Err(SimError::config(
                format!("{prefix}.filter_cutoff_hz"),
                format!(
                    "must be below half the sample rate ({} Hz), got {}",
                    0.5 * sample_rate_hz,
                    self.filter_cutoff_hz
                ),
            ));
        }
        for (k, f) in self.faults.iter().enumerate() {
            let p = format!("{prefix}.faults[{k}]");
            for (j, name) in f.joints.iter().enumerate() {
                joint_index(model, || format!("{p}.joints[{j}]"), name)?;
            }
            window(&p, f.t_start, f.t_end)?;
        }
        Ok(())
    }

    /// The quantisation step in rad (0 for none).
    pub fn resolution(&self) -> f64 {
        if self.counts_per_rev > 0.0 {
            std::f64::consts::TAU / self.counts_per_rev
        } else {
            self.resolution_rad
        }
    }
}

/// A causal 2nd-order Butterworth low-pass on several channels (direct form I biquad,
/// bilinear transform with the cut-off pre-warped). Each channel starts at steady state
/// on its first sample. A cut-off of 0 makes it the identity.
#[derive(Clone, Debug)]
pub struct LowPass {
    b: [f64; 3],
    a: [f64; 2],
    passthrough: bool,
    x1: Vec<f64>,
    x2: Vec<f64>,
    y1: Vec<f64>,
    y2: Vec<f64>,
    started: Vec<bool>,
}

impl LowPass {
    /// A Butterworth low-pass at `cutoff_hz` for samples at `sample_rate_hz` (0 < cutoff <
    /// sample_rate / 2; a cut-off of 0 gives the identity).
    pub fn butterworth2(
        cutoff_hz: f64,
        sample_rate_hz: f64,
        channels: usize,
    ) -> Result<Self, SimError> {
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(SimError::config(
                "sample_rate_hz",
                format!("must be > 0, got {sample_rate_hz}"),
            ));
        }
        if !(cutoff_hz.is_finite() && cutoff_hz >= 0.0 && cutoff_hz < 0.5 * sample_rate_hz) {
            return Err(SimError::config(
                "filter_cutoff_hz",
                format!(
                    "must be in [0, {}) Hz, got {cutoff_hz}",
                    0.5 * sample_rate_hz
                ),
            ));
        }
        let passthrough = cutoff_hz == 0.0;
        let (b, a) = if passthrough {
            ([1.0, 0.0, 0.0], [0.0, 0.0])
        } else {
            let k = (std::f64::consts::PI * cutoff_hz / sample_rate_hz).tan();
            let k2 = k * k;
            let sqrt2 = std::f64::consts::SQRT_2;
            let norm = 1.0 / (1.0 + sqrt2 * k + k2);
            let b0 = k2 * norm;
            (
                [b0, 2.0 * b0, b0],
                [2.0 * (k2 - 1.0) * norm, (1.0 - sqrt2 * k + k2) * norm],
            )
        };
        Ok(Self {
            b,
            a,
            passthrough,
            x1: vec![0.0; channels],
            x2: vec![0.0; channels],
            y1: vec![0.0; channels],
            y2: vec![0.0; channels],
            started: vec![false; channels],
        })
    }

    /// Filters one sample of channel `ch`.
    #[inline]
    pub fn update(&mut self, ch: usize, x: f64) -> f64 {
        if self.passthrough {
            return x;
        }
        if !self.started[ch] {
            self.started[ch] = true;
            self.x1[ch] = x;
            self.x2[ch] = x;
            self.y1[ch] = x;
            self.y2[ch] = x;
            return x;
        }
        let y = self.b[0] * x + self.b[1] * self.x1[ch] + self.b[2] * self.x2[ch]
            - self.a[0] * self.y1[ch]
            - self.a[1] * self.y2[ch];
        self.x2[ch] = self.x1[ch];
        self.x1[ch] = x;
        self.y2[ch] = self.y1[ch];
        self.y1[ch] = y;
        y
    }

    /// Forgets the history of every channel.
    pub fn reset(&mut self) {
        self.started.fill(false);
    }

    /// Forgets the history of channel `ch`: its next sample starts it at steady state.
    pub fn restart(&mut self, ch: usize) {
        if let Some(s) = self.started.get_mut(ch) {
            *s = false;
        }
    }

    /// Numerator `[b0, b1, b2]` and denominator `[a1, a2]` (with `a0 = 1`).
    pub fn coefficients(&self) -> ([f64; 3], [f64; 2]) {
        (self.b, self.a)
    }

    /// Group delay at zero frequency, in samples.
    pub fn dc_group_delay(&self) -> f64 {
        if self.passthrough {
            return 0.0;
        }
        let (b, a) = (self.b, self.a);
        let num = (b[1] + 2.0 * b[2]) / (b[0] + b[1] + b[2]);
        let den = (a[0] + 2.0 * a[1]) / (1.0 + a[0] + a[1]);
        num - den
    }
}

/// One sample of the sensors, as the controller receives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// When the sample was delivered (s).
    pub time: f64,
    /// When each joint's sample was taken: older than `time` for a stale sample.
    pub sample_time: Vec<f64>,
    /// Encoder angles, quantised and noisy, unfiltered (NaN on an injected NaN fault).
    pub q: Vec<f64>,
    /// Low-pass filtered angles.
    pub q_filtered: Vec<f64>,
    /// Backward difference of `q_filtered`.
    pub qdot: Vec<f64>,
    /// Backward difference of `qdot`.
    pub qddot: Vec<f64>,
    /// The command passed in (held over the period that just ended; non-finite values as 0).
    pub tau_commanded: Vec<f64>,
    /// `tau_commanded` through the same low-pass as `q_filtered`.
    pub tau_filtered: Vec<f64>,
    /// Ground truth of fault injection: this joint's sample was replaced by NaN.
    pub injected_nan: Vec<bool>,
    /// Ground truth of fault injection: this joint's sample repeats the previous one.
    pub injected_stale: Vec<bool>,
}

impl Measurement {
    fn new(n: usize) -> Self {
        Self {
            time: 0.0,
            sample_time: vec![0.0; n],
            q: vec![0.0; n],
            q_filtered: vec![0.0; n],
            qdot: vec![0.0; n],
            qddot: vec![0.0; n],
            tau_commanded: vec![0.0; n],
            tau_filtered: vec![0.0; n],
            injected_nan: vec![false; n],
            injected_stale: vec![false; n],
        }
    }

    /// Whether every signal the controller would use is finite.
    pub fn is_finite(&self) -> bool {
        [&self.q, &self.q_filtered, &self.qdot, &self.qddot]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
    }
}

#[derive(Clone, Debug)]
struct Fault {
    kind: FaultKind,
    mask: Vec<bool>,
    start: f64,
    end: f64,
}

/// The encoders and differentiators of a plant (built from a [`SensorConfig`]).
#[derive(Clone, Debug)]
pub struct Sensors {
    n: usize,
    dt: f64,
    resolution: f64,
    noise_std: f64,
    seed: u64,
    rng: ChaCha8Rng,
    q_filter: LowPass,
    tau_filter: LowPass,
    faults: Vec<Fault>,
    last_raw: Vec<f64>,
    last_raw_time: Vec<f64>,
    have_raw: Vec<bool>,
    /// Valid samples seen per joint (saturates at 2).
    valid: Vec<u8>,
    prev_qf: Vec<f64>,
    prev_qdot: Vec<f64>,
    measurement: Measurement,
}

impl Sensors {
    /// Sensors for `model`'s joints sampled at `sample_rate_hz` (normally the control rate).
    pub fn new(
        model: &Model,
        config: &SensorConfig,
        sample_rate_hz: f64,
    ) -> Result<Self, SimError> {
        config.validate(model, sample_rate_hz, "sensors")?;
        let n = model.nq();
        let faults = config
            .faults
            .iter()
            .map(|f| {
                let mut mask = vec![f.joints.is_empty(); n];
                for name in &f.joints {
                    if let Some(i) = model.joint_index(name) {
                        mask[i] = true;
                    }
                }
                Fault {
                    kind: f.kind,
                    mask,
                    start: f.t_start,
                    end: f.t_end,
                }
            })
            .collect();
        Ok(Self {
            n,
            dt: 1.0 / sample_rate_hz,
            resolution: config.resolution(),
            noise_std: config.noise_std,
            seed: config.seed,
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            q_filter: LowPass::butterworth2(config.filter_cutoff_hz, sample_rate_hz, n)?,
            tau_filter: LowPass::butterworth2(config.filter_cutoff_hz, sample_rate_hz, n)?,
            faults,
            last_raw: vec![0.0; n],
            last_raw_time: vec![0.0; n],
            have_raw: vec![false; n],
            valid: vec![0; n],
            prev_qf: vec![0.0; n],
            prev_qdot: vec![0.0; n],
            measurement: Measurement::new(n),
        })
    }

    /// Back to the state before the first sample, the noise stream restarted from the seed.
    pub fn reset(&mut self) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
        self.q_filter.reset();
        self.tau_filter.reset();
        self.have_raw.fill(false);
        self.valid.fill(0);
        self.prev_qf.fill(0.0);
        self.prev_qdot.fill(0.0);
        self.measurement = Measurement::new(self.n);
    }

    /// Sample period (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The filter applied to q and tau (for its delay).
    pub fn filter(&self) -> &LowPass {
        &self.q_filter
    }

    /// The last measurement.
    pub fn measurement(&self) -> &Measurement {
        &self.measurement
    }

    /// Takes a sample at `time` of the true angles `q_true`, with `tau_commanded` the
    /// command held over the period that just ended. Does not allocate.
    pub fn sample(
        &mut self,
        time: f64,
        q_true: &[f64],
        tau_commanded: &[f64],
    ) -> Result<&Measurement, SimError> {
        check_len("q_true", q_true, self.n)?;
        check_len("tau_commanded", tau_commanded, self.n)?;
        let dt = self.dt;
        let m = &mut self.measurement;
        m.time = time;
        for i in 0..self.n {
            let noise: f64 = self.rng.sample(StandardNormal);
            let mut nan = false;
            let mut stale = false;
            for f in &self.faults {
                if f.mask[i] && f.start <= time && time < f.end {
                    match f.kind {
                        FaultKind::Nan => nan = true,
                        FaultKind::Stale => stale = true,
                    }
                }
            }
            stale &= self.have_raw[i];
            m.injected_nan[i] = nan && !stale;
            m.injected_stale[i] = stale;
            let raw = if stale {
                m.sample_time[i] = self.last_raw_time[i];
                self.last_raw[i]
            } else if nan {
                m.sample_time[i] = time;
                f64::NAN
            } else {
                let mut x = q_true[i] + self.noise_std * noise;
                if self.resolution > 0.0 {
                    x = (x / self.resolution).round() * self.resolution;
                }
                self.last_raw[i] = x;
                self.last_raw_time[i] = time;
                self.have_raw[i] = true;
                m.sample_time[i] = time;
                x
            };
            m.q[i] = raw;
            if raw.is_finite() {
                let qf = self.q_filter.update(i, raw);
                match self.valid[i] {
                    0 => {
                        m.qdot[i] = 0.0;
                        m.qddot[i] = 0.0;
                    }
                    1 => {
                        m.qdot[i] = (qf - self.prev_qf[i]) / dt;
                        m.qddot[i] = 0.0;
                    }
                    _ => {
                        m.qdot[i] = (qf - self.prev_qf[i]) / dt;
                        m.qddot[i] = (m.qdot[i] - self.prev_qdot[i]) / dt;
                    }
                }
                m.q_filtered[i] = qf;
                self.prev_qf[i] = qf;
                self.prev_qdot[i] = m.qdot[i];
                self.valid[i] = (self.valid[i] + 1).min(2);
            } else if self.valid[i] == 0 {
                // Nothing valid yet: no filtered angle to hold.
                m.q_filtered[i] = f64::NAN;
                m.qdot[i] = 0.0;
                m.qddot[i] = 0.0;
            }
            let tau = if tau_commanded[i].is_finite() {
                tau_commanded[i]
            } else {
                0.0
            };
            m.tau_commanded[i] = tau;
            m.tau_filtered[i] = self.tau_filter.update(i, tau);
        }
        Ok(&self.measurement)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn butterworth_has_unit_dc_gain_and_half_power_at_cutoff() {
        let (fs, fc) = (1000.0, 20.0);
        let lp = LowPass::butterworth2(fc, fs, 1).unwrap();
        let (b, a) = lp.coefficients();
        assert!(((b[0] + b[1] + b[2]) / (1.0 + a[0] + a[1]) - 1.0).abs() < 1e-12);
        // |H(e^{jw})| at the cut-off = 1/sqrt(2) (pre-warped bilinear transform).
        let w = std::f64::consts::TAU * fc / fs;
        let z = |k: f64| nalgebra::Complex::new((k * w).cos(), -(k * w).sin());
        let num = z(0.0) * b[0] + z(1.0) * b[1] + z(2.0) * b[2];
        let den = z(0.0) + z(1.0) * a[0] + z(2.0) * a[1];
        assert!(((num / den).norm() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-9);
        assert!(lp.dc_group_delay() > 0.0);
    }

    #[test]
    fn filter_starts_at_steady_state() {
        let mut lp = LowPass::butterworth2(10.0, 1000.0, 1).unwrap();
        for _ in 0..10 {
            assert!((lp.update(0, 3.0) - 3.0).abs() < 1e-12);
        }
    }
}
