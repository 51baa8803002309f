//! The `Payload` class: a rigid payload at the tip, as `identify_payload` returns it
//! (`identify_payload.rs`) or a user states it (issue 30's contract; docs/python.md,
//! "Identification"). `Identification.with_payload` lives with the identification's methods.

use admittance_dynamics::Payload;
use nalgebra::{Matrix3, Vector3};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::convert::{matrix_out, value_error, vector};

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
