//! `Admittance`: the joint-space admittance model with the smooth reference saturation
//! (docs/method.md section 2, eq. 5-7).

use admittance_control::{
    Admittance, AdmittanceConfig, AdmittanceInput, JointValues, SaturationConfig,
};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::config;
use crate::control::{stepped_pymethods, FaultRecord};
use crate::convert::{config_error, read_vector, value_error, vector_out};
use crate::model::PyModel;

const JOINTS: &str = "one value per joint, in chain order";

/// The admittance model `M_d (q_a'' - q_d'') + C_d (q_a' - q_d') + G_d (q_a - q_d) =
/// tau_ext_hat` (docs/method.md section 2; without `mass` first order) and the smooth saturation
/// `q_r = c + sat(q_a - c)` that keeps the reference strictly inside `(c - C, c + C)`.
///
/// `damping` (C_d), `stiffness` (G_d) and `mass` (M_d, optional) are one number or one per
/// joint. The saturation: `rho` in (0, 1) is the linear fraction of the range (`None`: no
/// saturation); `bound=None` takes the range from the joint limits of `m` (centre and
/// half-range of `[lower, upper]`; a joint without finite limits is not saturated), a number
/// or one per joint is the half-range `C` about 0 (the paper: `bound=1.1`; `inf`: that joint
/// not saturated). `deadband` (N m, one number or one per joint, e.g. a contact floor's
/// `contact_thresholds`): an estimate within it moves nothing, above it only the excess
/// drives the model, through a smooth knee (default: none). `Admittance.from_config` takes a
/// scenario's `[admittance]` keys instead.
///
/// `step` never raises on bad numbers: on a non-finite input or an invalid `dt` it keeps its
/// state, returns the last reference with zero velocity and acceleration, and records the
/// fault in `fault` / `fault_count`.
#[pyclass(module = "admittance._admittance", name = "Admittance")]
pub struct PyAdmittance {
    inner: Admittance,
    n: usize,
    /// `q_d, qdot_d, qddot_d, tau_ext_hat`, `n` each.
    input: Vec<f64>,
    faults: FaultRecord,
}

/// A configuration key as the keyword constructor calls it.
fn keyword_name(key: &str) -> String {
    for (config_key, keyword) in [
        ("saturation.rho", "rho"),
        ("saturation.half_range", "bound"),
        ("saturation.centre", "bound"),
        ("inertia", "mass"),
    ] {
        if let Some(rest) = key.strip_prefix(config_key) {
            return format!("{keyword}{rest}");
        }
    }
    key.to_string()
}

impl PyAdmittance {
    fn build(n: usize, cfg: &AdmittanceConfig, context: &str, keywords: bool) -> PyResult<Self> {
        let inner = Admittance::new(n, cfg).map_err(|mut e| {
            if keywords {
                e.key = keyword_name(&e.key);
            }
            config_error(context, e)
        })?;
        Ok(PyAdmittance {
            inner,
            n,
            input: vec![0.0; 4 * n],
            faults: FaultRecord::new(),
        })
    }
}

stepped_pymethods!(PyAdmittance {
    #[new]
    #[pyo3(signature = (m, damping, stiffness, mass=None, rho=Some(0.95), bound=None, deadband=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        m: &Bound<'_, PyModel>,
        damping: &Bound<'_, PyAny>,
        stiffness: &Bound<'_, PyAny>,
        mass: Option<&Bound<'_, PyAny>>,
        rho: Option<f64>,
        bound: Option<&Bound<'_, PyAny>>,
        deadband: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let pm = m.get();
        let n = pm.dof();
        let inertia = match mass {
            Some(v) if !v.is_none() => Some(config::joint_values(v, "mass", n)?),
            _ => None,
        };
        let saturation =
            match (rho, bound) {
                (None, Some(b)) if !b.is_none() => return Err(value_error(
                    "Admittance: `bound` needs `rho` (the saturation's linear fraction, e.g. 0.95)",
                )),
                (None, _) => None,
                (Some(rho), Some(b)) if !b.is_none() => Some(SaturationConfig {
                    rho,
                    centre: JointValues::Uniform(0.0),
                    half_range: config::joint_values(b, "bound", n)?,
                }),
                (Some(rho), _) => {
                    let (lower, upper) = pm.model.position_limits().unzip::<f64, f64, Vec<f64>, Vec<f64>>();
                    Some(SaturationConfig::from_limits(rho, &lower, &upper))
                }
            };
        let cfg = AdmittanceConfig {
            damping: config::joint_values(damping, "damping", n)?,
            stiffness: config::joint_values(stiffness, "stiffness", n)?,
            inertia,
            saturation,
        };
        let mut built = Self::build(n, &cfg, "Admittance", true)?;
        if let Some(d) = deadband.filter(|d| !d.is_none()) {
            let d = match d.extract::<f64>() {
                Ok(v) => vec![v; n],
                Err(_) => crate::convert::vector(d, "deadband", n, JOINTS)?,
            };
            built.inner = built
                .inner
                .with_deadband(&d)
                .map_err(|e| config_error("Admittance", e))?;
        }
        Ok(built)
    }

    /// An admittance model from the keys of a scenario's `[admittance]` table (`damping`,
    /// `stiffness`, `inertia`, `saturation = {rho, centre, half_range}`), validated as in a
    /// scenario file.
    #[staticmethod]
    fn from_config(m: &Bound<'_, PyModel>, config: &Bound<'_, PyAny>) -> PyResult<Self> {
        let cfg: AdmittanceConfig = config::parse(Some(config), "Admittance config")?;
        Self::build(m.get().dof(), &cfg, "Admittance config", false)
    }

    /// Advances the model by `dt` (s) with the desired trajectory `q_d`, `qdot_d`,
    /// `qddot_d` and the external-torque estimate `tau_ext_hat` (each `(n,)`); returns the
    /// compliant reference `(q_r, qdot_r, qddot_r)`. With `out`, a tuple of three float64
    /// `(n,)` arrays, the reference is written into them and they are returned.
    #[allow(clippy::type_complexity, clippy::too_many_arguments)]
    #[pyo3(signature = (q_d, qdot_d, qddot_d, tau_ext_hat, dt, *, out=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        q_d: &Bound<'py, PyAny>,
        qdot_d: &Bound<'py, PyAny>,
        qddot_d: &Bound<'py, PyAny>,
        tau_ext_hat: &Bound<'py, PyAny>,
        dt: f64,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let n = self.n;
        let outs = match out {
            None => [None, None, None],
            Some(o) => {
                let t = o
                    .cast::<PyTuple>()
                    .ok()
                    .filter(|t| t.len() == 3)
                    .ok_or_else(|| {
                        value_error(format!(
                        "`out` must be a tuple of three writeable float64 arrays of shape ({n},)"
                    ))
                    })?;
                [
                    Some(t.get_item(0)?),
                    Some(t.get_item(1)?),
                    Some(t.get_item(2)?),
                ]
            }
        };
        let b = &mut self.input;
        read_vector(q_d, "q_d", &mut b[..n], JOINTS)?;
        read_vector(qdot_d, "qdot_d", &mut b[n..2 * n], JOINTS)?;
        read_vector(qddot_d, "qddot_d", &mut b[2 * n..3 * n], JOINTS)?;
        read_vector(tau_ext_hat, "tau_ext_hat", &mut b[3 * n..], JOINTS)?;
        let input = AdmittanceInput {
            q_d: &b[..n],
            qdot_d: &b[n..2 * n],
            qddot_d: &b[2 * n..3 * n],
            external_torque_estimate: &b[3 * n..],
        };
        let status = self.inner.step(&input, dt);
        self.faults.record(status);
        Ok((
            vector_out(py, self.inner.q_r(), outs[0].as_ref(), "out[0]")?,
            vector_out(py, self.inner.qdot_r(), outs[1].as_ref(), "out[1]")?,
            vector_out(py, self.inner.qddot_r(), outs[2].as_ref(), "out[2]")?,
        ))
    }

    /// Back to zero deviation (`q_a = q_d`).
    fn reset(&mut self) {
        self.inner.reset();
        self.faults = FaultRecord::new();
    }

    /// The unsaturated admittance state `q_a` after the last step, `(n,)`.
    #[getter]
    fn q_a<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.q_a())
    }

    /// The deviation `q_a - q_d` after the last step, `(n,)`.
    #[getter]
    fn deviation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.deviation())
    }
});
