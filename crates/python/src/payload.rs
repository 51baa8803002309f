//! The payload from Python: `identify_payload(data, ident)` and the `Payload` it returns
//! (issue 30's contract; docs/python.md, "Identification"). `Identification.with_payload`
//! lives with the identification's methods.

use admittance_dynamics::{identify_payload as rust_identify_payload, Payload};
use nalgebra::{Matrix3, Vector3};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::convert::{matrix_out, value_error, vector};
use crate::identification::{conditioned_columns, PyIdentification};

/// A rigid payload at the tip frame: `mass` (kg), `com` (m, tip frame) and `inertia`
/// (3 x 3, kg m^2, about the centre of mass in tip-frame axes). `identify_payload` fits
/// one; `Payload(mass, com, inertia)` states a known one.
#[pyclass(frozen, module = "admittance._admittance", name = "Payload")]
pub struct PyPayload {
    pub(crate) payload: Payload,
}

#[pymethods]
impl PyPayload {
    #[new]
    #[pyo3(signature = (mass, com, inertia=None))]
    fn new(
        mass: f64,
        com: &Bound<'_, PyAny>,
        inertia: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let c = vector(com, "com", 3, "the centre of mass in the tip frame (m)")?;
        let i = match inertia.filter(|i| !i.is_none()) {
            Some(i) => {
                let rows: Vec<Vec<f64>> = i.extract().map_err(|_| {
                    value_error(
                        "`inertia` must be a 3 x 3 matrix (kg m^2, about the centre of mass)",
                    )
                })?;
                if rows.len() != 3 || rows.iter().any(|r| r.len() != 3) {
                    return Err(value_error(
                        "`inertia` must be a 3 x 3 matrix (kg m^2, about the centre of mass)",
                    ));
                }
                Matrix3::from_fn(|r, k| rows[r][k])
            }
            None => Matrix3::zeros(),
        };
        let ok = mass.is_finite()
            && mass >= 0.0
            && c.iter().all(|v| v.is_finite())
            && i.iter().all(|v| v.is_finite());
        if !ok {
            return Err(value_error(
                "a payload needs a finite mass >= 0 and a finite com and inertia",
            ));
        }
        Ok(PyPayload {
            payload: Payload {
                mass,
                com: Vector3::new(c[0], c[1], c[2]),
                inertia: i,
            },
        })
    }

    /// Mass (kg).
    #[getter]
    fn mass(&self) -> f64 {
        self.payload.mass
    }

    /// Centre of mass in the tip frame (m), `(3,)`.
    #[getter]
    fn com<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.payload.com.as_slice())
    }

    /// Rotational inertia about the centre of mass, tip-frame axes (kg m^2), `(3, 3)`.
    #[getter]
    fn inertia<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_out(
            py,
            (3, 3),
            |r, c| self.payload.inertia[(r, c)],
            None,
            "inertia",
        )
    }

    fn __repr__(&self) -> String {
        let p = &self.payload;
        format!(
            "Payload(mass={:.4} kg, com=[{:.4}, {:.4}, {:.4}] m)",
            p.mass, p.com.x, p.com.y, p.com.z
        )
    }
}

/// The payload at the tip frame of `ident`'s arm from free-motion `data` recorded with it
/// attached (a CSV path or a dict of arrays, as for `identify`; 20 s is enough), fitted on
/// top of `ident` (what it does not explain is the payload's torque) and physically
/// consistent. The data are conditioned as `ident`'s were (`summary["input_filter_hz"]`;
/// `input_filter_hz` overrides it), the whole recording, and the rows from `from_s` seconds
/// after its start are fitted (leave out a start the models do not describe: the arm
/// settling under the new load).
#[pyfunction]
#[pyo3(signature = (data, ident, input_filter_hz=None, from_s=0.0))]
pub fn identify_payload(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    ident: &Bound<'_, PyIdentification>,
    input_filter_hz: Option<f64>,
    from_s: f64,
) -> PyResult<PyPayload> {
    let ident = ident.get();
    let base = ident.identification.clone();
    let filter_hz = input_filter_hz.unwrap_or(base.summary.input_filter_hz);
    if !(filter_hz.is_finite() && filter_hz >= 0.0) {
        return Err(value_error(format!(
            "`input_filter_hz` is {filter_hz}: a cut-off in Hz >= 0 (0: the signals as recorded)"
        )));
    }
    if !(from_s.is_finite() && from_s >= 0.0) {
        return Err(value_error(format!(
            "`from_s` is {from_s}: seconds from the recording's start, >= 0"
        )));
    }
    let skip = rows_before(data, &ident.urdf, from_s)?;
    let columns = conditioned_columns(py, data, "data", &ident.urdf, filter_hz)?;
    let samples = columns.samples();
    if skip >= samples.len() {
        return Err(value_error(format!(
            "`from_s` {from_s} leaves no sample of `data`"
        )));
    }
    let samples = samples.slice(skip, samples.len());
    let payload = py
        .detach(|| rust_identify_payload(&base, &samples))
        .map_err(|e| value_error(e.to_string()))?;
    Ok(PyPayload { payload })
}

/// The rows of `data` less than `from_s` seconds after its first.
fn rows_before(
    data: &Bound<'_, PyAny>,
    model: &admittance_dynamics::Model,
    from_s: f64,
) -> PyResult<usize> {
    if from_s == 0.0 {
        return Ok(0);
    }
    let joints: Vec<String> = model.joint_names().map(String::from).collect();
    let t = match crate::free_motion::data_arg(data, "data", model.nq(), Some(&joints))? {
        crate::free_motion::DataArg::Csv(path) => {
            admittance_scenario::FreeMotionData::load(&path)
                .map_err(crate::convert::free_motion_error)?
                .t
        }
        crate::free_motion::DataArg::Arrays(d) => d.t,
    };
    let start = t.first().copied().unwrap_or(0.0);
    Ok(t.iter().take_while(|x| **x < start + from_s).count())
}
