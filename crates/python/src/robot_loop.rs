//! `RobotLoop`: the robot's side of the loop in Python, the Rust `admittance_loop::RobotLoop`
//! that the C ABI and the ROS 2 bridge wrap too (docs/your_robot.md): raw measured angles and
//! torques in, through the plausibility gates and the signal chain, command, estimate,
//! reference, wrench and a status out. Built from a deployment folder (`admittance deploy`);
//! it never trains.

use std::path::PathBuf;

use admittance_loop::{Implausible, RobotInput, RobotLoop, RobotStatus};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{read_vector, value_error};

const JOINTS: &str = "one value per joint, in chain order";

/// An optional argument that was given and is not `None`.
fn given<'a, 'py>(v: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
    v.filter(|v| !v.is_none())
}

/// The robot's loop of a deployment folder (the loop `adm_create` of the C ABI builds).
///
/// `RobotLoop.load(path, overrides=None, *, wrench=False)` reads and verifies the folder
/// (a missing or edited file is a `ValueError` naming it). `step(t, q, tau=None, *,
/// qdot=None, q_d=None, qdot_d=None, qddot_d=None)` takes one period's raw measurements
/// (`tau=None`: the loop's last command; no `q_d`: hold the first measured pose) and returns
/// `(torque, estimate)`; `status` says what the step saw (implausible samples, no angle yet,
/// faults). A step never raises on bad numbers: NaN and implausible values are flagged and
/// held, as in the C ABI.
#[pyclass(unsendable, module = "admittance._admittance", name = "RobotLoop")]
pub struct PyRobotLoop {
    inner: RobotLoop,
    n: usize,
    /// `q, tau, qdot, q_d, qdot_d, qddot_d`, `n` each.
    input: Vec<f64>,
    status: Option<RobotStatus>,
}

#[pymethods]
impl PyRobotLoop {
    /// Loads a deployment folder; `overrides` are `KEY=VALUE` settings of its loop.toml;
    /// `wrench=True` estimates the hand wrench each step.
    #[staticmethod]
    #[pyo3(signature = (path, overrides=None, *, wrench=false))]
    fn load(path: PathBuf, overrides: Option<Vec<String>>, wrench: bool) -> PyResult<Self> {
        let overrides = overrides.unwrap_or_default();
        let refs: Vec<&str> = overrides.iter().map(String::as_str).collect();
        let mut inner = RobotLoop::load(&path, &refs).map_err(|e| value_error(e.text()))?;
        if wrench {
            inner
                .enable_wrench(0.0)
                .map_err(|e| value_error(e.text()))?;
        }
        let n = inner.dof();
        Ok(Self {
            inner,
            n,
            input: vec![0.0; 6 * n],
            status: None,
        })
    }

    /// One control period at `t` (s); returns `(torque, estimate)` as float64 `(n,)` arrays.
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    #[pyo3(signature = (t, q, tau=None, *, qdot=None, q_d=None, qdot_d=None, qddot_d=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        tau: Option<&Bound<'py, PyAny>>,
        qdot: Option<&Bound<'py, PyAny>>,
        q_d: Option<&Bound<'py, PyAny>>,
        qdot_d: Option<&Bound<'py, PyAny>>,
        qddot_d: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        // As the C ABI's ADM_ERR_TIME: nothing is stepped on a time that is not finite.
        if !t.is_finite() {
            return Err(value_error(format!(
                "`t` is {t}: the sample time must be finite (nothing was stepped)"
            )));
        }
        let n = self.n;
        let b = &mut self.input;
        read_vector(q, "q", &mut b[..n], JOINTS)?;
        let has_tau = given(tau).is_some();
        if let Some(v) = given(tau) {
            read_vector(v, "tau", &mut b[n..2 * n], JOINTS)?;
        }
        let has_qdot = given(qdot).is_some();
        if let Some(v) = given(qdot) {
            read_vector(v, "qdot", &mut b[2 * n..3 * n], JOINTS)?;
        }
        let has_desired = given(q_d).is_some();
        if let Some(v) = given(q_d) {
            read_vector(v, "q_d", &mut b[3 * n..4 * n], JOINTS)?;
            b[4 * n..].fill(0.0);
            if let Some(v) = given(qdot_d) {
                read_vector(v, "qdot_d", &mut b[4 * n..5 * n], JOINTS)?;
            }
            if let Some(v) = given(qddot_d) {
                read_vector(v, "qddot_d", &mut b[5 * n..], JOINTS)?;
            }
        } else if given(qdot_d).is_some() || given(qddot_d).is_some() {
            return Err(value_error("qdot_d and qddot_d need q_d"));
        }
        let b = &self.input;
        let status = self.inner.step(&RobotInput {
            time: t,
            q: &b[..n],
            tau: has_tau.then_some(&b[n..2 * n]),
            qdot: has_qdot.then_some(&b[2 * n..3 * n]),
            desired: has_desired.then_some([&b[3 * n..4 * n], &b[4 * n..5 * n], &b[5 * n..]]),
        });
        self.status = Some(status);
        Ok((
            PyArray1::from_slice(py, self.inner.torque()),
            PyArray1::from_slice(py, self.inner.external_torque_estimate()),
        ))
    }

    /// What the last step saw: `ok`, `controller_fault` (text or None), `observer_fault`,
    /// `nonfinite_input`, `implausible` (None or `(joint, "angle" | "jump" | "torque")`),
    /// `waiting_for_angles`, `warmup`, `holding_pose`, `stale_input`, `outside_training_range`
    /// (an angle outside the positions the identification was fitted on),
    /// `faster_than_training` (a velocity beyond the speeds it was fitted at), `contact` (None or
    /// a dict of `contact`, `collision`, `link`); None before the first step.
    #[getter]
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(s) = &self.status else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("ok", s.is_ok())?;
        d.set_item(
            "controller_fault",
            s.controller_fault.map(|f| format!("{f:?}")),
        )?;
        d.set_item("observer_fault", s.observer_fault)?;
        d.set_item("nonfinite_input", s.nonfinite_input)?;
        d.set_item(
            "implausible",
            s.implausible.map(|g| {
                let gate = match g.gate {
                    Implausible::Angle => "angle",
                    Implausible::Jump => "jump",
                    Implausible::Torque => "torque",
                    Implausible::Velocity => "velocity",
                };
                (g.joint, gate)
            }),
        )?;
        d.set_item("waiting_for_angles", s.waiting_for_angles)?;
        d.set_item("warmup", s.warmup)?;
        d.set_item("holding_pose", s.holding_pose)?;
        d.set_item("stale_input", s.stale_input)?;
        d.set_item("outside_training_range", s.outside_training_range)?;
        d.set_item("faster_than_training", s.faster_than_training)?;
        match s.contact {
            Some(c) => {
                let cd = PyDict::new(py);
                cd.set_item("contact", c.contact)?;
                cd.set_item("collision", c.collision)?;
                cd.set_item("link", c.link)?;
                d.set_item("contact", cd)?;
            }
            None => d.set_item("contact", py.None())?,
        }
        Ok(Some(d))
    }

    /// Samples refused by the plausibility gates so far.
    #[getter]
    fn implausible_samples(&self) -> u64 {
        self.inner.implausible_samples()
    }

    /// Number of joints.
    #[getter]
    fn n(&self) -> usize {
        self.n
    }

    /// Joint names in chain order.
    #[getter]
    fn joints(&self) -> Vec<String> {
        self.inner.joints().to_vec()
    }

    /// The control period (s).
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.dt()
    }

    /// The compliant reference `(q_r, qdot_r, qddot_r)` of the last step.
    #[getter]
    fn reference<'py>(
        &self,
        py: Python<'py>,
    ) -> (
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    ) {
        let [a, b, c] = self.inner.reference();
        (
            PyArray1::from_slice(py, a),
            PyArray1::from_slice(py, b),
            PyArray1::from_slice(py, c),
        )
    }

    /// The hand wrench of the last step `(base, tip)` (force N, moment N m), with
    /// `wrench=True`; else None.
    #[getter]
    fn wrench<'py>(
        &self,
        py: Python<'py>,
    ) -> Option<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        self.inner
            .wrench()
            .map(|(b, t)| (PyArray1::from_slice(py, b), PyArray1::from_slice(py, t)))
    }

    /// With a contact floor, the wrench at the touched link of the last step `(base, link)`
    /// (force N, moment N m, in the base axes and the link's; zero while no contact is
    /// flagged); else None.
    #[getter]
    fn contact_wrench<'py>(
        &self,
        py: Python<'py>,
    ) -> Option<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        self.inner
            .contact_wrench()
            .map(|(b, l)| (PyArray1::from_slice(py, b), PyArray1::from_slice(py, l)))
    }

    fn __repr__(&self) -> String {
        format!(
            "RobotLoop({} joints at {:.0} Hz, {} implausible samples)",
            self.n,
            1.0 / self.inner.dt(),
            self.inner.implausible_samples()
        )
    }
}
