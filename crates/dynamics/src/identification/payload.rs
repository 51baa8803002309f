//! The payload: a rigid body fixed at the tip frame (a tool, a gripper, a carried part),
//! identified from a short recording with it attached, on top of an existing
//! identification (docs/method.md section 1, eq. 1: the torque stays linear in the added
//! body's 10 inertial parameters).
//!
//! What the identification does not explain, `tau - predict(q, q', q'')`, is the payload's
//! torque: the columns of the tip body's inertial parameters in the joint-torque regressor,
//! `Y_j(q, q', q'')`, times the payload's parameters in that body's joint frame. Those are a
//! linear function of its parameters in the tip frame (the tip frame's fixed placement on
//! the body: [`Inertia::transformed`]), so the regressor of the tip-frame parameters is
//! `Y_j T` with a constant 10 x 10 `T`. The fit is least squares over physically possible
//! bodies (the payload's pseudo-inertia positive definite: a convex set, the barrier method
//! of `constrained.rs`); when the plain least-squares answer already is one, it is that
//! answer.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};

use super::acceleration_gain::AccelerationGains;
use super::consistency::{margin, project};
use super::constrained::fit_possible_body;
use super::{Identification, Samples};
use crate::algorithms::regressor::{joint_torque_regressor, PARAMETERS_PER_BODY};
use crate::data::Data;
use crate::error::DynamicsError;
use crate::model::{Model, Payload};
use crate::spatial::Inertia;

type Matrix10 = SMatrix<f64, PARAMETERS_PER_BODY, PARAMETERS_PER_BODY>;
type Vector10 = SVector<f64, PARAMETERS_PER_BODY>;

/// Ridge toward no payload, relative to each parameter's column scale: only directions the
/// motion does not excite at all feel it.
const RELATIVE_RIDGE: f64 = 1e-12;
/// Fewest samples a payload fit takes.
const MIN_SAMPLES: usize = 20;

/// The payload at the tip frame of `ident`'s arm, from `samples` recorded with it attached:
/// mass (kg), centre of mass (m, tip frame) and rotational inertia about the centre of mass
/// (kg m^2, tip-frame axes), physically consistent. The samples are conditioned as the
/// identification's were (`ident.summary.input_filter_hz`); 20 s of motion that moves the
/// wrist in every direction is enough.
pub fn identify_payload(
    ident: &Identification,
    samples: &Samples,
) -> Result<Payload, DynamicsError> {
    let model = &ident.model;
    samples.check("payload data", model.nq())?;
    if samples.len() < MIN_SAMPLES {
        return Err(DynamicsError::InvalidArgument(format!(
            "payload data: {} samples, a payload fit takes at least {MIN_SAMPLES}",
            samples.len()
        )));
    }
    let (r, z) = with_ridge(triangular_system(ident, samples)?);
    let plain = r.solve_upper_triangular(&z).ok_or_else(|| {
        DynamicsError::InvalidArgument(
            "payload data: the motion does not move the tip (no parameter of the payload is excited)"
                .into(),
        )
    })?;
    let plain: [f64; PARAMETERS_PER_BODY] = plain.into();
    let consistent =
        crate::identification::is_physically_consistent(&Inertia::from_parameters(&plain));
    let body = if consistent {
        plain
    } else {
        constrained_fit(&r, &z, &plain)
    };
    let body = Inertia::from_parameters(&body);
    Ok(Payload {
        mass: body.mass,
        com: body.com(),
        inertia: body.inertia_about_com(),
    })
}

/// Rows of samples stacked per QR update (bounds the memory at any recording length).
const BLOCK: usize = 256;

/// The least-squares problem in the payload's tip-frame parameters as `||R pi - z||`
/// (`R` upper triangular): the QR factor of the stacked `[Y_j T | tau - predict]`, updated
/// block by block, so that its conditioning is the regressor's, not its square.
fn triangular_system(
    ident: &Identification,
    samples: &Samples,
) -> Result<(Matrix10, Vector10), DynamicsError> {
    let model = &ident.model;
    let n = model.nq();
    let (body, to_body) = tip_body(model)?;
    let mut data = Data::new(model);
    let mut predicted = vec![0.0; n];
    let mut gains = AccelerationGains::new(&ident.summary, None);
    let mut g = vec![0.0; n];
    let width = PARAMETERS_PER_BODY + 1;
    let mut stack = DMatrix::<f64>::zeros(width + BLOCK * n, width);
    let mut rows = width;
    let mut y = DMatrix::<f64>::zeros(n, PARAMETERS_PER_BODY);
    for k in 0..samples.len() {
        let (q, qd, qdd, tau) = samples.row(k);
        gains.update(qdd, &mut g);
        ident.predict_with_gains(&mut data, q, qd, qdd, &g, &mut predicted)?;
        let full = joint_torque_regressor(model, &mut data, q, qd, qdd)?;
        y.copy_from(&full.columns(PARAMETERS_PER_BODY * body, PARAMETERS_PER_BODY));
        let yt = &y * &to_body;
        for i in 0..n {
            for c in 0..PARAMETERS_PER_BODY {
                stack[(rows + i, c)] = yt[(i, c)];
            }
            stack[(rows + i, PARAMETERS_PER_BODY)] = tau[i] - predicted[i];
        }
        rows += n;
        if rows + n > stack.nrows() || k + 1 == samples.len() {
            let r = stack.rows(0, rows).into_owned().qr().r();
            stack.fill(0.0);
            stack.view_mut((0, 0), (r.nrows(), width)).copy_from(&r);
            rows = width;
        }
    }
    let r = Matrix10::from_fn(|i, j| stack[(i, j)]);
    let z = Vector10::from_fn(|i, _| stack[(i, PARAMETERS_PER_BODY)]);
    Ok((r, z))
}

/// `R`, `z` with a ridge toward no payload appended (rows `sqrt(ridge) * |column|`), and
/// re-triangularised.
fn with_ridge((r, z): (Matrix10, Vector10)) -> (Matrix10, Vector10) {
    let width = PARAMETERS_PER_BODY + 1;
    let mut stack = DMatrix::<f64>::zeros(2 * PARAMETERS_PER_BODY, width);
    for i in 0..PARAMETERS_PER_BODY {
        for j in 0..PARAMETERS_PER_BODY {
            stack[(i, j)] = r[(i, j)];
        }
        stack[(i, PARAMETERS_PER_BODY)] = z[i];
        let column = r.column(i).norm().max(f64::MIN_POSITIVE);
        stack[(PARAMETERS_PER_BODY + i, i)] = RELATIVE_RIDGE.sqrt() * column;
    }
    let out = stack.qr().r();
    (
        Matrix10::from_fn(|i, j| out[(i, j)]),
        Vector10::from_fn(|i, _| out[(i, PARAMETERS_PER_BODY)]),
    )
}

/// The body carrying the tip frame and the map `T` from a payload's parameters in the tip
/// frame to the same body's parameters in that body's joint frame (linear: the inertia's
/// change of frame is linear in mass, first moment and rotational inertia).
fn tip_body(model: &Model) -> Result<(usize, DMatrix<f64>), DynamicsError> {
    let tip = model.tip();
    let Some(body) = tip.parent_joint else {
        return Err(DynamicsError::InvalidArgument(format!(
            "the tip frame '{}' is fixed to the base: a payload there moves nothing",
            tip.name
        )));
    };
    let mut t = DMatrix::zeros(PARAMETERS_PER_BODY, PARAMETERS_PER_BODY);
    for k in 0..PARAMETERS_PER_BODY {
        let mut unit = [0.0; PARAMETERS_PER_BODY];
        unit[k] = 1.0;
        let moved = Inertia::from_parameters(&unit)
            .transformed(&tip.placement)
            .to_parameters();
        t.column_mut(k).copy_from_slice(&moved);
    }
    Ok((body, t))
}

/// Least squares `||R pi - z||^2` over physically possible bodies (the barrier method of
/// `constrained.rs`), started near the plain answer.
fn constrained_fit(
    r: &Matrix10,
    z: &Vector10,
    plain: &[f64; PARAMETERS_PER_BODY],
) -> [f64; PARAMETERS_PER_BODY] {
    let start = project(plain, 0.0).unwrap_or_else(|| fallback_start(r, z));
    let margin = margin(&start);
    let (r_dyn, z_dyn) = (
        DMatrix::from_column_slice(PARAMETERS_PER_BODY, PARAMETERS_PER_BODY, r.as_slice()),
        nalgebra::DVector::from_column_slice(z.as_slice()),
    );
    fit_possible_body(&r_dyn, &z_dyn, &start, margin)
        .or_else(|| fit_possible_body(&r_dyn, &z_dyn, &fallback_start(r, z), margin))
        .unwrap_or(start)
}

/// A start when the plain answer has no positive mass distribution: a compact body of the
/// mass the data give for a point at the tip frame (at least 10 g), 2 cm in radius.
fn fallback_start(a: &Matrix10, b: &Vector10) -> [f64; PARAMETERS_PER_BODY] {
    let mass = if a[(0, 0)] > 0.0 {
        b[0] / a[(0, 0)]
    } else {
        0.0
    };
    let mass = mass.max(0.01);
    let radius: f64 = 0.02;
    Inertia::from_com(
        mass,
        Vector3::zeros(),
        Matrix3::identity() * (0.4 * mass * radius * radius),
    )
    .to_parameters()
}

impl Identification {
    /// This identification carrying `payload` rigidly at the tip frame: its spatial inertia
    /// added to the body of the tip frame's joint ([`Model::with_payload`]); joint terms and
    /// summary kept. What every consumer of an identification takes once the tool is on.
    pub fn with_payload(&self, payload: &Payload) -> Result<Identification, DynamicsError> {
        Ok(Identification {
            model: self.model.with_payload(payload)?,
            joint_terms: self.joint_terms.clone(),
            summary: self.summary.clone(),
        })
    }

    /// Per joint, the rms of `tau - predict` over `samples` (N m): the false torque this
    /// model leaves on free motion.
    pub fn false_torque_rms(&self, samples: &Samples) -> Result<Vec<f64>, DynamicsError> {
        samples.check("samples", self.model.nq())?;
        Ok(self.joint_errors(samples)?.rms)
    }
}
