//! `FreeMotionStepper`: the co-simulation's free-motion recording in Rust (issue 33, part
//! 3): per control period the encoder read of MuJoCo's angles, the sensors' input
//! conditioning, the PD (with nominal gravity) on the excitation, the command into MuJoCo's
//! `qfrc_applied` and MuJoCo's `mj_step` (its Python bindings, called from here), the
//! conditioned signals written into preallocated numpy rows. The same values as the Python
//! loop of `admittance.mujoco._cosim.record_free_motion_stepwise`
//! (crates/python/tests/test_mujoco_stepper.py compares the two).

use admittance_control::{ControlInput, Controller, PdConfig, PdController};
use admittance_loop::InputConditioner;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::config;
use crate::convert::{config_error, value_error};
use crate::cosim::{rows, Plant, View};
use crate::model::PyModel;

/// The free-motion recording's control steps in Rust: built from the arm `m`, the PD's
/// `pd_config` (`PdController`'s keys), `plant` (`MujocoArm.stepper_plant()`), the control
/// period `dt`, the sensors' low-pass `sensor_cutoff_hz` at `rate_hz`, the encoder's
/// `resolution` and `out`, the rows `q`, `qdot`, `qddot`, `tau` `(steps, n)` (C-contiguous
/// float64) it writes: the conditioned signals of each step. `run` takes the plan of a
/// stretch of steps (the desired motion and the encoder's noise), so that a long recording
/// never holds all of it.
#[pyclass(
    unsendable,
    module = "admittance._admittance",
    name = "FreeMotionStepper"
)]
pub struct PyFreeMotionStepper {
    plant: Plant,
    controller: PdController,
    sensors: InputConditioner,
    n: usize,
    steps: usize,
    dt: f64,
    resolution: f64,
    /// The rows written: `q, qdot, qddot, tau`.
    out: [View; 4],
    q_meas: Vec<f64>,
    /// The command of the last step (zeros before the first).
    torque: Vec<f64>,
    zeros: Vec<f64>,
}

#[pymethods]
impl PyFreeMotionStepper {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (m, pd_config, plant, *, dt, sensor_cutoff_hz, rate_hz, resolution, out))]
    fn new(
        m: &Bound<'_, PyModel>,
        pd_config: &Bound<'_, PyAny>,
        plant: &Bound<'_, PyDict>,
        dt: f64,
        sensor_cutoff_hz: f64,
        rate_hz: f64,
        resolution: f64,
        out: &Bound<'_, PyDict>,
    ) -> PyResult<Self> {
        let cfg: PdConfig = config::parse(Some(pd_config), "PdController config")?;
        let model = m.get().model.clone();
        let n = model.nq();
        let controller =
            PdController::new(model, &cfg).map_err(|e| config_error("PdController config", e))?;
        let sensors = InputConditioner::new(n, sensor_cutoff_hz, rate_hz)
            .map_err(|e| value_error(format!("FreeMotionStepper: {e}")))?;
        if !(dt.is_finite() && dt > 0.0 && resolution.is_finite() && resolution > 0.0) {
            return Err(value_error(
                "FreeMotionStepper: dt and resolution must be positive",
            ));
        }
        let steps = out
            .get_item("q")?
            .ok_or_else(|| value_error("FreeMotionStepper: out has no `q`"))?
            .len()?;
        let out = [
            View::new(out, "q", steps * n, true)?,
            View::new(out, "qdot", steps * n, true)?,
            View::new(out, "qddot", steps * n, true)?,
            View::new(out, "tau", steps * n, true)?,
        ];
        Ok(PyFreeMotionStepper {
            plant: Plant::new(plant, n)?,
            controller,
            sensors,
            n,
            steps,
            dt,
            resolution,
            out,
            q_meas: vec![0.0; n],
            torque: vec![0.0; n],
            zeros: vec![0.0; n],
        })
    }

    /// Records the control steps from `start` on, one per row of `q_d`, `qdot_d`,
    /// `qddot_d` (the desired motion) and `noise` (the encoder's, times its standard
    /// deviation), `(count, n)` each (in order, each step once). `ValueError` on a
    /// non-finite encoder read or command (the sensors refuse it), `RuntimeError` when
    /// MuJoCo's angles are no longer finite.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &mut self,
        py: Python<'_>,
        start: usize,
        q_d: &Bound<'_, PyAny>,
        qdot_d: &Bound<'_, PyAny>,
        qddot_d: &Bound<'_, PyAny>,
        noise: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (n, count) = (self.n, q_d.len()?);
        if start + count > self.steps {
            return Err(value_error(format!(
                "FreeMotionStepper.run: steps {start}..{} not within 0..{}",
                start + count,
                self.steps
            )));
        }
        let plan = [
            rows(q_d, "q_d", count, n)?,
            rows(qdot_d, "qdot_d", count, n)?,
            rows(qddot_d, "qddot_d", count, n)?,
            rows(noise, "noise", count, n)?,
        ];
        for c in 0..count {
            let k = start + c;
            let t = k as f64 * self.dt;
            let (row, plan_row) = (k * n..(k + 1) * n, c * n..(c + 1) * n);
            // Encoder::read: q + noise, rounded (ties to even, numpy's round) to counts.
            let (qpos, res) = (self.plant.qpos.get(), self.resolution);
            for ((m, &i), &e) in self
                .q_meas
                .iter_mut()
                .zip(&self.plant.qpos_index)
                .zip(&plan[3][plan_row.clone()])
            {
                *m = ((qpos[i] + e) / res).round_ties_even() * res;
            }
            // InputConditioner.update's check: a non-finite sample would stay in the filter.
            for (v, name) in [(&self.q_meas, "q"), (&self.torque, "tau")] {
                if let Some(j) = v.iter().position(|x| !x.is_finite()) {
                    return Err(value_error(format!(
                        "`{name}` element {j} is {}: every value must be finite",
                        v[j]
                    )));
                }
            }
            self.sensors.update(&self.q_meas, &self.torque);
            let s = &self.sensors;
            for (view, v) in self.out.iter().zip([&s.q, &s.qdot, &s.qddot, &s.tau]) {
                view.get_mut()[row.clone()].copy_from_slice(v);
            }
            let input = ControlInput {
                time: t,
                q: &self.q_meas,
                qdot: &s.qdot,
                q_ref: &plan[0][plan_row.clone()],
                qdot_ref: &plan[1][plan_row.clone()],
                qddot_ref: &plan[2][plan_row],
                external_torque_estimate: &self.zeros,
            };
            let _ = self.controller.step(&input, self.dt, &mut self.torque);
            self.plant.apply(&self.torque, None);
            self.plant.step(py)?;
            let qpos = self.plant.qpos.get();
            if self.plant.qpos_index.iter().any(|&i| !qpos[i].is_finite()) {
                return Err(PyRuntimeError::new_err(format!(
                    "the free-motion recording diverged at t = {t:.3} s"
                )));
            }
        }
        Ok(())
    }

    /// Control steps in the plan.
    #[getter]
    fn steps(&self) -> usize {
        self.steps
    }
}
