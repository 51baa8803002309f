//! External-torque observers: `Observer` (the shared `update`), `MomentumObserver`,
//! `LearnedObserver`, `HybridObserver`, `OracleObserver`; and `InputConditioner`, the
//! observers' second input filter (`observer.input_filter_hz`); `EstimateLowPass`, the
//! estimate's low-pass (`observer.cutoff_hz`).

use admittance_control::{
    HybridObserver, LearnedObserver, MomentumObserver, MomentumObserverConfig, Observer,
    ObserverInput, OracleObserver,
};
use admittance_loop::{EstimateLowPass, InputConditioner};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::config;
use crate::control::{stepped_pymethods, FaultRecord};
use crate::convert::{
    config_error, read_vector, require_finite, rows, value_error, vector, vector_out,
};
use crate::network::PyNetwork;

pub(crate) enum AnyObserver {
    Momentum(Box<MomentumObserver>),
    Learned(Box<LearnedObserver>),
    Hybrid(Box<HybridObserver>),
    Oracle(OracleObserver),
}

impl AnyObserver {
    fn as_dyn(&mut self) -> &mut dyn Observer {
        match self {
            AnyObserver::Momentum(o) => o.as_mut(),
            AnyObserver::Learned(o) => o.as_mut(),
            AnyObserver::Hybrid(o) => o.as_mut(),
            AnyObserver::Oracle(o) => o,
        }
    }
}

const JOINTS: &str = "one value per joint, in chain order";

/// Reads the arguments of an observer update into `b` (`n` each, in this order) and returns
/// the observer input of them.
fn observer_input<'b>(
    b: &'b mut [f64],
    n: usize,
    time: f64,
    [q, qdot, qddot, tau]: [&Bound<'_, PyAny>; 4],
) -> PyResult<ObserverInput<'b>> {
    for (k, (obj, name)) in [(q, "q"), (qdot, "qdot"), (qddot, "qddot"), (tau, "tau")]
        .into_iter()
        .enumerate()
    {
        read_vector(obj, name, &mut b[k * n..(k + 1) * n], JOINTS)?;
    }
    // A value beyond what any arm measures (the bound of free-motion data, issue 34) takes
    // the path of a NaN: the update faults instead of integrating it into the estimate.
    for v in b[..4 * n].iter_mut() {
        if v.abs() > admittance_learning::broad::MAX_ABS_DATA_VALUE {
            *v = f64::NAN;
        }
    }
    Ok(ObserverInput {
        time,
        q: &b[..n],
        qdot: &b[n..2 * n],
        qddot: &b[2 * n..3 * n],
        tau_commanded: &b[3 * n..],
    })
}

/// An external-torque observer: the common interface of `MomentumObserver`,
/// `LearnedObserver`, `HybridObserver` and `OracleObserver` (not constructed directly).
///
/// The estimate has docs/method.md's sign: the torque the environment applies to the robot.
/// `update` never raises on bad numbers: on a non-finite input (or one beyond +-1e12, the
/// bound of free-motion data) or an invalid `dt` it returns zeros and records the fault in
/// `fault` / `fault_count` (the momentum observer restarts its integral at the next valid
/// sample). Arguments of the wrong shape are a `ValueError`.
#[pyclass(subclass, module = "admittance._admittance", name = "Observer")]
pub struct PyObserver {
    inner: AnyObserver,
    n: usize,
    /// `q, qdot, qddot, tau`, `n` each.
    input: Vec<f64>,
    estimate: Vec<f64>,
    faults: FaultRecord,
}

impl PyObserver {
    fn new(inner: AnyObserver, n: usize) -> Self {
        PyObserver {
            inner,
            n,
            input: vec![0.0; 4 * n],
            estimate: vec![0.0; n],
            faults: FaultRecord::new(),
        }
    }
}

stepped_pymethods!(PyObserver {
    /// One update with the sample at time `t` (s) of a period `dt` (s): the estimate of the
    /// external joint torque `(n,)`. `q`, `qdot`, `qddot`: measured angles, velocities and
    /// (filtered) accelerations; `tau`: the torque commanded (for a learned network, the
    /// torque signal its training data used). With `out`, the estimate is written into that
    /// float64 `(n,)` array, which is returned.
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
        let input = observer_input(&mut self.input, self.n, t, [q, qdot, qddot, tau])?;
        let status = self.inner.as_dyn().update(&input, dt, &mut self.estimate);
        self.faults.record(status);
        vector_out(py, &self.estimate, out, "out")
    }

    /// Benchmark hook of scripts/bench/python_overhead.py, not part of the API: the same
    /// `update` called `calls` times from Rust on this observer with these arguments (read
    /// once), timed in Rust; returns the seconds per call.
    #[allow(clippy::too_many_arguments)]
    fn _rust_update_seconds(
        &mut self,
        t: f64,
        q: &Bound<'_, PyAny>,
        qdot: &Bound<'_, PyAny>,
        qddot: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        dt: f64,
        calls: usize,
    ) -> PyResult<f64> {
        let input = observer_input(&mut self.input, self.n, t, [q, qdot, qddot, tau])?;
        let obs = self.inner.as_dyn();
        let start = std::time::Instant::now();
        for _ in 0..calls {
            let status = obs.update(std::hint::black_box(&input), dt, &mut self.estimate);
            std::hint::black_box((&status, &self.estimate));
        }
        Ok(start.elapsed().as_secs_f64() / calls.max(1) as f64)
    }

    /// Back to the state just after construction.
    fn reset(&mut self) {
        self.inner.as_dyn().reset();
        self.faults = FaultRecord::new();
    }

    /// `"momentum"`, `"learned"`, `"hybrid"` or `"oracle"`.
    #[getter]
    fn name(&mut self) -> String {
        self.inner.as_dyn().name().to_string()
    }
});

/// The momentum observer's settings from `gain` (one number or one per joint) or a
/// `config` dict with the keys of `[observer.momentum]`; not both.
fn momentum_config(
    gain: Option<&Bound<'_, PyAny>>,
    config: Option<&Bound<'_, PyAny>>,
    n: usize,
    context: &str,
) -> PyResult<MomentumObserverConfig> {
    match (gain, config) {
        (Some(_), Some(c)) if !c.is_none() => Err(value_error(format!(
            "{context}: give `gain` or `config`, not both"
        ))),
        (Some(g), _) if !g.is_none() => Ok(MomentumObserverConfig {
            gain: config::joint_values(g, "gain", n)?,
        }),
        (_, c) => config::parse(c, context),
    }
}

/// The momentum observer on a nominal model: a URDF model as it is (bit for bit the
/// observer of the scenarios), or an identification with its joint terms.
fn momentum(
    nominal: &admittance_dynamics::Identification,
    cfg: &MomentumObserverConfig,
) -> Result<MomentumObserver, admittance_control::ConfigError> {
    if nominal.has_joint_terms() {
        MomentumObserver::from_identification(nominal, cfg)
    } else {
        MomentumObserver::new(std::sync::Arc::new(nominal.model.clone()), cfg)
    }
}

/// The generalised-momentum observer on the nominal model `m` (a `Model` or an
/// `Identification`; docs/method.md section 5): the
/// estimate follows the true external torque (less the friction `m` does not know) through
/// a first-order lag of time constant `1 / gain` (1/s; default 50).
///
/// `config` alternatively takes the keys of a scenario's `[observer.momentum]` table.
#[pyclass(extends = PyObserver, module = "admittance._admittance", name = "MomentumObserver")]
pub struct PyMomentumObserver;

#[pymethods]
impl PyMomentumObserver {
    #[new]
    #[pyo3(signature = (m, gain=None, config=None))]
    fn new(
        m: &Bound<'_, PyAny>,
        gain: Option<&Bound<'_, PyAny>>,
        config: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let nominal = crate::identification::nominal_arg(m, "m")?;
        let n = nominal.model.nq();
        let cfg = momentum_config(gain, config, n, "MomentumObserver config")?;
        let o = momentum(&nominal, &cfg).map_err(|e| config_error("MomentumObserver", e))?;
        Ok(
            PyClassInitializer::from(PyObserver::new(AnyObserver::Momentum(Box::new(o)), n))
                .add_subclass(Self),
        )
    }
}

/// The paper's learned observer (eq. 19): `tau_ext_hat = LP(f_hat(q, qdot, qddot) - tau)`
/// with a network from `train` or `load_network` (inputs `[q, qdot, qddot]`, outputs the
/// joint torques) and a first-order low-pass at `cutoff_hz` (0: none).
#[pyclass(extends = PyObserver, module = "admittance._admittance", name = "LearnedObserver")]
pub struct PyLearnedObserver;

#[pymethods]
impl PyLearnedObserver {
    #[new]
    #[pyo3(signature = (network, cutoff_hz=0.0))]
    fn new(network: PyRef<'_, PyNetwork>, cutoff_hz: f64) -> PyResult<PyClassInitializer<Self>> {
        let o = LearnedObserver::new(network.deployment_copy(), cutoff_hz)
            .map_err(|e| config_error("LearnedObserver", e))?;
        let n = o.dof();
        Ok(
            PyClassInitializer::from(PyObserver::new(AnyObserver::Learned(Box::new(o)), n))
                .add_subclass(Self),
        )
    }
}

/// The hybrid observer: the momentum observer on the nominal model `m`, fed the torque
/// corrected by a network that learned what `m` misses in free motion (`train(...,
/// nominal=m)`: the residual `tau - RNEA_m(q, qdot, qddot)`). `gain` / `config` as for
/// `MomentumObserver`.
#[pyclass(extends = PyObserver, module = "admittance._admittance", name = "HybridObserver")]
pub struct PyHybridObserver;

#[pymethods]
impl PyHybridObserver {
    #[new]
    #[pyo3(signature = (m, network, gain=None, config=None))]
    fn new(
        m: &Bound<'_, PyAny>,
        network: PyRef<'_, PyNetwork>,
        gain: Option<&Bound<'_, PyAny>>,
        config: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let nominal = crate::identification::nominal_arg(m, "m")?;
        let n = nominal.model.nq();
        let cfg = momentum_config(gain, config, n, "HybridObserver config")?;
        let momentum = momentum(&nominal, &cfg).map_err(|e| config_error("HybridObserver", e))?;
        let o = HybridObserver::new(momentum, network.deployment_copy())
            .map_err(|e| config_error("HybridObserver", e))?;
        Ok(
            PyClassInitializer::from(PyObserver::new(AnyObserver::Hybrid(Box::new(o)), n))
                .add_subclass(Self),
        )
    }
}

/// The oracle: returns the true external torque given by `set_true_value` before each
/// `update` (an upper bound for any observer, in simulation).
#[pyclass(extends = PyObserver, module = "admittance._admittance", name = "OracleObserver")]
pub struct PyOracleObserver;

#[pymethods]
impl PyOracleObserver {
    #[new]
    fn new(n: usize) -> PyResult<PyClassInitializer<Self>> {
        if n == 0 {
            return Err(value_error("OracleObserver: `n` must be at least 1"));
        }
        Ok(PyClassInitializer::from(PyObserver::new(
            AnyObserver::Oracle(OracleObserver::new(n)),
            n,
        ))
        .add_subclass(Self))
    }

    /// Sets the true external torque `(n,)` returned by the next `update` (non-finite
    /// values make that update fault).
    fn set_true_value(mut slf: PyRefMut<'_, Self>, tau_ext: &Bound<'_, PyAny>) -> PyResult<()> {
        let base = slf.as_super();
        let v = vector(tau_ext, "tau_ext", base.n, JOINTS)?;
        if let AnyObserver::Oracle(o) = &mut base.inner {
            o.set_true_value(&v);
        }
        Ok(())
    }
}

/// The observers' second input filter (`observer.input_filter_hz` of the scenarios; the
/// `input_filter_hz` of `train`): a 2nd-order Butterworth low-pass at `cutoff_hz` on the
/// angles and torques sampled at `rate_hz`, with the filtered angles differentiated twice.
/// Feed a learned observer through it with the same cut-off its network was trained with.
#[pyclass(module = "admittance._admittance", name = "InputConditioner")]
pub struct PyInputConditioner {
    inner: InputConditioner,
    n: usize,
    q: Vec<f64>,
    tau: Vec<f64>,
}

#[pymethods]
impl PyInputConditioner {
    #[new]
    fn new(n: usize, cutoff_hz: f64, rate_hz: f64) -> PyResult<Self> {
        if n == 0 {
            return Err(value_error("InputConditioner: `n` must be at least 1"));
        }
        let inner = InputConditioner::new(n, cutoff_hz, rate_hz)
            .map_err(|e| value_error(format!("InputConditioner: {e}")))?;
        Ok(PyInputConditioner {
            inner,
            n,
            q: vec![0.0; n],
            tau: vec![0.0; n],
        })
    }

    /// Takes one sample of angles `q` and torques `tau` (finite, `(n,)` each) and returns
    /// the conditioned `(q, qdot, qddot, tau)`, four new `(n,)` arrays.
    #[allow(clippy::type_complexity)]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        tau: &Bound<'py, PyAny>,
    ) -> PyResult<(
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        read_vector(q, "q", &mut self.q, JOINTS)?;
        read_vector(tau, "tau", &mut self.tau, JOINTS)?;
        // A non-finite sample would stay in the filter's state for good.
        require_finite(&self.q, "q")?;
        require_finite(&self.tau, "tau")?;
        self.inner.update(&self.q, &self.tau);
        let c = &self.inner;
        Ok((
            PyArray1::from_slice(py, &c.q),
            PyArray1::from_slice(py, &c.qdot),
            PyArray1::from_slice(py, &c.qddot),
            PyArray1::from_slice(py, &c.tau),
        ))
    }

    /// Number of joints.
    #[getter]
    fn n(&self) -> usize {
        self.n
    }
}

/// The estimate's first-order low-pass of the loop (`observer.cutoff_hz`,
/// `admittance_loop::EstimateLowPass`): `y += alpha (x - y)` per joint from rest, `alpha =
/// dt / (dt + 1 / (2 pi cutoff_hz))` at `rate_hz`; 0 passes the estimate through.
#[pyclass(module = "admittance._admittance", name = "EstimateLowPass")]
pub struct PyEstimateLowPass {
    inner: EstimateLowPass,
    raw: Vec<f64>,
}

#[pymethods]
impl PyEstimateLowPass {
    #[new]
    fn new(n: usize, cutoff_hz: f64, rate_hz: f64) -> PyResult<Self> {
        if n == 0 {
            return Err(value_error("EstimateLowPass: `n` must be at least 1"));
        }
        let inner = EstimateLowPass::new(n, cutoff_hz, rate_hz)
            .map_err(|e| value_error(format!("EstimateLowPass: {e}")))?;
        Ok(PyEstimateLowPass {
            inner,
            raw: vec![0.0; n],
        })
    }

    /// One sample of the raw estimate `(n,)`; returns the filtered estimate, a new array.
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        raw: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        read_vector(raw, "raw", &mut self.raw, JOINTS)?;
        require_finite(&self.raw, "raw")?;
        Ok(PyArray1::from_slice(py, self.inner.update(&self.raw)))
    }

    /// The rows of `raw` `(N, n)`, one sample each, in order (continuing from the filter's
    /// state); returns the filtered `(N, n)`.
    fn filter<'py>(
        &mut self,
        py: Python<'py>,
        raw: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let n = self.inner.n();
        let (values, count, _) = rows(raw, "raw", n, false)?;
        require_finite(&values, "raw")?;
        let mut out = vec![0.0; values.len()];
        for (x, y) in values.chunks_exact(n).zip(out.chunks_exact_mut(n)) {
            y.copy_from_slice(self.inner.update(x));
        }
        let a = numpy::ndarray::Array2::from_shape_vec((count, n), out)
            .map_err(|e| value_error(format!("EstimateLowPass.filter: {e}")))?;
        Ok(PyArray2::from_owned_array(py, a))
    }

    /// Back to rest (zero).
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Number of joints.
    #[getter]
    fn n(&self) -> usize {
        self.inner.n()
    }
}
