//! Controllers: `Controller` (the shared `step`), `NeuralController`, `PdController`,
//! `ComputedTorqueController`. Built once, stepped every control period; `step` copies the
//! arguments into buffers made at construction and calls the Rust `Controller::step`.

use admittance_control::{
    ComputedTorqueConfig, ComputedTorqueController, ControlInput, Controller, Fault,
    NeuralController, NeuralControllerConfig, PdConfig, PdController, StepStatus,
};
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::config;
use crate::convert::{config_error, read_vector, vector_out};
use crate::model::PyModel;

/// What a step ran on, with its fault record (shared by controllers, observers and the
/// admittance model).
pub(crate) struct FaultRecord {
    pub last: Option<Fault>,
    pub count: u64,
}

impl FaultRecord {
    pub fn new() -> Self {
        FaultRecord {
            last: None,
            count: 0,
        }
    }

    pub fn record(&mut self, status: StepStatus) {
        self.last = status.fault();
        if self.last.is_some() {
            self.count += 1;
        }
    }

    pub fn message(&self) -> Option<String> {
        self.last.map(|f| f.to_string())
    }
}

pub(crate) enum AnyController {
    Neural(Box<NeuralController>),
    Pd(PdController),
    ComputedTorque(ComputedTorqueController),
}

impl AnyController {
    fn as_dyn(&mut self) -> &mut dyn Controller {
        match self {
            AnyController::Neural(c) => c.as_mut(),
            AnyController::Pd(c) => c,
            AnyController::ComputedTorque(c) => c,
        }
    }
}

const JOINTS: &str = "one value per joint, in chain order";

/// A `#[pymethods]` block of a class stepped every control period that has `n` (joints) and
/// `faults` (a [`FaultRecord`]): the class's own `methods` and, defined once for the
/// controllers, the observers and the admittance model, the getters `n`, `fault` and
/// `fault_count`.
macro_rules! stepped_pymethods {
    ($ty:ty { $($methods:tt)* }) => {
        #[pymethods]
        impl $ty {
            $($methods)*

            /// Number of joints.
            #[getter]
            fn n(&self) -> usize {
                self.n
            }

            /// What the last step faulted on (the safe fallback was returned instead), or
            /// `None` after a valid step.
            #[getter]
            fn fault(&self) -> Option<String> {
                self.faults.message()
            }

            /// Steps that faulted since construction or `reset`.
            #[getter]
            fn fault_count(&self) -> u64 {
                self.faults.count
            }
        }
    };
}
pub(crate) use stepped_pymethods;

/// Reads the arguments of a controller step into `b` (`n` each, in this order).
#[allow(clippy::too_many_arguments)]
fn read_control_input(
    b: &mut [f64],
    n: usize,
    q: &Bound<'_, PyAny>,
    qdot: &Bound<'_, PyAny>,
    q_ref: &Bound<'_, PyAny>,
    qdot_ref: &Bound<'_, PyAny>,
    qddot_ref: &Bound<'_, PyAny>,
    tau_ext_hat: &Bound<'_, PyAny>,
) -> PyResult<()> {
    for (k, (obj, name)) in [
        (q, "q"),
        (qdot, "qdot"),
        (q_ref, "q_ref"),
        (qdot_ref, "qdot_ref"),
        (qddot_ref, "qddot_ref"),
        (tau_ext_hat, "tau_ext_hat"),
    ]
    .into_iter()
    .enumerate()
    {
        read_vector(obj, name, &mut b[k * n..(k + 1) * n], JOINTS)?;
    }
    Ok(())
}

/// The controller input of the values read by [`read_control_input`].
fn control_input(b: &[f64], n: usize, time: f64) -> ControlInput<'_> {
    ControlInput {
        time,
        q: &b[..n],
        qdot: &b[n..2 * n],
        q_ref: &b[2 * n..3 * n],
        qdot_ref: &b[3 * n..4 * n],
        qddot_ref: &b[4 * n..5 * n],
        external_torque_estimate: &b[5 * n..],
    }
}

/// A joint-torque controller: the common interface of `NeuralController`, `PdController`
/// and `ComputedTorqueController` (not constructed directly).
///
/// `step` never raises on bad numbers: on a non-finite or stale measurement, a non-finite
/// reference or estimate, or an invalid `dt` it returns the documented safe hold (gravity of
/// the nominal model at the last valid position minus damping, within the effort limits),
/// freezes adaptation, and records the fault in `fault` / `fault_count`. Arguments of the
/// wrong shape are a `ValueError`.
#[pyclass(subclass, module = "admittance._admittance", name = "Controller")]
pub struct PyController {
    inner: AnyController,
    n: usize,
    /// `q, qdot, q_ref, qdot_ref, qddot_ref, tau_ext_hat`, `n` each.
    input: Vec<f64>,
    torque: Vec<f64>,
    faults: FaultRecord,
}

impl PyController {
    fn new(inner: AnyController, n: usize) -> Self {
        PyController {
            inner,
            n,
            input: vec![0.0; 6 * n],
            torque: vec![0.0; n],
            faults: FaultRecord::new(),
        }
    }
}

stepped_pymethods!(PyController {
    /// One control step of length `dt` (s): the commanded joint torque `(n,)`, finite and
    /// within the effort limits. `q`, `qdot`: measured state; `q_ref`, `qdot_ref`,
    /// `qddot_ref`: the (compliant) reference; `tau_ext_hat`: the external-torque estimate
    /// (zeros without an observer). With `out`, the torque is written into that float64
    /// `(n,)` array, which is returned.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (t, q, qdot, q_ref, qdot_ref, qddot_ref, tau_ext_hat, dt, *, out=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        q_ref: &Bound<'py, PyAny>,
        qdot_ref: &Bound<'py, PyAny>,
        qddot_ref: &Bound<'py, PyAny>,
        tau_ext_hat: &Bound<'py, PyAny>,
        dt: f64,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let n = self.n;
        read_control_input(
            &mut self.input, n, q, qdot, q_ref, qdot_ref, qddot_ref, tau_ext_hat,
        )?;
        let input = control_input(&self.input, n, t);
        let status = self.inner.as_dyn().step(&input, dt, &mut self.torque);
        self.faults.record(status);
        vector_out(py, &self.torque, out, "out")
    }

    /// Benchmark hook of scripts/bench/python_overhead.py, not part of the API: the same
    /// `step` called `calls` times from Rust on this controller with these arguments (read
    /// once), timed in Rust; returns the seconds per call.
    #[allow(clippy::too_many_arguments)]
    fn _rust_step_seconds(
        &mut self,
        t: f64,
        q: &Bound<'_, PyAny>,
        qdot: &Bound<'_, PyAny>,
        q_ref: &Bound<'_, PyAny>,
        qdot_ref: &Bound<'_, PyAny>,
        qddot_ref: &Bound<'_, PyAny>,
        tau_ext_hat: &Bound<'_, PyAny>,
        dt: f64,
        calls: usize,
    ) -> PyResult<f64> {
        let n = self.n;
        read_control_input(
            &mut self.input, n, q, qdot, q_ref, qdot_ref, qddot_ref, tau_ext_hat,
        )?;
        let input = control_input(&self.input, n, t);
        let ctl = self.inner.as_dyn();
        let start = std::time::Instant::now();
        for _ in 0..calls {
            let status = ctl.step(std::hint::black_box(&input), dt, &mut self.torque);
            std::hint::black_box((&status, &self.torque));
        }
        Ok(start.elapsed().as_secs_f64() / calls.max(1) as f64)
    }

    /// Back to the state just after construction (learned weights included).
    fn reset(&mut self) {
        self.inner.as_dyn().reset();
        self.faults = FaultRecord::new();
    }

    /// `"nn"`, `"pd"`, `"pd_gravity"` or `"computed_torque"`.
    #[getter]
    fn name(&mut self) -> String {
        self.inner.as_dyn().name().to_string()
    }
});

/// The paper's adaptive RBF neural controller with deadzone compensation (docs/method.md
/// section 3) on the nominal model `m`.
///
/// `config` takes the keys of a scenario's `[controller.neural]` table (`k1`, `k2`, `f`,
/// `deadzone_compensation`, `deadzone_network`, `deadzone_inverse`, `adaptation`,
/// `track_relevance`, `safe_hold`); `None`: the paper's experiment A. An unknown key or a
/// bad value is a `ValueError` naming the key.
#[pyclass(extends = PyController, module = "admittance._admittance", name = "NeuralController")]
pub struct PyNeuralController;

#[pymethods]
impl PyNeuralController {
    #[new]
    #[pyo3(signature = (m, config=None))]
    fn new(
        m: &Bound<'_, PyModel>,
        config: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let cfg: NeuralControllerConfig = config::parse(config, "NeuralController config")?;
        let model = m.get().model.clone();
        let n = model.nq();
        let c = NeuralController::new(model, &cfg)
            .map_err(|e| config_error("NeuralController config", e))?;
        Ok(
            PyClassInitializer::from(PyController::new(AnyController::Neural(Box::new(c)), n))
                .add_subclass(Self),
        )
    }
}

/// Joint-space PD `tau = Kp (q_r - q) + Kd (qdot_r - qdot)`, with `gravity_compensation`
/// plus the nominal `G(q)` of `m`; clamped to the effort limits.
///
/// `config` takes the keys of a scenario's `[controller.pd]` table: `kp`, `kd` (one number
/// or one per joint), `gravity_compensation`, `safe_hold`.
#[pyclass(extends = PyController, module = "admittance._admittance", name = "PdController")]
pub struct PyPdController;

#[pymethods]
impl PyPdController {
    #[new]
    fn new(
        m: &Bound<'_, PyModel>,
        config: &Bound<'_, PyAny>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let cfg: PdConfig = config::parse(Some(config), "PdController config")?;
        let model = m.get().model.clone();
        let n = model.nq();
        let c =
            PdController::new(model, &cfg).map_err(|e| config_error("PdController config", e))?;
        Ok(PyClassInitializer::from(PyController::new(AnyController::Pd(c), n)).add_subclass(Self))
    }
}

/// Computed torque with the nominal model `m`:
/// `tau = M(q) (qddot_r + Kd (qdot_r - qdot) + Kp (q_r - q)) + C(q, qdot) qdot + G(q)`.
///
/// `config` takes the keys of a scenario's `[controller.computed_torque]` table: `kp`,
/// `kd`, `safe_hold`.
#[pyclass(extends = PyController, module = "admittance._admittance", name = "ComputedTorqueController")]
pub struct PyComputedTorqueController;

#[pymethods]
impl PyComputedTorqueController {
    #[new]
    fn new(
        m: &Bound<'_, PyModel>,
        config: &Bound<'_, PyAny>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let cfg: ComputedTorqueConfig =
            config::parse(Some(config), "ComputedTorqueController config")?;
        let model = m.get().model.clone();
        let n = model.nq();
        let c = ComputedTorqueController::new(model, &cfg)
            .map_err(|e| config_error("ComputedTorqueController config", e))?;
        Ok(
            PyClassInitializer::from(PyController::new(AnyController::ComputedTorque(c), n))
                .add_subclass(Self),
        )
    }
}
