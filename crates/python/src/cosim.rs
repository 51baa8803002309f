//! `CosimStepper`: the MuJoCo co-simulation's control steps in Rust (issue 33, part 3). One
//! call runs a stretch of control periods: the encoder read of MuJoCo's angles, the
//! `ClosedLoop` step, the command and the scripted push written into MuJoCo's
//! `qfrc_applied` and `xfrc_applied`, MuJoCo's own `mj_step` (its Python bindings, called
//! from here), the push's true joint torque `J^T f` (MuJoCo's `mj_jac`) and the
//! `VariantRecorder`'s gathering; on a step with contacts (a wall), their torque comes from
//! `MujocoArm.external_torque`. It does, value for value, what the Python loop of
//! `admittance.mujoco._cosim.run_variant_stepwise` does with `MujocoArm` and `Encoder`
//! (crates/python/tests/test_mujoco_stepper.py compares the two); only the Python calls
//! and numpy temporaries of every step are gone.

use numpy::prelude::*;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::closed_loop::{PyClosedLoop, PyVariantRecorder};
use crate::convert::{read_vector, value_error};

/// A float64 array of MuJoCo's `MjData` (or the stepper's Jacobian buffer), read and
/// written through its data pointer between calls into MuJoCo.
pub(crate) struct View {
    /// Keeps the array, and so the `MjData` memory it views, alive.
    _array: Py<PyAny>,
    ptr: *mut f64,
    len: usize,
}

impl View {
    pub(crate) fn new(
        plant: &Bound<'_, PyDict>,
        key: &str,
        len: usize,
        write: bool,
    ) -> PyResult<Self> {
        let obj = plant
            .get_item(key)?
            .ok_or_else(|| value_error(format!("CosimStepper: plant has no `{key}`")))?;
        let bad = || {
            value_error(format!(
                "CosimStepper: plant[`{key}`] must be a C-contiguous float64 array of {len} values{}",
                if write { ", writeable" } else { "" }
            ))
        };
        let a = obj.cast::<PyArrayDyn<f64>>().map_err(|_| bad())?;
        if a.len() != len || !a.is_c_contiguous() || (write && a.try_readwrite().is_err()) {
            return Err(bad());
        }
        Ok(View {
            _array: obj.clone().unbind(),
            ptr: a.data(),
            len,
        })
    }

    /// The values now. SAFETY of the slices here: the array is alive (held above), C
    /// contiguous with `len` elements; a slice lives only between two calls into MuJoCo
    /// (which writes this memory), while this thread holds the interpreter, so nothing
    /// else reads or writes it meanwhile.
    pub(crate) fn get(&self) -> &[f64] {
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }

    #[allow(clippy::mut_from_ref)]
    pub(crate) fn get_mut(&self) -> &mut [f64] {
        unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) }
    }
}

/// The MuJoCo side: the step and Jacobian functions with their argument tuples, the
/// arrays the loop reads and writes, and where the arm's joints and hand are in them.
pub(crate) struct Plant {
    data: Py<PyAny>,
    /// `MujocoArm.external_torque(push)`, for the steps with contacts; `None`: the arm has
    /// no geometry (no contacts).
    contact_torque: Option<Py<PyAny>>,
    mj_step: Py<PyAny>,
    step_args: Py<PyTuple>,
    mj_jac: Py<PyAny>,
    jac_args: Py<PyTuple>,
    pub(crate) qpos: View,
    qvel: View,
    qfrc_applied: View,
    xfrc_applied: View,
    xpos: View,
    xipos: View,
    jacp: View,
    pub(crate) qpos_index: Vec<usize>,
    dof_index: Vec<usize>,
    tip: usize,
    nv: usize,
}

fn item<'py>(plant: &Bound<'py, PyDict>, key: &str) -> PyResult<Bound<'py, PyAny>> {
    plant
        .get_item(key)?
        .ok_or_else(|| value_error(format!("CosimStepper: plant has no `{key}`")))
}

impl Plant {
    pub(crate) fn new(plant: &Bound<'_, PyDict>, n: usize) -> PyResult<Self> {
        let py = plant.py();
        let nq: usize = item(plant, "nq")?.extract()?;
        let nv: usize = item(plant, "nv")?.extract()?;
        let nbody: usize = item(plant, "nbody")?.extract()?;
        let qpos_index: Vec<usize> = item(plant, "qpos_index")?.extract()?;
        let dof_index: Vec<usize> = item(plant, "dof_index")?.extract()?;
        let tip: usize = item(plant, "tip_body")?.extract()?;
        if qpos_index.len() != n || qpos_index.iter().any(|&i| i >= nq) {
            return Err(value_error(format!(
                "CosimStepper: qpos_index must hold {n} indices below nq = {nq}"
            )));
        }
        if dof_index.len() != n || dof_index.iter().any(|&i| i >= nv) || tip >= nbody {
            return Err(value_error(format!(
                "CosimStepper: dof_index must hold {n} indices below nv = {nv}, tip_body be below nbody = {nbody}"
            )));
        }
        let (model, data) = (item(plant, "model")?, item(plant, "data")?);
        let step_args = PyTuple::new(py, [&model, &data])?.unbind();
        let stored_data = data.clone().unbind();
        let jac_args = PyTuple::new(
            py,
            [
                model,
                data,
                item(plant, "jacp")?,
                item(plant, "jacr")?,
                item(plant, "tip_xpos")?,
                tip.into_pyobject(py)?.into_any(),
            ],
        )?
        .unbind();
        let contact_torque = item(plant, "contact_torque")?;
        Ok(Plant {
            data: stored_data,
            contact_torque: (!contact_torque.is_none()).then(|| contact_torque.unbind()),
            mj_step: item(plant, "mj_step")?.unbind(),
            step_args,
            mj_jac: item(plant, "mj_jac")?.unbind(),
            jac_args,
            qpos: View::new(plant, "qpos", nq, false)?,
            qvel: View::new(plant, "qvel", nv, false)?,
            qfrc_applied: View::new(plant, "qfrc_applied", nv, true)?,
            xfrc_applied: View::new(plant, "xfrc_applied", 6 * nbody, true)?,
            xpos: View::new(plant, "xpos", 3 * nbody, false)?,
            xipos: View::new(plant, "xipos", 3 * nbody, false)?,
            jacp: View::new(plant, "jacp", 3 * nv, false)?,
            qpos_index,
            dof_index,
            tip,
            nv,
        })
    }

    /// MuJoCo's `mj_step` on the arm (its Python bindings).
    pub(crate) fn step(&self, py: Python<'_>) -> PyResult<()> {
        self.mj_step.bind(py).call1(self.step_args.bind(py))?;
        Ok(())
    }

    /// `MujocoArm.step`'s inputs: the joint torques on the chain's dofs, the push at the
    /// tip frame's origin as a force and the moment of its offset from the body's centre
    /// of mass (`xfrc_applied` acts there), numpy's `cross` term by term.
    pub(crate) fn apply(&self, torque: &[f64], push: Option<&[f64]>) {
        let qfrc = self.qfrc_applied.get_mut();
        qfrc.fill(0.0);
        for (&d, &t) in self.dof_index.iter().zip(torque) {
            qfrc[d] = t;
        }
        let xfrc = self.xfrc_applied.get_mut();
        xfrc.fill(0.0);
        if let Some(f) = push {
            let (xpos, xipos) = (self.xpos.get(), self.xipos.get());
            let b = 3 * self.tip;
            let a = [
                xpos[b] - xipos[b],
                xpos[b + 1] - xipos[b + 1],
                xpos[b + 2] - xipos[b + 2],
            ];
            let w = &mut xfrc[6 * self.tip..6 * self.tip + 6];
            w[..3].copy_from_slice(f);
            w[3] = a[1] * f[2] - a[2] * f[1];
            w[4] = a[2] * f[0] - a[0] * f[2];
            w[5] = a[0] * f[1] - a[1] * f[0];
        }
    }

    /// `MujocoArm.external_torque`: without contacts, `J^T f` of the push at the tip, in
    /// its order (`zeros + (jacp[0] f0 + jacp[1] f1 + jacp[2] f2)`, no fused multiply-add),
    /// on the chain's dofs (zeros without a
    /// push); on a step with contacts, that Python function itself.
    fn external_torque(
        &self,
        py: Python<'_>,
        push: Option<&[f64]>,
        out: &mut [f64],
    ) -> PyResult<()> {
        if let Some(f) = &self.contact_torque {
            let ncon: usize = self
                .data
                .bind(py)
                .getattr(pyo3::intern!(py, "ncon"))?
                .extract()?;
            if ncon > 0 {
                let push = push.map(|p| numpy::PyArray1::from_slice(py, p));
                let tau = f.bind(py).call1((push,))?;
                return read_vector(&tau, "external_torque", out, "one value per joint");
            }
        }
        let Some(f) = push else {
            out.fill(0.0);
            return Ok(());
        };
        self.mj_jac.bind(py).call1(self.jac_args.bind(py))?;
        let (jacp, nv) = (self.jacp.get(), self.nv);
        for (o, &d) in out.iter_mut().zip(&self.dof_index) {
            *o = 0.0 + (jacp[d] * f[0] + jacp[nv + d] * f[1] + jacp[2 * nv + d] * f[2]);
        }
        Ok(())
    }
}

/// The plan of a variant, one row per control step: the desired motion, the encoder's
/// noise (already times its standard deviation) and the scripted push.
struct Plan {
    steps: usize,
    q_d: Vec<f64>,
    qdot_d: Vec<f64>,
    qddot_d: Vec<f64>,
    noise: Vec<f64>,
    push: Vec<f64>,
    push_on: Vec<bool>,
}

/// The values of a float64 `(steps, cols)` array, row after row (`name` in its errors).
pub(crate) fn rows(
    obj: &Bound<'_, PyAny>,
    name: &str,
    steps: usize,
    cols: usize,
) -> PyResult<Vec<f64>> {
    let a = obj.cast::<PyArrayDyn<f64>>().map_err(|_| {
        value_error(format!(
            "`{name}` must be a float64 array of shape ({steps}, {cols})"
        ))
    })?;
    if a.shape() != [steps, cols] {
        return Err(value_error(format!(
            "`{name}` has shape {:?}, expected ({steps}, {cols})",
            a.shape()
        )));
    }
    Ok(a.to_vec()
        .unwrap_or_else(|_| a.to_owned_array().iter().copied().collect()))
}

/// The control steps of one co-simulated variant, run in Rust (docs/python.md): built
/// from the variant's `ClosedLoop` and `VariantRecorder`, `plant` (a dict of the MuJoCo
/// arm's model, data, arrays and indices: `MujocoArm.stepper_plant()`), the control
/// period `dt` and, per step, the desired motion `q_d`, `qdot_d`, `qddot_d` `(steps, n)`,
/// the encoder's noise `(steps, n)` (times its standard deviation), the encoder's
/// `resolution` (rad) and the push at the hand `push` `(steps, 3)` with `push_on`
/// `(steps,)`.
#[pyclass(unsendable, module = "admittance._admittance", name = "CosimStepper")]
pub struct PyCosimStepper {
    closed_loop: Py<PyClosedLoop>,
    recorder: Py<PyVariantRecorder>,
    plant: Plant,
    plan: Plan,
    n: usize,
    dt: f64,
    resolution: f64,
    /// The true external torque of the last plant step (the oracle's input).
    tau_ext: Vec<f64>,
}

#[pymethods]
impl PyCosimStepper {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (closed_loop, recorder, plant, *, dt, q_d, qdot_d, qddot_d, noise, resolution, push, push_on))]
    fn new(
        closed_loop: Py<PyClosedLoop>,
        recorder: Py<PyVariantRecorder>,
        plant: &Bound<'_, PyDict>,
        dt: f64,
        q_d: &Bound<'_, PyAny>,
        qdot_d: &Bound<'_, PyAny>,
        qddot_d: &Bound<'_, PyAny>,
        noise: &Bound<'_, PyAny>,
        resolution: f64,
        push: &Bound<'_, PyAny>,
        push_on: Vec<bool>,
    ) -> PyResult<Self> {
        let py = plant.py();
        let n = closed_loop.bind(py).borrow().joints();
        if recorder.bind(py).borrow().joints() != n {
            return Err(value_error(
                "CosimStepper: the loop and the recorder differ in joints",
            ));
        }
        if !(dt.is_finite() && dt > 0.0 && resolution.is_finite() && resolution > 0.0) {
            return Err(value_error(
                "CosimStepper: dt and resolution must be positive",
            ));
        }
        let steps = push_on.len();
        let plan = Plan {
            steps,
            q_d: rows(q_d, "q_d", steps, n)?,
            qdot_d: rows(qdot_d, "qdot_d", steps, n)?,
            qddot_d: rows(qddot_d, "qddot_d", steps, n)?,
            noise: rows(noise, "noise", steps, n)?,
            push: rows(push, "push", steps, 3)?,
            push_on,
        };
        Ok(PyCosimStepper {
            plant: Plant::new(plant, n)?,
            closed_loop,
            recorder,
            plan,
            n,
            dt,
            resolution,
            tau_ext: vec![0.0; n],
        })
    }

    /// Runs the control steps `start..end` (of `0..steps`, in order, each once). Returns
    /// `None`, or why the variant diverged (the scenario runner's health rules: stop then).
    fn run(&mut self, py: Python<'_>, start: usize, end: usize) -> PyResult<Option<String>> {
        if start > end || end > self.plan.steps {
            return Err(value_error(format!(
                "CosimStepper.run: steps {start}..{end} not within 0..{}",
                self.plan.steps
            )));
        }
        let mut lp = self.closed_loop.bind(py).borrow_mut();
        let mut rec = self.recorder.bind(py).borrow_mut();
        let n = self.n;
        for k in start..end {
            let t = k as f64 * self.dt;
            let row = k * n..(k + 1) * n;
            // Encoder::read: q + noise, rounded (ties to even, numpy's round) to counts.
            let (qpos, res) = (self.plant.qpos.get(), self.resolution);
            for ((m, &i), &e) in lp
                .slot_mut(0)
                .iter_mut()
                .zip(&self.plant.qpos_index)
                .zip(&self.plan.noise[row.clone()])
            {
                *m = ((qpos[i] + e) / res).round_ties_even() * res;
            }
            lp.hold_command();
            lp.slot_mut(2).copy_from_slice(&self.plan.q_d[row.clone()]);
            lp.slot_mut(3)
                .copy_from_slice(&self.plan.qdot_d[row.clone()]);
            lp.slot_mut(4).copy_from_slice(&self.plan.qddot_d[row]);
            lp.slot_mut(5).copy_from_slice(&self.tau_ext);
            lp.step_input(t)?;
            let push = self.plan.push_on[k].then(|| &self.plan.push[3 * k..3 * k + 3]);
            self.plant.apply(lp.torque_now(), push);
            self.plant.step(py)?;
            self.plant.external_torque(py, push, &mut self.tau_ext)?;
            let (qpos, qvel) = (self.plant.qpos.get(), self.plant.qvel.get());
            let b = rec.input_mut();
            for j in 0..n {
                b[j] = qpos[self.plant.qpos_index[j]];
                b[n + j] = qvel[self.plant.dof_index[j]];
            }
            b[2 * n..3 * n].copy_from_slice(&self.tau_ext);
            b[3 * n..].copy_from_slice(lp.torque_now());
            if let Some(reason) = rec.add_input(&lp)? {
                return Ok(Some(reason));
            }
        }
        Ok(None)
    }

    /// Control steps in the plan.
    #[getter]
    fn steps(&self) -> usize {
        self.plan.steps
    }
}
