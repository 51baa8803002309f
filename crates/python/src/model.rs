//! `Model` and the dynamics functions (`rnea`, `crba`, `gravity`, `coriolis`, `tip_pose`,
//! `tip_jacobian`, `aba`): the conventions of `admittance dynamics` (SI units, base frame,
//! linear rows first, gravity `(0, 0, -9.81)` unless the model's is changed).

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use admittance_dynamics::{
    aba as rust_aba, coriolis_matrix, crba as rust_crba, forward_kinematics, gravity_torque,
    rnea as rust_rnea, tip_jacobian as rust_tip_jacobian, Data, Model,
};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::convert::{dynamics_error, matrix_out, require_finite, value_error, vector, vector_out};

/// A serial arm loaded from a URDF: the chain from a base link to a tip link.
///
/// Immutable; build it once with `Model.from_urdf` and pass it to the dynamics functions,
/// controllers and observers. Joint order is chain order (`joint_names`).
#[pyclass(frozen, module = "admittance._admittance", name = "Model")]
pub struct PyModel {
    pub(crate) model: Arc<Model>,
    /// The workspace of the dynamics functions (one call at a time).
    data: Mutex<Data>,
}

impl PyModel {
    pub(crate) fn new(model: Model) -> Self {
        let data = Mutex::new(Data::new(&model));
        PyModel {
            model: Arc::new(model),
            data,
        }
    }

    pub(crate) fn dof(&self) -> usize {
        self.model.nq()
    }

    fn data(&self) -> MutexGuard<'_, Data> {
        // A panic cannot happen inside the algorithms (lengths are checked), so the lock
        // is never poisoned; take the data either way.
        self.data.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A joint vector argument, checked for shape and finiteness.
    pub(crate) fn joint_vector(&self, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
        let v = vector(obj, name, self.dof(), "one value per joint, in chain order")?;
        require_finite(&v, name)?;
        Ok(v)
    }

    fn limits(&self, f: impl Fn(&admittance_dynamics::JointLimits) -> f64) -> Vec<f64> {
        self.model.joints.iter().map(|j| f(&j.limits)).collect()
    }
}

#[pymethods]
impl PyModel {
    /// Loads the chain between `base` (default: the URDF's root link) and `tip` (default:
    /// the arm's hand, past gripper fingers) from a URDF file, as `admittance model` does.
    /// Revolute, continuous, prismatic and fixed joints; fixed joints fold their child's
    /// inertia into the moving body; moving branches off the chain are held at 0 (or at
    /// `lock={"joint": value}`) with their mass kept, or left out (`drop=["joint"]`).
    /// Gravity is the root link's -z in `base`'s axes (`gravity`): joints above the base
    /// turn it, moving ones at 0 or their `lock` value. Physically impossible inertias load with a warning (`warnings`) unless `strict`. A
    /// bad file is a `ValueError` naming the file, line and element; a missing one an
    /// `OSError`.
    #[staticmethod]
    #[pyo3(signature = (path, base=None, tip=None, *, strict=false, lock=None, drop=None))]
    fn from_urdf(
        py: Python<'_>,
        path: PathBuf,
        base: Option<String>,
        tip: Option<String>,
        strict: bool,
        lock: Option<std::collections::BTreeMap<String, f64>>,
        drop: Option<Vec<String>>,
    ) -> PyResult<Self> {
        let options = admittance_dynamics::UrdfOptions {
            base,
            tip,
            strict,
            lock: lock.unwrap_or_default().into_iter().collect(),
            drop: drop.unwrap_or_default(),
        };
        let model = py
            .detach(|| Model::from_urdf_file_with(&path, &options))
            .map_err(dynamics_error)?;
        Ok(PyModel::new(model))
    }

    /// What the loader accepted with a warning (`file:line: element: problem`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.model
            .warnings()
            .iter()
            .map(|w| w.to_string())
            .collect()
    }

    /// Loads the chain from URDF text (`source` names the text in error messages).
    #[staticmethod]
    #[pyo3(signature = (text, base=None, tip=None, source="<string>"))]
    fn from_urdf_string(
        text: &str,
        base: Option<String>,
        tip: Option<String>,
        source: &str,
    ) -> PyResult<Self> {
        let model = Model::from_urdf_str(text, source, base.as_deref(), tip.as_deref())
            .map_err(dynamics_error)?;
        Ok(PyModel::new(model))
    }

    /// Number of moving joints.
    #[getter]
    fn n(&self) -> usize {
        self.model.nq()
    }

    /// Names of the moving joints, in chain order.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.model.joint_names().map(String::from).collect()
    }

    /// Lower position limits (rad or m; `-inf` where the URDF gives none).
    #[getter]
    fn lower<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.limits(|l| l.lower))
    }

    /// Upper position limits (rad or m; `inf` where the URDF gives none).
    #[getter]
    fn upper<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.limits(|l| l.upper))
    }

    /// Velocity limits (rad/s or m/s; `inf` where the URDF gives none).
    #[getter]
    fn velocity_limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.limits(|l| l.velocity))
    }

    /// Effort limits (N m or N; `inf` where the URDF gives none).
    #[getter]
    fn effort_limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.limits(|l| l.effort))
    }

    /// Gravity in the base frame (m/s^2), `(3,)`.
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.model.gravity.as_slice())
    }

    /// The base link's name.
    #[getter]
    fn base_link(&self) -> String {
        self.model.base_link.clone()
    }

    /// The tip frame's name.
    #[getter]
    fn tip_link(&self) -> String {
        self.model.tip().name.clone()
    }

    /// Total mass of the moving bodies (kg).
    #[getter]
    fn total_moving_mass(&self) -> f64 {
        self.model.total_moving_mass()
    }

    /// A copy with gravity `g` (3 values, base frame, m/s^2).
    fn with_gravity(&self, g: &Bound<'_, PyAny>) -> PyResult<Self> {
        let g = vector(g, "g", 3, "GX, GY, GZ in the base frame")?;
        require_finite(&g, "g")?;
        let mut m = (*self.model).clone();
        m.gravity = nalgebra::Vector3::new(g[0], g[1], g[2]);
        Ok(PyModel::new(m))
    }

    /// A copy with every body's mass and inertia multiplied by `scale` (> 0): e.g. 0.8 for
    /// an observer's nominal model with a 20 % inertia error (`observer.nominal_inertia_scale`).
    fn with_scaled_inertias(&self, scale: f64) -> PyResult<Self> {
        let m = self
            .model
            .with_scaled_inertias(scale)
            .map_err(dynamics_error)?;
        Ok(PyModel::new(m))
    }

    fn __repr__(&self) -> String {
        format!(
            "Model('{}', {} -> {}, n={})",
            self.model.robot_name,
            self.model.base_link,
            self.model.tip().name,
            self.model.nq()
        )
    }
}

/// Inverse dynamics `tau = M(q) a + C(q, v) v + G(q)` (RNEA), `(n,)`.
#[pyfunction]
#[pyo3(signature = (m, q, v, a, *, out=None))]
pub fn rnea<'py>(
    m: &Bound<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    a: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let pm = m.get();
    let (q, v, a) = (
        pm.joint_vector(q, "q")?,
        pm.joint_vector(v, "v")?,
        pm.joint_vector(a, "a")?,
    );
    let mut data = pm.data();
    let tau =
        rust_rnea(&pm.model, &mut data, &q, &v, &a).map_err(|e| value_error(e.to_string()))?;
    vector_out(m.py(), tau.as_slice(), out, "out")
}

/// Joint-space inertia matrix `M(q)` (CRBA), `(n, n)`.
#[pyfunction]
#[pyo3(signature = (m, q, *, out=None))]
pub fn crba<'py>(
    m: &Bound<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let pm = m.get();
    let q = pm.joint_vector(q, "q")?;
    let mut data = pm.data();
    let mass = rust_crba(&pm.model, &mut data, &q).map_err(|e| value_error(e.to_string()))?;
    let n = pm.dof();
    matrix_out(m.py(), (n, n), |i, j| mass[(i, j)], out, "out")
}

/// Gravity torque `G(q)`, `(n,)`.
#[pyfunction]
#[pyo3(signature = (m, q, *, out=None))]
pub fn gravity<'py>(
    m: &Bound<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let pm = m.get();
    let q = pm.joint_vector(q, "q")?;
    let mut data = pm.data();
    let g = gravity_torque(&pm.model, &mut data, &q).map_err(|e| value_error(e.to_string()))?;
    vector_out(m.py(), g.as_slice(), out, "out")
}

/// Coriolis matrix `C(q, v)` with `dM/dt = C + C^T` (so `C(q, v) v` is the Coriolis and
/// centrifugal torque), `(n, n)`.
#[pyfunction]
#[pyo3(signature = (m, q, v, *, out=None))]
pub fn coriolis<'py>(
    m: &Bound<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let pm = m.get();
    let (q, v) = (pm.joint_vector(q, "q")?, pm.joint_vector(v, "v")?);
    let mut data = pm.data();
    let c =
        coriolis_matrix(&pm.model, &mut data, &q, &v).map_err(|e| value_error(e.to_string()))?;
    let n = pm.dof();
    matrix_out(m.py(), (n, n), |i, j| c[(i, j)], out, "out")
}

/// A position `(3,)` and a rotation `(3, 3)`.
type Pose<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// Pose of the tip frame in the base frame: `(position (3,), rotation (3, 3))`, the
/// rotation's columns being the tip's axes in base coordinates.
#[pyfunction]
pub fn tip_pose<'py>(m: &Bound<'py, PyModel>, q: &Bound<'py, PyAny>) -> PyResult<Pose<'py>> {
    let pm = m.get();
    let q = pm.joint_vector(q, "q")?;
    let mut data = pm.data();
    forward_kinematics(&pm.model, &mut data, &q).map_err(|e| value_error(e.to_string()))?;
    let tip = data.tip_placement(&pm.model);
    let py = m.py();
    let position = PyArray1::from_slice(py, tip.translation.as_slice());
    let rotation = matrix_out(py, (3, 3), |i, j| tip.rotation[(i, j)], None, "out")?;
    Ok((position, rotation))
}

/// Geometric Jacobian of the tip frame, `(6, n)`: linear rows first, base axes, at the
/// tip's origin (`[v; w] = J qdot`).
#[pyfunction]
#[pyo3(signature = (m, q, *, out=None))]
pub fn tip_jacobian<'py>(
    m: &Bound<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let pm = m.get();
    let q = pm.joint_vector(q, "q")?;
    let mut data = pm.data();
    let j = rust_tip_jacobian(&pm.model, &mut data, &q).map_err(|e| value_error(e.to_string()))?;
    matrix_out(m.py(), (6, pm.dof()), |r, c| j[(r, c)], out, "out")
}

/// Forward dynamics `qddot = M(q)^-1 (tau - C(q, v) v - G(q))` (ABA), `(n,)`.
#[pyfunction]
#[pyo3(signature = (m, q, v, tau, *, out=None))]
pub fn aba<'py>(
    m: &Bound<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let pm = m.get();
    let (q, v, tau) = (
        pm.joint_vector(q, "q")?,
        pm.joint_vector(v, "v")?,
        pm.joint_vector(tau, "tau")?,
    );
    let mut data = pm.data();
    let qdd =
        rust_aba(&pm.model, &mut data, &q, &v, &tau).map_err(|e| value_error(e.to_string()))?;
    vector_out(m.py(), qdd.as_slice(), out, "out")
}
