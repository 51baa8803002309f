//! `ClosedLoop`: one control period of `admittance_loop` (the sensors' signal chain, the
//! observer stage, the admittance model, the controller), built from a dict with the keys of
//! a scenario's `[controller]`, `[admittance]`, `[task_admittance]` and `[observer]` tables
//! by the same serde structs and `ClosedLoop::from_config`; and `VariantRecorder`, which
//! gathers a variant's metrics, health checks and time series from a loop stepped against a
//! plant outside Rust (the MuJoCo co-simulation) with the scenario runner's code, and
//! `write_run_folder`, which writes them as a run folder.

use std::path::PathBuf;

use admittance_loop::{ClosedLoop, LoopConfig, LoopError, LoopInput, LoopStatus, SignalChain};
use admittance_scenario::{Desired, ExternalVariant, PlantStep, VariantRun};
use numpy::PyArray1;
use pyo3::exceptions::{PyFileExistsError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use crate::config;
use crate::control::FaultRecord;
use crate::convert::{config_error, read_vector, value_error, vector_out};
use crate::model::PyModel;
use crate::network::PyNetwork;

const JOINTS: &str = "one value per joint, in chain order";

/// A loop error under `context`, with the text the C ABI and the command line show.
fn loop_error(context: &str, e: LoopError) -> PyErr {
    value_error(format!("{context}: {}", e.text()))
}

/// One control period of force-sensorless admittance control (the Rust `ClosedLoop`,
/// docs/python.md): the encoder angles through the sensors' low-pass and differentiation
/// (`sensor_cutoff_hz`, the loop's one default `DEFAULT_SIGNAL_CUTOFF_HZ`, 20 Hz; 0: none), the observer stage (input conditioning, estimate
/// low-pass, warm-up), the admittance model and the controller, as a scenario's variant runs
/// them.
///
/// `config` is a dict with the keys of a scenario's loop tables: `control_rate_hz`,
/// `controller` (`kind`, `pd`, `neural`, `computed_torque`, `subtract_estimate`),
/// `admittance` or `task_admittance`, `observer` (`kind`, `nominal_inertia_scale`,
/// `cutoff_hz`, `input_filter_hz`, `warmup`, `momentum`, `identification`). `network` is
/// the trained network of a `learned` or `hybrid` observer (`train`). A bad key or value is
/// a `ValueError` naming its dotted key.
///
/// `step` never raises on bad numbers and allocates nothing in Rust: a bad measurement
/// makes the controller hold safely (`fault`).
#[pyclass(unsendable, module = "admittance._admittance", name = "ClosedLoop")]
pub struct PyClosedLoop {
    pub(crate) inner: ClosedLoop,
    chain: SignalChain,
    n: usize,
    /// `q, tau, q_d, qdot_d, qddot_d, tau_ext`, `n` each.
    input: Vec<f64>,
    time: f64,
    pub(crate) status: Option<LoopStatus>,
    faults: FaultRecord,
    observer_faults: u64,
}

impl PyClosedLoop {
    fn slice(&self, k: usize) -> &[f64] {
        &self.input[k * self.n..(k + 1) * self.n]
    }

    /// The input slot `k` of `q, tau, q_d, qdot_d, qddot_d, tau_ext` (`n` values), for a
    /// caller that fills it in place (`step_input` reads them all).
    pub(crate) fn slot_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.input[k * self.n..(k + 1) * self.n]
    }

    /// The command of the last step.
    pub(crate) fn torque_now(&self) -> &[f64] {
        self.inner.torque()
    }

    /// `tau` = this loop's last command (what `step` does with `tau=None`).
    pub(crate) fn hold_command(&mut self) {
        let n = self.n;
        self.input[n..2 * n].copy_from_slice(self.inner.torque());
    }

    /// Number of joints.
    pub(crate) fn joints(&self) -> usize {
        self.n
    }

    /// One control period at `t` on the inputs already in the buffer (`step`'s code,
    /// shared with the co-simulation's `CosimStepper`).
    pub(crate) fn step_input(&mut self, t: f64) -> PyResult<()> {
        let n = self.n;
        let b = &self.input;
        let measurement = self
            .chain
            .sample(t, &b[..n], &b[n..2 * n])
            .map_err(|e| value_error(e.to_string()))?;
        let status = self.inner.step(&LoopInput {
            time: t,
            q_d: &b[2 * n..3 * n],
            qdot_d: &b[3 * n..4 * n],
            qddot_d: &b[4 * n..5 * n],
            measurement,
            true_external_torque: &b[5 * n..],
        });
        self.time = t;
        self.faults.record(status.controller);
        if !status.observer_ok {
            self.observer_faults += 1;
        }
        self.status = Some(status);
        Ok(())
    }
}

#[pymethods]
impl PyClosedLoop {
    #[new]
    #[pyo3(signature = (m, config, network=None, *, sensor_cutoff_hz=admittance_loop::DEFAULT_SIGNAL_CUTOFF_HZ))]
    fn new(
        m: &Bound<'_, PyModel>,
        config: &Bound<'_, PyAny>,
        network: Option<PyRef<'_, PyNetwork>>,
        sensor_cutoff_hz: f64,
    ) -> PyResult<Self> {
        let cfg: LoopConfig = config::parse(Some(config), "ClosedLoop config")?;
        let model = &m.get().model;
        let n = model.nq();
        let trained = network.map(|net| net.deployment_copy());
        let inner = ClosedLoop::from_config(model, &cfg, trained)
            .map_err(|e| loop_error("ClosedLoop config", e))?;
        let chain = SignalChain::new(n, sensor_cutoff_hz, cfg.control_rate_hz)
            .map_err(|e| loop_error("ClosedLoop", e.at("sensor_cutoff_hz")))?;
        Ok(PyClosedLoop {
            inner,
            chain,
            n,
            input: vec![0.0; 6 * n],
            time: 0.0,
            status: None,
            faults: FaultRecord::new(),
            observer_faults: 0,
        })
    }

    /// One control period at time `t` (s): `q` the encoder angles just read, `tau` the
    /// torque applied over the period that just ended (`None`: this loop's last command),
    /// `q_d`, `qdot_d`, `qddot_d` the desired trajectory, `tau_ext` the true external torque
    /// (read only by an `oracle` observer; `None`: zeros). Returns `(torque, estimate)`: the
    /// command to send (finite, within the effort limits) and the external-torque estimate
    /// that drove the admittance model. With `out`, a tuple of two float64 `(n,)` arrays,
    /// they are written into those and returned.
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    #[pyo3(signature = (t, q, tau, q_d, qdot_d, qddot_d, tau_ext=None, *, out=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        tau: Option<&Bound<'py, PyAny>>,
        q_d: &Bound<'py, PyAny>,
        qdot_d: &Bound<'py, PyAny>,
        qddot_d: &Bound<'py, PyAny>,
        tau_ext: Option<&Bound<'py, PyAny>>,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        let n = self.n;
        let outs = match out {
            None => [None, None],
            Some(o) => {
                let t = o
                    .cast::<PyTuple>()
                    .ok()
                    .filter(|t| t.len() == 2)
                    .ok_or_else(|| {
                        value_error(format!(
                            "`out` must be a tuple of two writeable float64 arrays of shape ({n},)"
                        ))
                    })?;
                [Some(t.get_item(0)?), Some(t.get_item(1)?)]
            }
        };
        {
            let (b, torque) = (&mut self.input, self.inner.torque());
            read_vector(q, "q", &mut b[..n], JOINTS)?;
            match tau {
                Some(v) if !v.is_none() => read_vector(v, "tau", &mut b[n..2 * n], JOINTS)?,
                _ => b[n..2 * n].copy_from_slice(torque),
            }
            read_vector(q_d, "q_d", &mut b[2 * n..3 * n], JOINTS)?;
            read_vector(qdot_d, "qdot_d", &mut b[3 * n..4 * n], JOINTS)?;
            read_vector(qddot_d, "qddot_d", &mut b[4 * n..5 * n], JOINTS)?;
            match tau_ext {
                Some(v) if !v.is_none() => read_vector(v, "tau_ext", &mut b[5 * n..], JOINTS)?,
                _ => b[5 * n..].fill(0.0),
            }
        }
        self.step_input(t)?;
        Ok((
            vector_out(py, self.inner.torque(), outs[0].as_ref(), "out[0]")?,
            vector_out(
                py,
                self.inner.external_torque_estimate(),
                outs[1].as_ref(),
                "out[1]",
            )?,
        ))
    }

    /// Number of joints.
    #[getter]
    fn n(&self) -> usize {
        self.n
    }

    /// The control period `1 / control_rate_hz` (s).
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.dt()
    }

    /// The command of the last step `(n,)` (N m).
    #[getter]
    fn torque<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.torque())
    }

    /// The external-torque estimate of the last step `(n,)` (N m).
    #[getter]
    fn estimate<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.external_torque_estimate())
    }

    /// The compliant reference `q_r` of the last step `(n,)`.
    #[getter]
    fn q_r<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.q_r())
    }

    /// `q_r'` of the last step `(n,)`.
    #[getter]
    fn qdot_r<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.qdot_r())
    }

    /// `q_r''` of the last step `(n,)`.
    #[getter]
    fn qddot_r<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.qddot_r())
    }

    /// The last measurement as the controller saw it: a dict of `(n,)` arrays `q`,
    /// `q_filtered`, `qdot`, `qddot`, `tau_filtered`.
    #[getter]
    fn measurement<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = self.chain.measurement();
        let d = PyDict::new(py);
        for (k, v) in [
            ("q", &m.q),
            ("q_filtered", &m.q_filtered),
            ("qdot", &m.qdot),
            ("qddot", &m.qddot),
            ("tau_filtered", &m.tau_filtered),
        ] {
            d.set_item(k, PyArray1::from_slice(py, v))?;
        }
        Ok(d)
    }

    /// What the controller's last step faulted on (it held safely instead), or `None`.
    #[getter]
    fn fault(&self) -> Option<String> {
        self.faults.message()
    }

    /// Controller steps that faulted since construction.
    #[getter]
    fn fault_count(&self) -> u64 {
        self.faults.count
    }

    /// Observer updates that faulted since construction.
    #[getter]
    fn observer_fault_count(&self) -> u64 {
        self.observer_faults
    }
}

/// The metrics, health checks and time series of one variant whose plant runs outside
/// Rust (the MuJoCo co-simulation), gathered with the scenario runner's code: call `add`
/// after each `ClosedLoop.step` and plant step, `finish` at the end, and `write_run_folder`
/// with the recorders. `config` is the loop's config dict; metrics are taken over
/// `[evaluation_start, duration]`; `VARIANT.csv` gets a row every `decimation` steps.
/// `contact_floor` (a `ContactFloor`): contact detection on the loop's estimate, as a
/// scenario's `[contact]` (its columns, metrics and the floor's file in the run folder).
#[pyclass(
    unsendable,
    module = "admittance._admittance",
    name = "VariantRecorder"
)]
pub struct PyVariantRecorder {
    name: String,
    gather: Option<ExternalVariant>,
    run: Option<VariantRun>,
    /// Steps gathered when `finish` was called.
    steps: usize,
    n: usize,
    /// `q, qdot, tau_ext, applied`, `n` each.
    input: Vec<f64>,
}

impl PyVariantRecorder {
    /// Number of joints.
    pub(crate) fn joints(&self) -> usize {
        self.n
    }

    /// The buffer of `q, qdot, tau_ext, applied` (`n` each), for a caller that fills it in
    /// place (`add_input` reads it).
    pub(crate) fn input_mut(&mut self) -> &mut [f64] {
        &mut self.input
    }

    /// `add`'s gathering on the plant's values already in the buffer (shared with the
    /// co-simulation's `CosimStepper`).
    pub(crate) fn add_input(&mut self, closed_loop: &PyClosedLoop) -> PyResult<Option<String>> {
        let n = self.n;
        let Some(status) = closed_loop.status.as_ref() else {
            return Err(value_error(
                "VariantRecorder.add: the loop has not stepped yet",
            ));
        };
        let gather = self
            .gather
            .as_mut()
            .ok_or_else(|| PyRuntimeError::new_err("VariantRecorder: already finished"))?;
        let b = &self.input;
        let desired = Desired {
            q_d: closed_loop.slice(2),
            qdot_d: closed_loop.slice(3),
            qddot_d: closed_loop.slice(4),
        };
        let plant = PlantStep {
            q: &b[..n],
            qdot: &b[n..2 * n],
            tau_ext: &b[2 * n..3 * n],
            applied: &b[3 * n..],
        };
        let divergence = gather.add(
            closed_loop.time,
            &desired,
            closed_loop.chain.measurement(),
            &closed_loop.inner,
            status,
            &plant,
        );
        Ok(divergence.map(|d| d.reason.clone()))
    }
}

#[pymethods]
impl PyVariantRecorder {
    #[new]
    #[pyo3(signature = (name, m, config, duration, evaluation_start, decimation=10, contact_floor=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        name: String,
        m: &Bound<'_, PyModel>,
        config: &Bound<'_, PyAny>,
        duration: f64,
        evaluation_start: f64,
        decimation: usize,
        contact_floor: Option<PyRef<'_, crate::contact::PyContactFloor>>,
    ) -> PyResult<Self> {
        let cfg: LoopConfig = config::parse(Some(config), "VariantRecorder config")?;
        let model = &m.get().model;
        let mut gather =
            ExternalVariant::new(&name, model, &cfg, duration, evaluation_start, decimation)
                .map_err(|e| loop_error("VariantRecorder", e))?;
        if let Some(floor) = contact_floor {
            gather
                .detect_contact(&floor.floor)
                .map_err(|e| config_error("VariantRecorder", e))?;
        }
        let n = model.nq();
        Ok(PyVariantRecorder {
            name,
            gather: Some(gather),
            run: None,
            steps: 0,
            n,
            input: vec![0.0; 4 * n],
        })
    }

    /// Gathers the step `closed_loop` just made (its time, desired trajectory, measurement
    /// and status) and what the plant then did: the true angles `q` and velocities `qdot`
    /// at the end of the step, its true external torque `tau_ext` and the torque the
    /// actuators applied (`None`: the command). Returns `None`, or why the variant diverged
    /// (the health rules of the scenario runner; stop stepping then).
    #[pyo3(signature = (closed_loop, q, qdot, tau_ext, applied=None))]
    fn add(
        &mut self,
        closed_loop: PyRef<'_, PyClosedLoop>,
        q: &Bound<'_, PyAny>,
        qdot: &Bound<'_, PyAny>,
        tau_ext: &Bound<'_, PyAny>,
        applied: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<String>> {
        let n = self.n;
        if closed_loop.n != n {
            return Err(value_error(format!(
                "VariantRecorder.add: the loop has {} joints, the recorder {n}",
                closed_loop.n
            )));
        }
        let b = &mut self.input;
        read_vector(q, "q", &mut b[..n], JOINTS)?;
        read_vector(qdot, "qdot", &mut b[n..2 * n], JOINTS)?;
        read_vector(tau_ext, "tau_ext", &mut b[2 * n..3 * n], JOINTS)?;
        match applied {
            Some(v) if !v.is_none() => read_vector(v, "applied", &mut b[3 * n..], JOINTS)?,
            _ => b[3 * n..].copy_from_slice(closed_loop.inner.torque()),
        }
        self.add_input(&closed_loop)
    }

    /// Ends the variant: its metrics (as in `summary.json`) from then on in `metrics`.
    /// `network`: the trained network of its observer, for the training metrics.
    #[pyo3(signature = (closed_loop, network=None))]
    fn finish(
        &mut self,
        closed_loop: PyRef<'_, PyClosedLoop>,
        network: Option<PyRef<'_, PyNetwork>>,
    ) -> PyResult<()> {
        let gather = self
            .gather
            .take()
            .ok_or_else(|| PyRuntimeError::new_err("VariantRecorder: already finished"))?;
        self.steps = gather.steps();
        let run = gather
            .finish(&closed_loop.inner, network.map(|n| n.training_metrics()))
            .map_err(|e| value_error(e.message))?;
        self.run = Some(run);
        Ok(())
    }

    /// The variant's name.
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    /// Control steps gathered (up to and including a divergence).
    #[getter]
    fn steps(&self) -> usize {
        self.gather.as_ref().map_or(self.steps, |g| g.steps())
    }

    /// When and why the variant diverged: `(time, reason)`, or `None`.
    #[getter]
    fn divergence(&self) -> Option<(f64, String)> {
        let d = match (&self.gather, &self.run) {
            (Some(g), _) => g.divergence(),
            (None, Some(r)) => r.divergence.as_ref(),
            _ => None,
        };
        d.map(|d| (d.time, d.reason.clone()))
    }

    /// The metrics of `summary.json` (a dict) after `finish`; `None` before.
    #[getter]
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(run) = &self.run else {
            return Ok(None);
        };
        let text = serde_json::to_string(&run.metrics.to_map())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(Some(py.import("json")?.call_method1("loads", (text,))?))
    }
}

/// Writes the run folder of finished `VariantRecorder`s (in this order) as `admittance run`
/// writes one: a `VARIANT.csv` each, `summary.json` (the metrics, plus the keys of `extra`)
/// and `scenario.toml` from the dict `scenario` (a scenario file's keys, with a
/// `[variants.NAME]` per recorder; it must load as a scenario). Atomic (a hidden sibling
/// renamed into place); `out` may replace only a folder this tool wrote, or an empty one,
/// unless `force` (`FileExistsError`). Returns `(summary, failures)`: the summary dict and
/// what failed (a divergence, a metric not finite).
#[pyfunction]
#[pyo3(signature = (out, scenario, recorders, extra=None, *, force=false, protect=None, header=None))]
#[allow(clippy::too_many_arguments)]
pub fn write_run_folder<'py>(
    py: Python<'py>,
    out: PathBuf,
    scenario: &Bound<'py, PyAny>,
    recorders: &Bound<'py, PyList>,
    extra: Option<&Bound<'py, PyAny>>,
    force: bool,
    protect: Option<PathBuf>,
    header: Option<String>,
) -> PyResult<(Bound<'py, PyAny>, Vec<String>)> {
    let table: toml::Table = config::parse(Some(scenario), "write_run_folder scenario")?;
    let mut text = String::new();
    if let Some(h) = header {
        for line in h.lines() {
            text.push_str(&format!("# {line}\n"));
        }
    }
    text.push_str(
        &toml::to_string(&table)
            .map_err(|e| value_error(format!("write_run_folder scenario: {e}")))?,
    );
    let extra: serde_json::Map<String, serde_json::Value> = match extra {
        Some(e) if !e.is_none() => config::parse(Some(e), "write_run_folder extra")?,
        _ => serde_json::Map::new(),
    };
    let mut runs = Vec::new();
    for r in recorders.iter() {
        let r = r.cast::<PyVariantRecorder>().map_err(|_| {
            value_error("write_run_folder: `recorders` must be a list of VariantRecorder")
        })?;
        let r = r.borrow();
        let run = r.run.clone().ok_or_else(|| {
            value_error(format!(
                "write_run_folder: the recorder of `{}` is not finished (call finish)",
                r.name
            ))
        })?;
        runs.push(run);
    }
    let protect = protect.unwrap_or_default();
    let (summary, failures) = py
        .detach(|| {
            admittance_scenario::write_external_run_folder(
                &out, &text, &runs, extra, force, &protect,
            )
        })
        .map_err(|e| match e {
            admittance_scenario::RunError::Refused(m) => PyFileExistsError::new_err(m),
            admittance_scenario::RunError::Io { path, source } => {
                PyOSError::new_err(format!("{path}: {source}"))
            }
            other => PyValueError::new_err(other.to_string()),
        })?;
    let text =
        serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok((py.import("json")?.call_method1("loads", (text,))?, failures))
}

/// Whether a run may write the folder `out`, by `admittance run`'s rule: it may be new,
/// empty, or a run folder this tool wrote (anything else only with `force`), and must not
/// hold the current folder or `protect` (a file the run reads). Raises `FileExistsError`
/// (nothing is written) when it may not; call it before a long run.
#[pyfunction]
#[pyo3(signature = (out, *, force=false, protect=None))]
pub fn check_out_dir(out: PathBuf, force: bool, protect: Option<PathBuf>) -> PyResult<()> {
    admittance_scenario::check_out_dir(&out, &protect.unwrap_or_default(), force).map_err(|e| {
        match e {
            admittance_scenario::RunError::Refused(m) => PyFileExistsError::new_err(m),
            other => PyOSError::new_err(other.to_string()),
        }
    })
}
