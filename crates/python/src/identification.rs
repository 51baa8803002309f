//! Identification from Python: `identify`, the `Identification` it returns
//! (`predict`, `model`, `save`), `load_identification` and `excitation` (issue 22's contract;
//! docs/python.md, "Identification").

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use admittance_dynamics::{
    excitation as rust_excitation, Data, ExcitationSettings, Identification,
    IdentificationSettings, Model, Samples, FIT_ACCELERATION_HZ,
};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{rows, value_error, vector_out};
use crate::free_motion::{data_arg, training_arrays, DataArg};
use crate::model::PyModel;
use admittance_scenario::FreeMotionData;

/// An identified arm (`identify`, `load_identification`): the rigid-body `model` with its
/// identified inertias, and per-joint rotor inertia, friction, offset and springs.
/// `predict(q, qdot, qddot)` is the torque it needs; `summary` what it is expected to get
/// wrong on motion it was not trained on.
#[pyclass(frozen, module = "admittance._admittance", name = "Identification")]
pub struct PyIdentification {
    pub(crate) identification: Arc<Identification>,
    /// The URDF model it was identified from (what files record).
    pub(crate) urdf: Arc<Model>,
    /// The payload `with_payload` added (recorded in files `save` writes).
    pub(crate) payload: Option<serde_json::Value>,
}

/// Splits conditioned rows `[q, qdot, qddot]` into the four arrays of `Samples`.
pub(crate) struct Columns {
    q: Vec<f64>,
    qdot: Vec<f64>,
    qddot: Vec<f64>,
    tau: Vec<f64>,
    n: usize,
}

impl Columns {
    fn new(x: &[f64], tau: Vec<f64>, n: usize) -> Self {
        let (mut q, mut qdot, mut qddot) = (Vec::new(), Vec::new(), Vec::new());
        for row in x.chunks_exact(3 * n) {
            q.extend_from_slice(&row[..n]);
            qdot.extend_from_slice(&row[n..2 * n]);
            qddot.extend_from_slice(&row[2 * n..]);
        }
        Columns {
            q,
            qdot,
            qddot,
            tau,
            n,
        }
    }
    pub(crate) fn samples(&self) -> Samples<'_> {
        Samples {
            q: &self.q,
            qdot: &self.qdot,
            qddot: &self.qddot,
            tau: &self.tau,
            dof: self.n,
        }
    }
}

/// `data` conditioned as an identification's samples (`columns`), for the payload fit.
pub(crate) fn conditioned_columns(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    arg: &str,
    model: &Model,
    input_filter_hz: f64,
) -> PyResult<Columns> {
    columns(py, data, arg, model, input_filter_hz)
}

fn columns(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    arg: &str,
    model: &Model,
    input_filter_hz: f64,
) -> PyResult<Columns> {
    let n = model.nq();
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let data = data_arg(data, arg, n, Some(&joints))?;
    let (x, y, _) =
        py.detach(|| training_arrays(data, arg, n, Some(&joints), input_filter_hz, None))?;
    Ok(Columns::new(&x, y, n))
}

/// The free-motion data of a `data` argument (a CSV path or a dict of arrays), its joints
/// checked against the arm's.
fn recording(data: &Bound<'_, PyAny>, arg: &str, model: &Model) -> PyResult<FreeMotionData> {
    let n = model.nq();
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let (data, source) = match data_arg(data, arg, n, Some(&joints))? {
        DataArg::Csv(path) => (
            crate::free_motion::load_csv(data.py(), &path)?,
            path.display().to_string(),
        ),
        DataArg::Arrays(d) => (d, format!("`{arg}`")),
    };
    if data.dof() != n || data.joints != joints {
        return Err(value_error(format!(
            "{source}: joints [{}] are not the arm's [{}] (chain order)",
            data.joints.join(", "),
            joints.join(", ")
        )));
    }
    Ok(data)
}

/// Identifies the arm `m` from free-motion `data` (a CSV path or a dict of arrays, as for
/// `train`): inertial parameters regularised toward the URDF and kept physically possible,
/// and with `friction` each joint's rotor inertia, friction (dissipative), offset and
/// springs. Settings are chosen on `validation` (another recording) when given, else by
/// blocked cross-validation over contiguous stretches of `data`. `input_filter_hz`
/// conditions q and tau as the observers do at run time (0: the columns as recorded);
/// `None` (default): chosen on held-out motion among 4, 6 and 10 Hz and the columns as
/// recorded. The choice, each joint's torque delay and the estimate's 90 % step-response
/// time are in `summary` (`input_filter_hz`, `delay_s`, `step_response_s`). Each body's
/// mass stays at most `max_mass_ratio` times the URDF's (plus a twentieth of the arm's) and
/// within twice its size (`None`: no bound); `summary["bodies_at_extent"]` names those held
/// there. `coulomb_width` is the narrower smooth sign's width `w` of the friction,
/// `tanh(qdot / w)` (rad/s, `admittance identify --coulomb-width`); `None` (default): chosen
/// on held-out motion among `COULOMB_WIDTH_CANDIDATES` (each joint's terms carry it).
/// `fit_acceleration_hz`: the zero-phase low-pass on the acceleration the fit regresses on
/// (`FIT_ACCELERATION_HZ`, at least twice the conditioning's cut-off; predictions use the
/// acceleration as measured); `None`: as measured, for exact accelerations (a simulation's).
#[pyfunction]
#[pyo3(signature = (data, m, friction=true, validation=None, input_filter_hz=None, springs=true, max_mass_ratio=Some(2.0), coulomb_width=None, fit_acceleration_hz=Some(FIT_ACCELERATION_HZ)))]
#[allow(clippy::too_many_arguments)]
pub fn identify(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    m: &Bound<'_, PyModel>,
    friction: bool,
    validation: Option<&Bound<'_, PyAny>>,
    input_filter_hz: Option<f64>,
    springs: bool,
    max_mass_ratio: Option<f64>,
    coulomb_width: Option<f64>,
    fit_acceleration_hz: Option<f64>,
) -> PyResult<PyIdentification> {
    if let Some(f) = input_filter_hz {
        if !(f.is_finite() && f >= 0.0) {
            return Err(value_error(format!(
                "`input_filter_hz` is {f}, must be >= 0 (0: the columns as recorded; None: chosen)"
            )));
        }
    }
    let urdf = m.get().model.clone();
    let train = recording(data, "data", &urdf)?;
    let validation = match validation.filter(|v| !v.is_none()) {
        Some(v) => Some(recording(v, "validation", &urdf)?),
        None => None,
    };
    let settings = IdentificationSettings {
        friction,
        springs: friction && springs,
        max_mass_ratio,
        coulomb_width,
        fit_acceleration_hz,
        ..Default::default()
    };
    settings
        .validate()
        .map_err(|e| value_error(e.to_string()))?;
    if validation.is_none() {
        let period =
            crate::free_motion::repeat_period_of_positions(&train.q, urdf.nq(), settings.folds);
        if let Some(period) = period {
            crate::free_motion::warn_repeating(py, "data", period)?;
        }
    }
    crate::free_motion::warn_gaps(py, "data", &train)?;
    if let Some(v) = &validation {
        crate::free_motion::warn_gaps(py, "validation", v)?;
    }
    let (ident, _tried) = py
        .detach(|| {
            admittance_scenario::identify_recording(
                &urdf,
                &train,
                train.len(),
                validation.as_ref(),
                &settings,
                input_filter_hz,
            )
        })
        .map_err(value_error)?;
    for warning in admittance_scenario::identification_warnings(&urdf, &ident) {
        crate::free_motion::warn(py, &warning)?;
    }
    Ok(PyIdentification {
        identification: Arc::new(ident),
        urdf,
        payload: None,
    })
}

/// Reads an identification file (`Identification.save`, `admittance identify`) with the URDF
/// it names; with `m`, applies it to that model instead (which must be the arm it was made for).
#[pyfunction]
#[pyo3(signature = (path, m=None))]
pub fn load_identification(
    path: PathBuf,
    m: Option<&Bound<'_, PyModel>>,
) -> PyResult<PyIdentification> {
    let (ident, urdf) = match m {
        Some(m) => {
            let urdf = m.get().model.clone();
            (
                Identification::load(&path, &urdf).map_err(|e| value_error(e.to_string()))?,
                urdf,
            )
        }
        None => {
            let (i, model) =
                Identification::load_with_urdf(&path).map_err(|e| value_error(e.to_string()))?;
            (i, Arc::new(model))
        }
    };
    Ok(PyIdentification {
        identification: Arc::new(ident),
        urdf,
        payload: None,
    })
}

#[pymethods]
impl PyIdentification {
    /// Per joint, how the positions `q` (`(n,)` or `(N, n)`, conditioned as the
    /// identification was) leave `summary["training_range"]` by more than 2 % of its span:
    /// a list of dicts with `samples_outside`, `furthest` (how far beyond, rad or m),
    /// `lowest` and `highest`;
    /// empty when the identification records no range.
    fn range_excursions<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.identification.model.nq();
        let (q, _, single) = rows(q, "q", n, true)?;
        crate::convert::require_finite_rows(&q, n, single, "q")?;
        let list: Vec<serde_json::Value> = self
            .identification
            .range_excursions(&q)
            .iter()
            .map(|e| {
                serde_json::json!({
                    "samples_outside": e.samples_outside,
                    "furthest": e.furthest,
                    "lowest": e.lowest,
                    "highest": e.highest,
                })
            })
            .collect();
        json_to_py(py, &serde_json::Value::Array(list))
    }

    /// Per joint, how the velocities `qdot` (`(n,)` or `(N, n)`, conditioned as the
    /// identification was) exceed `summary["training_speed"]` by more than half of it: a list of
    /// dicts with `samples_faster` and `fastest` (the highest speed, rad/s or m/s); empty
    /// when the identification records no speeds.
    fn speed_excursions<'py>(
        &self,
        py: Python<'py>,
        qdot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.identification.model.nq();
        let (qdot, _, single) = rows(qdot, "qdot", n, true)?;
        crate::convert::require_finite_rows(&qdot, n, single, "qdot")?;
        let list: Vec<serde_json::Value> = self
            .identification
            .speed_excursions(&qdot)
            .iter()
            .map(|e| {
                serde_json::json!({
                    "samples_faster": e.samples_faster,
                    "fastest": e.fastest,
                })
            })
            .collect();
        json_to_py(py, &serde_json::Value::Array(list))
    }

    /// The torque (N m) the identified arm needs: `(n,)` for one state, `(N, n)` for rows.
    /// Rows are consecutive samples of one motion at the identification's rate: the share of
    /// `qddot` taken rises above `summary["acceleration_gain"]` where that motion accelerates
    /// well beyond the training motion's noise (docs/method.md section 8); one state takes
    /// the gain itself.
    fn predict<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        qddot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.identification.model.nq();
        let (q, rq, single) = rows(q, "q", n, true)?;
        let (qd, rqd, _) = rows(qdot, "qdot", n, true)?;
        let (qdd, rqdd, _) = rows(qddot, "qddot", n, true)?;
        for (v, name) in [(&q, "q"), (&qd, "qdot"), (&qdd, "qddot")] {
            crate::convert::require_finite_rows(v, n, single, name)?;
        }
        if rq != rqd || rq != rqdd {
            return Err(value_error(format!(
                "`q`, `qdot` and `qddot` have {rq}, {rqd} and {rqdd} rows"
            )));
        }
        let mut out = vec![0.0; rq * n];
        if single {
            let mut data = Data::new(&self.identification.model);
            self.identification
                .predict(&mut data, &q, &qd, &qdd, &mut out)
                .map_err(|e| value_error(e.to_string()))?;
        } else {
            self.identification
                .predict_motion(&q, &qd, &qdd, &mut out)
                .map_err(|e| value_error(e.to_string()))?;
        }
        if single {
            return Ok(vector_out(py, &out, None, "out")?.into_any());
        }
        let a = numpy::ndarray::Array2::from_shape_vec((rq, n), out)
            .map_err(|e| value_error(e.to_string()))?;
        Ok(PyArray2::from_owned_array(py, a).into_any())
    }

    /// The identified rigid-body model (the URDF's kinematics, identified inertias).
    #[getter]
    fn model(&self) -> PyModel {
        PyModel::new(self.identification.model.clone())
    }

    /// Per-joint terms: a list of dicts (armature, viscous, coulomb, coulomb_width,
    /// offset, spring, spring_range).
    #[getter]
    fn joint_terms<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(
            py,
            &serde_json::to_value(&self.identification.joint_terms)
                .map_err(|e| value_error(e.to_string()))?,
        )
    }

    /// What was chosen and measured (held-out rms per joint in N m, ridge, springs, ...).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(
            py,
            &serde_json::to_value(&self.identification.summary)
                .map_err(|e| value_error(e.to_string()))?,
        )
    }

    /// Writes the identification file (JSON, versioned, checksummed, atomic); an existing
    /// file that is not an identification file is never overwritten.
    #[pyo3(signature = (path, data=None))]
    fn save(&self, path: PathBuf, data: Option<String>) -> PyResult<()> {
        let mut provenance = BTreeMap::new();
        provenance.insert(
            "data".to_string(),
            serde_json::Value::from(data.unwrap_or_else(|| "from Python".into())),
        );
        if let Some(record) = &self.payload {
            provenance.insert("payload".to_string(), record.clone());
        }
        self.identification
            .save(&path, &self.urdf, provenance)
            .map_err(|e| value_error(e.to_string()))
    }

    /// This identification carrying `payload` (`identify_payload`, or a known `Payload`)
    /// rigidly at the tip frame: its inertia added to the last body; joint terms and summary
    /// kept. `save` records the payload in the file's `data`.
    fn with_payload(&self, payload: &Bound<'_, crate::payload::PyPayload>) -> PyResult<Self> {
        let p = payload.get().payload;
        let carried = self
            .identification
            .with_payload(&p)
            .map_err(|e| value_error(e.to_string()))?;
        let i = &p.inertia;
        let record = serde_json::json!({
            "mass_kg": p.mass,
            "com_m": p.com.as_slice(),
            "inertia_kg_m2": (0..3).map(|r| [i[(r, 0)], i[(r, 1)], i[(r, 2)]]).collect::<Vec<_>>(),
            "frame": self.urdf.tip().name,
        });
        Ok(PyIdentification {
            identification: Arc::new(carried),
            urdf: self.urdf.clone(),
            payload: Some(record),
        })
    }

    fn __repr__(&self) -> String {
        let s = &self.identification.summary;
        let total = (s
            .expected_false_torque_rms
            .iter()
            .map(|x| x * x)
            .sum::<f64>()
            / s.expected_false_torque_rms.len().max(1) as f64)
            .sqrt();
        format!(
            "Identification({} joints, expected false torque {:.3} N m rms, held out: {})",
            self.identification.model.nq(),
            total,
            s.held_out
        )
    }
}

/// A JSON value as Python objects (through the json module: small, off the real-time path).
fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

/// A nominal model argument: a `Model` (its URDF alone) or an `Identification`.
pub(crate) fn nominal_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Arc<Identification>> {
    if let Ok(i) = obj.cast::<PyIdentification>() {
        return Ok(i.get().identification.clone());
    }
    if let Ok(m) = obj.cast::<PyModel>() {
        return Ok(Arc::new(Identification::from_model(
            m.get().model.as_ref().clone(),
        )));
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "`{name}` must be a Model or an Identification"
    )))
}

/// A motion designed for identification (`admittance excite`): a finite Fourier series per
/// joint inside an envelope, starting and ending at rest, optimised for the condition number
/// of the base regressor. The envelope: `range` (rad or m; a number, one per joint, or
/// `float("inf")` for the URDF's whole range; default 0.5) around `pose` (default: the middle
/// of the limits), `velocity_fraction` of the URDF's velocity limits and
/// `acceleration_fraction` of `acceleration_limit` rad/s^2 (defaults 0.3, 0.3 and 3), inside
/// the limits. Returns a dict of `t` `(N,)` and `q`, `qdot`, `qddot` `(N, n)` arrays and
/// `condition_number`.
#[pyfunction]
#[pyo3(signature = (m, duration, seed=1, harmonics=5, period=None, rate_hz=200.0, pose=None, range=None, velocity_fraction=None, acceleration_fraction=None, acceleration_limit=None))]
#[allow(clippy::too_many_arguments)]
pub fn excitation<'py>(
    py: Python<'py>,
    m: &Bound<'py, PyModel>,
    duration: f64,
    seed: u64,
    harmonics: usize,
    period: Option<f64>,
    rate_hz: f64,
    pose: Option<Vec<f64>>,
    range: Option<&Bound<'py, PyAny>>,
    velocity_fraction: Option<f64>,
    acceleration_fraction: Option<f64>,
    acceleration_limit: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = m.get().model.clone();
    // Without a period: the duration in equal periods of at most 10 s (as the CLI).
    let period = period.unwrap_or_else(|| duration / (duration / 10.0).ceil().max(1.0));
    let defaults = ExcitationSettings::default();
    let settings = ExcitationSettings {
        duration,
        period,
        harmonics,
        rate_hz,
        seed,
        pose: pose.unwrap_or_default(),
        range: match range.filter(|r| !r.is_none()) {
            Some(r) => range_arg(r)?,
            None => defaults.range.clone(),
        },
        velocity_fraction: velocity_fraction.unwrap_or(defaults.velocity_fraction),
        acceleration_fraction: acceleration_fraction.unwrap_or(defaults.acceleration_fraction),
        acceleration_limit: acceleration_limit.unwrap_or(defaults.acceleration_limit),
        ..defaults
    };
    let e = py
        .detach(|| rust_excitation(&model, &settings))
        .map_err(|e| value_error(e.to_string()))?;
    let n = e.dof;
    let out = PyDict::new(py);
    out.set_item("t", numpy::PyArray1::from_slice(py, &e.t))?;
    for (name, values) in [("q", &e.q), ("qdot", &e.qdot), ("qddot", &e.qddot)] {
        let a = numpy::ndarray::Array2::from_shape_vec((e.t.len(), n), values.clone())
            .map_err(|err| value_error(err.to_string()))?;
        out.set_item(name, PyArray2::from_owned_array(py, a))?;
    }
    out.set_item("condition_number", e.condition_number)?;
    Ok(out)
}

/// `range=`: one number or a sequence of numbers.
fn range_arg(r: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(v) = r.extract::<f64>() {
        return Ok(vec![v]);
    }
    r.extract::<Vec<f64>>().map_err(|_| {
        value_error(
            "`range` must be a number or one number per joint (rad or m; inf: the whole range)",
        )
    })
}
