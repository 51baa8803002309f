//! Step 4, validation of the inertial parameters the model uses.
//!
//! For a link whose mass moves with the chain (a chain link, a link rigidly attached to
//! one, a link of a locked branch):
//! * unreadable or non-finite numbers and negative masses are errors;
//! * `<mass value="0"/>` with an all-zero inertia is a massless link (as no `<inertial>`);
//!   a positive mass with a zero inertia is a point mass;
//! * an inertia no rigid body can have (principal moments negative or breaking the
//!   triangle inequality beyond a relative tolerance, or a zero mass with a nonzero
//!   inertia) is kept as written, as Pinocchio and MuJoCo do, with a warning; `strict`
//!   loading makes it an error.
//!
//! Links whose mass never moves (the base and what is fixed to it) and links left out of
//! the model are not validated: only their mass is read, leniently, for summaries.

use nalgebra::{Matrix3, SymmetricEigen};
use roxmltree::Node;

use super::xml::{child, parse_finite, Ctx};
use crate::error::{LoadWarning, UrdfError};
use crate::spatial::Inertia;

/// Relative tolerance (to the largest principal moment) of the positive semi-definiteness
/// and triangle-inequality checks: URDF numbers are often printed with six digits.
const RELATIVE_TOLERANCE: f64 = 1e-6;

/// A validated `<inertial>`: the spatial inertia in the link frame and the mass.
#[derive(Clone, Copy)]
pub(super) struct LinkInertia {
    pub(super) inertia: Inertia,
    pub(super) mass: f64,
}

/// Reads and checks the `<inertial>` of a link whose mass moves. `None` for a massless link.
/// Physically impossible values give a warning (pushed to `warnings`), or an error when
/// `strict`.
pub(super) fn moving_inertial(
    ctx: &Ctx,
    link: Node,
    name: &str,
    strict: bool,
    warnings: &mut Vec<LoadWarning>,
) -> Result<Option<LinkInertia>, UrdfError> {
    let Some(inertial) = child(link, "inertial") else {
        return Ok(None);
    };
    let el = format!("link '{name}' <inertial>");
    let origin = ctx.origin(inertial, &el)?;
    let mass_node =
        child(inertial, "mass").ok_or_else(|| ctx.err(Some(inertial), &el, "missing <mass>"))?;
    let mass = ctx.required_number(mass_node, &format!("{el} <mass>"), "value")?;
    if mass < 0.0 {
        return Err(ctx.err(
            Some(mass_node),
            format!("{el} <mass>"),
            format!("mass {mass} is negative"),
        ));
    }
    let inertia_node = child(inertial, "inertia")
        .ok_or_else(|| ctx.err(Some(inertial), &el, "missing <inertia>"))?;
    let iel = format!("{el} <inertia>");
    let mut v = [0.0; 6];
    for (k, attr) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
        .iter()
        .enumerate()
    {
        v[k] = ctx.required_number(inertia_node, &iel, attr)?;
    }
    let tensor = Matrix3::new(v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5]);
    if mass == 0.0 && tensor.iter().all(|&x| x == 0.0) {
        return Ok(None);
    }
    if let Some(problem) = physical_problem(mass, &tensor) {
        let finding = ctx.err(Some(inertia_node), &iel, problem);
        if strict {
            return Err(UrdfError {
                problem: format!("{} (strict loading)", finding.problem),
                ..finding
            });
        }
        warnings.push(LoadWarning {
            problem: format!("{}; loaded as written", finding.problem),
            ..finding.into()
        });
    }
    // The tensor is given in the inertial frame: rotate it into the link frame.
    let r = origin.rotation;
    let about_com = r * tensor * r.transpose();
    Ok(Some(LinkInertia {
        inertia: Inertia::from_com(mass, origin.translation, about_com),
        mass,
    }))
}

/// Why no rigid body has this mass and rotational inertia about its centre of mass, if so.
fn physical_problem(mass: f64, tensor: &Matrix3<f64>) -> Option<String> {
    let eig = SymmetricEigen::new(*tensor);
    let mut p = [eig.eigenvalues[0], eig.eigenvalues[1], eig.eigenvalues[2]];
    p.sort_by(f64::total_cmp);
    let slack = RELATIVE_TOLERANCE * p[2].abs().max(p[0].abs());
    if mass == 0.0 {
        return Some("a zero mass with a nonzero inertia (no rigid body has them)".into());
    }
    if p[0] < -slack {
        return Some(format!(
            "inertia tensor is not positive semi-definite (principal moments {:.6e}, {:.6e}, \
             {:.6e}; no rigid body has them)",
            p[0], p[1], p[2]
        ));
    }
    if p[0] + p[1] < p[2] - slack {
        return Some(format!(
            "principal moments {:.6e}, {:.6e}, {:.6e} break the triangle inequality \
             (no rigid body has them)",
            p[0], p[1], p[2]
        ));
    }
    None
}

/// The mass of a link that is not validated (fixed to the base, or left out): the value
/// when it reads as a finite non-negative number, else 0.
pub(super) fn lenient_mass(link: Node) -> f64 {
    child(link, "inertial")
        .and_then(|i| child(i, "mass"))
        .and_then(|m| m.attribute("value"))
        .and_then(|v| parse_finite(v.trim()).ok())
        .filter(|&m| m >= 0.0)
        .unwrap_or(0.0)
}
