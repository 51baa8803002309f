//! What the controller sees (docs/method.md sections 1 and 7): encoder angles with
//! quantisation and Gaussian noise, and velocities and accelerations only by numerical
//! differentiation of the low-pass-filtered angles. The commanded torque passes through
//! the same filter, so that an observer can pair signals with matching delays.
//!
//! Per sample (one per control period) and joint, `q = quantise(q_true + noise)`, noise
//! `N(0, noise_std^2)` from a seeded ChaCha8 stream (one draw per joint per sample whatever
//! the faults, so the stream does not depend on them); quantisation rounds to the nearest
//! multiple of the resolution. The readings then pass the real signal chain
//! ([`admittance_loop::SignalChain`]: 2nd-order Butterworth low-pass at
//! `filter_cutoff_hz`, numerical differentiation, the command through the same filter),
//! the same code a robot program runs on its encoders.
//!
//! Fault injection (for tests of the safe behaviour): in a time window, selected joints
//! deliver a NaN sample, or a stale sample (the previous raw value repeated, with its old
//! `Measurement::sample_time`). A NaN reaches `Measurement::q` as NaN; the joint's
//! filter, velocity and acceleration hold their previous values, so the derived signals
//! stay finite. The injected NaN and stale faults are reported in the measurement as
//! ground truth. A spike (`angle_spike`, `torque_spike`) delivers one finite but absurd
//! reading (`value`, e.g. an angle of 1e20 rad or a torque of 1e300 N m) in place of the
//! angle or the torque: finiteness checks pass it, only plausibility gates
//! (`admittance_loop::PlausibilityGates`, given to [`Sensors::sample_screened`]) stop it.
//! A window shorter than one period (`t_start = 2.0, t_end = 2.0005` at 1 kHz) gives a
//! single sample.

use admittance_dynamics::Model;
use admittance_loop::{LowPass, Measurement, SignalChain};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::checks::{finite, joint_index, non_negative, window};
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
            filter_cutoff_hz: admittance_loop::DEFAULT_SIGNAL_CUTOFF_HZ,
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
    /// The angle reads `value` (rad or m): finite, however absurd.
    AngleSpike,
    /// The torque reading (the command held over the period, or a robot's measured
    /// torque) is `value` (N m).
    TorqueSpike,
}

/// What a spike reads when its `value` is not given.
pub const DEFAULT_SPIKE_VALUE: f64 = 1e20;

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
    /// The reading of an `angle_spike` (rad or m) or `torque_spike` (N m): finite, only
    /// for those kinds. Default (absent) [`DEFAULT_SPIKE_VALUE`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
}

impl Default for FaultConfig {
    fn default() -> Self {
        Self {
            kind: FaultKind::Nan,
            joints: Vec::new(),
            t_start: 0.0,
            t_end: f64::INFINITY,
            value: None,
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
            if let Some(v) = f.value {
                if matches!(f.kind, FaultKind::Nan | FaultKind::Stale) {
                    return Err(SimError::config(
                        format!("{p}.value"),
                        "is the reading of a spike: give it only with kind = \"angle_spike\" or \"torque_spike\"",
                    ));
                }
                finite(|| format!("{p}.value"), v)?;
            }
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

#[derive(Clone, Debug)]
struct Fault {
    kind: FaultKind,
    mask: Vec<bool>,
    start: f64,
    end: f64,
    value: f64,
}

impl Fault {
    fn hits(&self, i: usize, time: f64) -> bool {
        self.mask[i] && self.start <= time && time < self.end
    }
}

/// The fake encoders of a plant (built from a [`SensorConfig`]): noise, quantisation and
/// injected faults in front of the real signal chain.
#[derive(Clone, Debug)]
pub struct Sensors {
    n: usize,
    resolution: f64,
    noise_std: f64,
    seed: u64,
    rng: ChaCha8Rng,
    faults: Vec<Fault>,
    last_raw: Vec<f64>,
    last_raw_time: Vec<f64>,
    have_raw: Vec<bool>,
    /// This sample's readings, their sample times and the faults injected in them.
    raw: Vec<f64>,
    raw_time: Vec<f64>,
    raw_tau: Vec<f64>,
    injected_nan: Vec<bool>,
    injected_stale: Vec<bool>,
    chain: SignalChain,
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
                    value: f.value.unwrap_or(DEFAULT_SPIKE_VALUE),
                }
            })
            .collect();
        let chain = SignalChain::new(n, config.filter_cutoff_hz, sample_rate_hz)
            .map_err(|e| e.at("sensors.filter_cutoff_hz"))?;
        Ok(Self {
            n,
            resolution: config.resolution(),
            noise_std: config.noise_std,
            seed: config.seed,
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            faults,
            last_raw: vec![0.0; n],
            last_raw_time: vec![0.0; n],
            have_raw: vec![false; n],
            raw: vec![0.0; n],
            raw_time: vec![0.0; n],
            raw_tau: vec![0.0; n],
            injected_nan: vec![false; n],
            injected_stale: vec![false; n],
            chain,
        })
    }

    /// Back to the state before the first sample, the noise stream restarted from the seed.
    pub fn reset(&mut self) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
        self.have_raw.fill(false);
        self.chain.reset();
    }

    /// Sample period (s).
    pub fn dt(&self) -> f64 {
        self.chain.dt()
    }

    /// The filter applied to q and tau (for its delay).
    pub fn filter(&self) -> &LowPass {
        self.chain.filter()
    }

    /// The last measurement.
    pub fn measurement(&self) -> &Measurement {
        self.chain.measurement()
    }

    /// Takes a sample at `time` of the true angles `q_true`, with `tau_commanded` the
    /// command held over the period that just ended. Does not allocate.
    pub fn sample(
        &mut self,
        time: f64,
        q_true: &[f64],
        tau_commanded: &[f64],
    ) -> Result<&Measurement, SimError> {
        self.sample_screened(time, q_true, tau_commanded, |_, _, _| {})
    }

    /// As [`Sensors::sample`], with `screen(time, angles, torques)` run on the raw
    /// readings before the signal chain sees them, where a robot program runs its
    /// plausibility gates (`admittance_loop::RobotLoop`): a value it sets to NaN takes the
    /// NaN path. Does not allocate.
    pub fn sample_screened(
        &mut self,
        time: f64,
        q_true: &[f64],
        tau_commanded: &[f64],
        screen: impl FnOnce(f64, &mut [f64], &mut [f64]),
    ) -> Result<&Measurement, SimError> {
        check_len("q_true", q_true, self.n)?;
        check_len("tau_commanded", tau_commanded, self.n)?;
        for (i, &q) in q_true.iter().enumerate() {
            self.read_encoder(i, time, q);
            self.raw_tau[i] = tau_commanded[i];
            for f in &self.faults {
                if f.kind == FaultKind::TorqueSpike && f.hits(i, time) {
                    self.raw_tau[i] = f.value;
                }
            }
        }
        screen(time, &mut self.raw, &mut self.raw_tau);
        self.chain
            .sample_at(time, &self.raw, &self.raw_time, &self.raw_tau)?;
        let m = self.chain.measurement_mut();
        m.injected_nan.copy_from_slice(&self.injected_nan);
        m.injected_stale.copy_from_slice(&self.injected_stale);
        Ok(self.chain.measurement())
    }

    /// Joint `i`'s reading at `time`: noise and quantisation, or an injected fault.
    fn read_encoder(&mut self, i: usize, time: f64, q_true: f64) {
        let noise: f64 = self.rng.sample(StandardNormal);
        let mut nan = false;
        let mut stale = false;
        let mut spike = None;
        for f in &self.faults {
            if f.hits(i, time) {
                match f.kind {
                    FaultKind::Nan => nan = true,
                    FaultKind::Stale => stale = true,
                    FaultKind::AngleSpike => spike = Some(f.value),
                    FaultKind::TorqueSpike => {}
                }
            }
        }
        stale &= self.have_raw[i];
        self.injected_nan[i] = nan && !stale;
        self.injected_stale[i] = stale;
        self.raw[i] = if stale {
            self.raw_time[i] = self.last_raw_time[i];
            self.last_raw[i]
        } else if nan {
            self.raw_time[i] = time;
            f64::NAN
        } else if let Some(value) = spike {
            // Not kept as the last reading: a stale fault repeats the last genuine one.
            self.raw_time[i] = time;
            value
        } else {
            let mut x = q_true + self.noise_std * noise;
            if self.resolution > 0.0 {
                x = (x / self.resolution).round() * self.resolution;
            }
            self.last_raw[i] = x;
            self.last_raw_time[i] = time;
            self.have_raw[i] = true;
            self.raw_time[i] = time;
            x
        };
    }
}
