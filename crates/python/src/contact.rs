//! Contact and collision detection from Python (issue 31): `calibrate_contact`, the
//! `ContactFloor` it returns (`save`, `load_contact_floor`) and `ContactDetector`, the
//! momentum observer on the identification (with the identification's input conditioning)
//! followed by the floor's detector.

use std::path::PathBuf;

use admittance_control::{
    ContactCalibrationConfig, ContactDetector, ContactFloor, ContactState, JointValues,
    MomentumObserver, MomentumObserverConfig, Observer, ObserverInput,
};
use admittance_loop::{InputConditioner, InputDelay};
use admittance_scenario::FreeMotionData;
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::convert::{config_error, read_vector, value_error, vector_out};
use crate::free_motion::{data_arg, DataArg};
use crate::identification::PyIdentification;

const JOINTS: &str = "one value per joint, in chain order";

/// Per-joint contact and collision thresholds (N m at standstill) for a stated false-alarm rate,
/// from `calibrate_contact` or `load_contact_floor`. `describe()` prints the floor with what
/// it guarantees and under which assumption; `save(path)` writes its versioned file.
#[pyclass(frozen, module = "admittance._admittance", name = "ContactFloor")]
pub struct PyContactFloor {
    pub(crate) floor: ContactFloor,
}

#[pymethods]
impl PyContactFloor {
    /// Contact level per joint at rest (N m), `(n,)`.
    #[getter]
    fn contact_thresholds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.floor.contact_thresholds)
    }
    /// Collision level per joint at rest (N m), `(n,)`.
    #[getter]
    fn collision_thresholds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.floor.collision_thresholds)
    }
    /// Relative growth of the levels per rad/s of the joint's speed, `(n,)`.
    #[getter]
    fn speed_gain<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.floor.speed_gain)
    }
    /// Relative growth of the levels per rad/s^2 of the joint's acceleration, `(n,)`.
    #[getter]
    fn acceleration_gain<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.floor.acceleration_gain)
    }
    /// The fraction the levels drop by once the joint moves faster than `rest_width`, `(n,)`
    /// (the false torque peaks at reversals).
    #[getter]
    fn moving_drop<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let n = self.floor.dof();
        let v: Vec<f64> = (0..n)
            .map(|i| self.floor.moving_drop.get(i).copied().unwrap_or(0.0))
            .collect();
        PyArray1::from_vec(py, v)
    }
    /// The contact levels (N m) at velocities `qdot` and accelerations `qddot`, `(n,)` or
    /// `(N, n)` as given: the detector's own levels (contact_thresholds times the floor's
    /// factor).
    fn contact_levels<'py>(
        &self,
        py: Python<'py>,
        qdot: &Bound<'py, PyAny>,
        qddot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.floor.dof();
        let (v, steps, single) = crate::convert::rows(qdot, "qdot", n, true)?;
        let (a, steps_a, _) = crate::convert::rows(qddot, "qddot", n, true)?;
        if steps_a != steps {
            return Err(value_error(format!(
                "contact_levels: qdot has {steps} rows, qddot {steps_a}"
            )));
        }
        let level = |k: usize, i: usize| self.floor.contact_level(i, v[k * n + i], a[k * n + i]);
        if single {
            let out: Vec<f64> = (0..n).map(|i| level(0, i)).collect();
            return Ok(PyArray1::from_vec(py, out).into_any());
        }
        Ok(crate::convert::matrix_out(py, (steps, n), level, None, "out")?.into_any())
    }
    /// The smallest steady torque detected at rest with 95 % probability per sample (N m).
    #[getter]
    fn smallest_detected<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.floor.calibration.smallest_detected)
    }
    /// The promised false contact events per hour, all joints together.
    #[getter]
    fn false_alarms_per_hour(&self) -> f64 {
        self.floor.false_alarms_per_hour
    }
    /// The floor's whole content as JSON text (what `save` writes as the payload).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.floor).map_err(|e| value_error(e.to_string()))
    }
    /// The floor as a table with its guarantee and assumption.
    fn describe(&self) -> String {
        self.floor.describe()
    }
    fn __repr__(&self) -> String {
        format!(
            "ContactFloor({} joints, {} false alarms per hour)",
            self.floor.dof(),
            self.floor.false_alarms_per_hour
        )
    }
    /// Writes the floor atomically as a versioned, checksummed JSON file (an existing file
    /// is replaced only when it is a contact floor).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.floor
            .save(&path)
            .map_err(|e| value_error(e.to_string()))
    }
}

/// Reads a contact-floor file (`ContactFloor.save`, `admittance calibrate-contact`).
#[pyfunction]
pub fn load_contact_floor(path: PathBuf) -> PyResult<PyContactFloor> {
    let floor = ContactFloor::load(&path).map_err(|e| value_error(e.to_string()))?;
    Ok(PyContactFloor { floor })
}

fn free_motion(py: Python<'_>, data: DataArg) -> PyResult<FreeMotionData> {
    match data {
        DataArg::Csv(path) => crate::free_motion::load_csv(py, &path),
        DataArg::Arrays(d) => Ok(d),
    }
}

/// The contact floor of the momentum observer on `ident` from free motion `data` that the
/// identification did not fit (a CSV path or a dict of arrays, as for `identify`, or a list
/// of them: several recordings pooled, each after its own warm-up): per joint, the levels
/// whose false events occur `false_alarms_per_hour` times per hour, all joints together
/// (docs/method.md section 5, "Contact"). `gain`: the observer's K_O (1/s);
/// `constant=True`: levels that do not grow with speed and acceleration.
#[pyfunction]
#[pyo3(signature = (data, ident, false_alarms_per_hour=1.0, gain=50.0, constant=false))]
pub fn calibrate_contact(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    ident: &Bound<'_, PyIdentification>,
    false_alarms_per_hour: f64,
    gain: f64,
    constant: bool,
) -> PyResult<PyContactFloor> {
    let id = ident.get().identification.clone();
    let joints: Vec<String> = id.model.joint_names().map(String::from).collect();
    let given: Vec<DataArg> = match data.cast::<pyo3::types::PyList>() {
        Ok(list) => list
            .iter()
            .enumerate()
            .map(|(i, d)| data_arg(&d, &format!("data[{i}]"), joints.len(), Some(&joints)))
            .collect::<PyResult<_>>()?,
        Err(_) => vec![data_arg(data, "data", joints.len(), Some(&joints))?],
    };
    let observer = MomentumObserverConfig {
        gain: JointValues::Uniform(gain),
    };
    let config = ContactCalibrationConfig {
        false_alarms_per_hour,
        grow_with_motion: !constant,
        ..Default::default()
    };
    let recordings = given
        .into_iter()
        .map(|d| free_motion(py, d))
        .collect::<PyResult<Vec<_>>>()?;
    let floor = py.detach(|| {
        admittance_scenario::calibrate_contact_on_all(&recordings, &id, &observer, &config)
            .map_err(|e| config_error("calibrate_contact", e))
    })?;
    Ok(PyContactFloor { floor })
}

/// The momentum observer on `ident` (raw measurements in, conditioned at the
/// identification's `input_filter_hz` as the observers are) followed by the contact
/// detector of `floor`. `update(t, q, qdot, qddot, tau, dt)` returns the estimate `(n,)` like
/// the observers and sets `contact`, `collision` and `link` (the last joint whose estimate
/// is significant, -1 when none). `detect(estimate, qdot, qddot)` runs the detector alone
/// on an estimate made elsewhere.
#[pyclass(module = "admittance._admittance", name = "ContactDetector")]
pub struct PyContactDetector {
    observer: MomentumObserver,
    detector: ContactDetector,
    filter_hz: f64,
    conditioner: Option<(f64, InputConditioner)>,
    /// The identification's torque delays, and their delay line at a rate.
    delay_s: Vec<f64>,
    delay: Option<(f64, Option<InputDelay>)>,
    n: usize,
    /// `q, qdot, qddot, tau`, `n` each.
    input: Vec<f64>,
    estimate: Vec<f64>,
    state: ContactState,
}

#[pymethods]
impl PyContactDetector {
    #[new]
    #[pyo3(signature = (ident, floor, gain=None))]
    fn new(
        ident: &Bound<'_, PyIdentification>,
        floor: &Bound<'_, PyContactFloor>,
        gain: Option<f64>,
    ) -> PyResult<Self> {
        let id = ident.get().identification.clone();
        let floor = &floor.get().floor;
        let n = id.model.nq();
        if floor.dof() != n {
            return Err(value_error(format!(
                "ContactDetector: the floor is for {} joints, the identification has {n}",
                floor.dof()
            )));
        }
        let recorded: Option<JointValues> = floor
            .source
            .get("observer_gain")
            .and_then(|v| serde_json::from_value(v.clone()).ok());
        let gain = match (gain, recorded) {
            (Some(g), _) => JointValues::Uniform(g),
            (None, Some(g)) => g,
            (None, None) => JointValues::Uniform(50.0),
        };
        let observer = MomentumObserver::from_identification(&id, &MomentumObserverConfig { gain })
            .map_err(|e| config_error("ContactDetector", e))?;
        let detector =
            ContactDetector::new(floor).map_err(|e| config_error("ContactDetector", e))?;
        Ok(PyContactDetector {
            observer,
            detector,
            filter_hz: id.summary.input_filter_hz,
            conditioner: None,
            delay_s: id.summary.delay_s.clone(),
            delay: None,
            n,
            input: vec![0.0; 4 * n],
            estimate: vec![0.0; n],
            state: ContactState::default(),
        })
    }

    /// One control period: raw `q`, `qdot`, `qddot`, the torque `tau` (each `(n,)`) at time
    /// `t` of a period `dt` (s). Returns the estimate `(n,)` (zeros on a fault: non-finite
    /// input or invalid `dt`, which leave the flags as they were).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (t, q, qdot, qddot, tau, dt, *, out=None))]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        qddot: &Bound<'py, PyAny>,
        tau: &Bound<'py, PyAny>,
        dt: f64,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let n = self.n;
        let b = &mut self.input;
        for (k, (obj, name)) in [(q, "q"), (qdot, "qdot"), (qddot, "qddot"), (tau, "tau")]
            .into_iter()
            .enumerate()
        {
            read_vector(obj, name, &mut b[k * n..(k + 1) * n], JOINTS)?;
        }
        if self.filter_hz > 0.0 && dt.is_finite() && dt > 0.0 {
            let rate = 1.0 / dt;
            let stale = self
                .conditioner
                .as_ref()
                .is_none_or(|(r, _)| (r - rate).abs() > 1e-6 * rate);
            if stale {
                let c = InputConditioner::new(n, self.filter_hz, rate)
                    .map_err(|e| value_error(format!("ContactDetector: {e}")))?;
                self.conditioner = Some((rate, c));
            }
            if let Some((_, c)) = self.conditioner.as_mut() {
                let (qs, rest) = b.split_at_mut(n);
                c.update(qs, &rest[2 * n..]);
                qs.copy_from_slice(&c.q);
                rest[..n].copy_from_slice(&c.qdot);
                rest[n..2 * n].copy_from_slice(&c.qddot);
                rest[2 * n..].copy_from_slice(&c.tau);
            }
        }
        // The identification's torque delay, as the run-time loop applies it.
        if dt.is_finite() && dt > 0.0 && self.delay_s.iter().any(|d| *d != 0.0) {
            let rate = 1.0 / dt;
            if self
                .delay
                .as_ref()
                .is_none_or(|(r, _)| (r - rate).abs() > 1e-6 * rate)
            {
                let line = InputDelay::new(&self.delay_s, rate)
                    .map_err(|e| value_error(format!("ContactDetector: {e}")))?;
                self.delay = Some((rate, line));
            }
            if let Some((_, Some(line))) = self.delay.as_mut() {
                let (q, rest) = b.split_at(n);
                let delayed = line.update(q, &rest[..n], &rest[n..2 * n], &rest[2 * n..]);
                b.copy_from_slice(delayed);
            }
        }
        let input = ObserverInput {
            time: t,
            q: &b[..n],
            qdot: &b[n..2 * n],
            qddot: &b[2 * n..3 * n],
            tau_commanded: &b[3 * n..],
        };
        if self.observer.update(&input, dt, &mut self.estimate).is_ok() {
            self.state = self
                .detector
                .update(&self.estimate, &b[n..2 * n], &b[2 * n..3 * n]);
        } else {
            self.estimate.fill(0.0);
        }
        vector_out(py, &self.estimate, out, "out")
    }

    /// The detector alone on an estimate `(n,)` made elsewhere, with the velocity and
    /// acceleration that set the levels; returns `(contact, collision, link)`.
    fn detect(
        &mut self,
        estimate: &Bound<'_, PyAny>,
        qdot: &Bound<'_, PyAny>,
        qddot: &Bound<'_, PyAny>,
    ) -> PyResult<(bool, bool, i32)> {
        let n = self.n;
        let b = &mut self.input;
        read_vector(estimate, "estimate", &mut b[..n], JOINTS)?;
        read_vector(qdot, "qdot", &mut b[n..2 * n], JOINTS)?;
        read_vector(qddot, "qddot", &mut b[2 * n..3 * n], JOINTS)?;
        self.state = self
            .detector
            .update(&b[..n], &b[n..2 * n], &b[2 * n..3 * n]);
        Ok((self.state.contact, self.state.collision, self.state.link))
    }

    /// Back to the state just after construction.
    fn reset(&mut self) {
        self.observer.reset();
        self.detector.reset();
        self.conditioner = None;
        self.state = ContactState::default();
    }

    /// Whether some joint's estimate is above its contact level (with hysteresis).
    #[getter]
    fn contact(&self) -> bool {
        self.state.contact
    }
    /// Whether some joint's estimate is above its collision level (with hysteresis).
    #[getter]
    fn collision(&self) -> bool {
        self.state.collision
    }
    /// The last joint whose estimate is significant (chain order from 0), -1 when none.
    #[getter]
    fn link(&self) -> i32 {
        self.state.link
    }
}
