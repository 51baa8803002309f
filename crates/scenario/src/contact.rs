//! The contact floor from a free-motion recording, and the false alarms a floor raises on
//! one (issue 31): the momentum observer on the identification, fed as at run time (the
//! identification's input conditioning, causal), then the calibration or the detector.

use admittance_control::{
    calibrate_contact_with, ConfigError, ContactCalibrationConfig, ContactDetector, ContactFloor,
    ContactState, MomentumObserver, MomentumObserverConfig, Observer, ObserverInput,
};
use admittance_dynamics::Identification;

use crate::free_motion::{observer_training_arrays, FreeMotionData};

/// The first stretch of a recording left out of the calibration and the counts (s): the
/// conditioning's derivatives and the observer start from rest there.
pub const CONTACT_WARM_UP_S: f64 = 1.0;

/// The momentum observer's estimate over a recording, with the velocities and
/// accelerations the detector sees (row-major, `joints` per sample).
#[derive(Clone, Debug, PartialEq)]
pub struct FreeMotionEstimates {
    /// Joints per sample.
    pub joints: usize,
    /// Sample times (s).
    pub t: Vec<f64>,
    /// The external-torque estimate (N m): in free motion, the false torque.
    pub estimate: Vec<f64>,
    /// Velocities as the observer sees them (rad/s).
    pub qdot: Vec<f64>,
    /// Accelerations as the observer sees them (rad/s^2).
    pub qddot: Vec<f64>,
}

impl FreeMotionEstimates {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there is no sample.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The mean sample period (s).
    pub fn mean_dt(&self) -> f64 {
        let span = self.t.last().copied().unwrap_or(0.0) - self.t.first().copied().unwrap_or(0.0);
        span / (self.len().max(2) - 1) as f64
    }

    /// The estimate through the loop's first-order low-pass at `cutoff_hz`
    /// (`observer.cutoff_hz`; 0 leaves it as it is), as the run's estimate passes it.
    pub fn low_passed(mut self, cutoff_hz: f64) -> Result<Self, ConfigError> {
        if cutoff_hz == 0.0 || self.is_empty() {
            return Ok(self);
        }
        let rate = 1.0 / self.mean_dt();
        let mut filter = admittance_loop::EstimateLowPass::new(self.joints, cutoff_hz, rate)
            .map_err(admittance_loop::LoopError::into_setting)?;
        for row in self.estimate.chunks_exact_mut(self.joints) {
            let y = filter.update(row);
            row.copy_from_slice(y);
        }
        Ok(self)
    }

    /// Several recordings' estimates as one series, each continuing one mean sample period
    /// after the last (their sample periods must agree within 1 %: the floor counts events
    /// per hour from the number of samples).
    pub fn pooled(parts: &[FreeMotionEstimates]) -> Result<FreeMotionEstimates, ConfigError> {
        let nonempty: Vec<&FreeMotionEstimates> = parts.iter().filter(|p| p.len() > 1).collect();
        let Some(first) = nonempty.first() else {
            return Ok(parts.first().cloned().unwrap_or(FreeMotionEstimates {
                joints: 0,
                t: Vec::new(),
                estimate: Vec::new(),
                qdot: Vec::new(),
                qddot: Vec::new(),
            }));
        };
        let dt = first.mean_dt();
        let mut out = FreeMotionEstimates {
            joints: first.joints,
            t: Vec::new(),
            estimate: Vec::new(),
            qdot: Vec::new(),
            qddot: Vec::new(),
        };
        for (i, p) in nonempty.iter().enumerate() {
            if p.joints != out.joints || (p.mean_dt() - dt).abs() > 0.01 * dt {
                return Err(ConfigError::new(
                    format!("data[{i}]"),
                    format!(
                        "is sampled every {:.6} s with {} joints, the first recording every \
                         {dt:.6} s with {}; resample the recordings to one rate",
                        p.mean_dt(),
                        p.joints,
                        out.joints
                    ),
                ));
            }
            let offset = out.t.last().map_or(0.0, |t| t + dt) - p.t[0];
            out.t.extend(p.t.iter().map(|t| t + offset));
            out.estimate.extend_from_slice(&p.estimate);
            out.qdot.extend_from_slice(&p.qdot);
            out.qddot.extend_from_slice(&p.qddot);
        }
        Ok(out)
    }

    /// The samples from `from_s` after the first on.
    pub fn after(&self, from_s: f64) -> FreeMotionEstimates {
        let t0 = self.t.first().copied().unwrap_or(0.0);
        let k = self
            .t
            .iter()
            .position(|t| t - t0 >= from_s)
            .unwrap_or(self.len());
        let n = self.joints;
        FreeMotionEstimates {
            joints: n,
            t: self.t[k..].to_vec(),
            estimate: self.estimate[k * n..].to_vec(),
            qdot: self.qdot[k * n..].to_vec(),
            qddot: self.qddot[k * n..].to_vec(),
        }
    }
}

/// Runs the momentum observer on `identification` over `data` (conditioned at the
/// identification's `input_filter_hz` and paired with its torque delay, as the observers
/// are at run time).
pub fn momentum_estimates(
    data: &FreeMotionData,
    identification: &Identification,
    observer: &MomentumObserverConfig,
) -> Result<FreeMotionEstimates, ConfigError> {
    momentum_estimates_at(
        data,
        identification,
        observer,
        identification.summary.input_filter_hz,
    )
}

/// [`momentum_estimates`] with the inputs conditioned at `filter_hz` (a scenario's
/// `observer.input_filter_hz`, which its identification was fitted at).
pub fn momentum_estimates_at(
    data: &FreeMotionData,
    identification: &Identification,
    observer: &MomentumObserverConfig,
    filter_hz: f64,
) -> Result<FreeMotionEstimates, ConfigError> {
    let n = data.dof();
    if n != identification.model.nq() {
        return Err(ConfigError::new(
            "data",
            format!(
                "has {n} joints, the identification {}",
                identification.model.nq()
            ),
        ));
    }
    let (x, tau) = observer_training_arrays(data, filter_hz)
        .map_err(|e| e.at("input_filter_hz").into_setting())?;
    let mut obs = MomentumObserver::from_identification(identification, observer)?;
    let mut out = FreeMotionEstimates {
        joints: n,
        t: data.t.clone(),
        estimate: Vec::with_capacity(data.len() * n),
        qdot: Vec::with_capacity(data.len() * n),
        qddot: Vec::with_capacity(data.len() * n),
    };
    let mut estimate = vec![0.0; n];
    // The identification's torque delay, applied as the run-time loop applies it.
    let rate = crate::identify_recording::sample_rate_hz(data);
    let mut delay = admittance_loop::InputDelay::new(&identification.summary.delay_s, rate)
        .map_err(|e| e.at("identification").into_setting())?;
    let mut delayed = vec![0.0; 4 * n];
    for k in 0..data.len() {
        let mut row = &x[k * 3 * n..(k + 1) * 3 * n];
        let mut torque = &tau[k * n..(k + 1) * n];
        if let Some(d) = delay.as_mut() {
            let (q, rest) = row.split_at(n);
            let (qd, qdd) = rest.split_at(n);
            delayed.copy_from_slice(d.update(q, qd, qdd, torque));
            row = &delayed[..3 * n];
            torque = &delayed[3 * n..];
        }
        let dt = if k == 0 {
            data.t.get(1).map_or(1e-3, |t1| t1 - data.t[0])
        } else {
            data.t[k] - data.t[k - 1]
        };
        let input = ObserverInput {
            time: data.t[k],
            q: &row[..n],
            qdot: &row[n..2 * n],
            qddot: &row[2 * n..],
            tau_commanded: torque,
        };
        if !obs.update(&input, dt, &mut estimate).is_ok() {
            estimate.iter_mut().for_each(|e| *e = 0.0);
        }
        out.estimate.extend_from_slice(&estimate);
        out.qdot.extend_from_slice(&row[n..2 * n]);
        out.qddot.extend_from_slice(&row[2 * n..]);
    }
    Ok(out)
}

/// The contact floor of `data` (free motion `identification` did not fit), after the
/// warm-up, with the joint names, and the data it was made from in `source`.
pub fn calibrate_contact_on(
    data: &FreeMotionData,
    identification: &Identification,
    observer: &MomentumObserverConfig,
    config: &ContactCalibrationConfig,
) -> Result<ContactFloor, ConfigError> {
    calibrate_contact_on_all(std::slice::from_ref(data), identification, observer, config)
}

/// [`calibrate_contact_on`] over several recordings of free motion: each runs through its own
/// observer and loses its own warm-up, and their estimates are pooled (a floor is only as
/// good as the variety of its motion: several short recordings at other speeds and poses
/// hold more of it than one long one).
pub fn calibrate_contact_on_all(
    recordings: &[FreeMotionData],
    identification: &Identification,
    observer: &MomentumObserverConfig,
    config: &ContactCalibrationConfig,
) -> Result<ContactFloor, ConfigError> {
    let Some(first) = recordings.first() else {
        return Err(ConfigError::new("data", "no recording was given"));
    };
    let mut parts = Vec::with_capacity(recordings.len());
    for (i, data) in recordings.iter().enumerate() {
        // Which recording is at fault, when there are several: its index is the key.
        let located = |e: ConfigError| match recordings.len() {
            1 => e,
            _ => ConfigError {
                key: format!("data[{i}]"),
                message: match e.key.as_str() {
                    "" | "data" => e.message,
                    key => format!("`{key}` {}", e.message),
                },
                hint: e.hint,
            },
        };
        if data.joints != first.joints {
            return Err(located(ConfigError::new(
                "joints",
                format!(
                    "are {:?}, recording 0 has {:?}; give recordings of one arm",
                    data.joints, first.joints
                ),
            )));
        }
        parts.push(momentum_estimates(data, identification, observer).map_err(located)?);
    }
    floor_of_estimates(&parts, &first.joints, identification, observer, config)
}

/// The contact floor of the momentum observer's estimates over one or more recordings of
/// free motion (each after its warm-up, then pooled), recording what they were made with.
pub fn floor_of_estimates(
    recordings: &[FreeMotionEstimates],
    joints: &[String],
    identification: &Identification,
    observer: &MomentumObserverConfig,
    config: &ContactCalibrationConfig,
) -> Result<ContactFloor, ConfigError> {
    let parts: Vec<FreeMotionEstimates> = recordings
        .iter()
        .map(|e| e.after(CONTACT_WARM_UP_S))
        .collect();
    let e = FreeMotionEstimates::pooled(&parts)?;
    let mut floor = calibrate_contact_with(
        &e.estimate,
        &e.qdot,
        &e.qddot,
        e.joints,
        e.mean_dt(),
        config,
    )?;
    floor.joints = joints.to_vec();
    floor.source.insert("observer".into(), "momentum".into());
    floor.source.insert(
        "observer_gain".into(),
        serde_json::to_value(&observer.gain).unwrap_or_default(),
    );
    floor.source.insert(
        "input_filter_hz".into(),
        identification.summary.input_filter_hz.into(),
    );
    floor
        .source
        .insert("warm_up_s".into(), CONTACT_WARM_UP_S.into());
    if parts.len() > 1 {
        floor.source.insert("recordings".into(), parts.len().into());
    }
    Ok(floor)
}

/// The false alarms a floor raises on a recording of free motion.
#[derive(Clone, Debug, PartialEq)]
pub struct FalseAlarms {
    /// Length counted (s), after the warm-up.
    pub duration_s: f64,
    /// Contact events (rising edges of the flag), all joints together.
    pub contact_events: usize,
    /// Collision events.
    pub collision_events: usize,
    /// Contact events that started on each joint (the last loaded joint at the rising edge).
    pub contact_events_by_link: Vec<usize>,
    /// Fraction of the samples flagged as contact.
    pub contact_fraction: f64,
}

impl FalseAlarms {
    /// Contact events per hour.
    pub fn contact_per_hour(&self) -> f64 {
        self.contact_events as f64 * 3600.0 / self.duration_s.max(f64::MIN_POSITIVE)
    }
    /// Collision events per hour.
    pub fn collision_per_hour(&self) -> f64 {
        self.collision_events as f64 * 3600.0 / self.duration_s.max(f64::MIN_POSITIVE)
    }
}

/// The flags of `floor`'s detector over `estimates`, sample by sample.
pub fn detect(
    floor: &ContactFloor,
    estimates: &FreeMotionEstimates,
) -> Result<Vec<ContactState>, ConfigError> {
    let n = estimates.joints;
    if floor.dof() != n {
        return Err(ConfigError::new(
            "contact_thresholds",
            format!(
                "the floor is for {} joints, the recording has {n}",
                floor.dof()
            ),
        ));
    }
    let mut det = ContactDetector::new(floor)?;
    Ok((0..estimates.len())
        .map(|k| {
            let r = k * n..(k + 1) * n;
            det.update(
                &estimates.estimate[r.clone()],
                &estimates.qdot[r.clone()],
                &estimates.qddot[r],
            )
        })
        .collect())
}

/// Counts the false alarms of `floor` on `estimates` (free motion: every flag is false).
pub fn count_false_alarms(
    floor: &ContactFloor,
    estimates: &FreeMotionEstimates,
) -> Result<FalseAlarms, ConfigError> {
    let states = detect(floor, estimates)?;
    let mut out = FalseAlarms {
        duration_s: estimates.mean_dt() * estimates.len() as f64,
        contact_events: 0,
        collision_events: 0,
        contact_events_by_link: vec![0; estimates.joints],
        contact_fraction: 0.0,
    };
    let mut last = ContactState::default();
    let mut flagged = 0usize;
    for s in &states {
        if s.contact && !last.contact {
            out.contact_events += 1;
            if let Some(c) = out.contact_events_by_link.get_mut(s.link.max(0) as usize) {
                *c += 1;
            }
        }
        out.collision_events += usize::from(s.collision && !last.collision);
        flagged += usize::from(s.contact);
        last = *s;
    }
    out.contact_fraction = flagged as f64 / states.len().max(1) as f64;
    Ok(out)
}
