//! Reading the joints the model uses: a chain joint in full (type, origin, axis, limits,
//! dynamics), and the placement of a joint off the chain at the position it is locked at.

use nalgebra::Vector3;

use super::tree::{JointType, TreeJoint};
use super::xml::{child, Ctx};
use crate::error::UrdfError;
use crate::model::{JointKind, JointLimits};
use crate::spatial::{axis_angle, Transform};

/// A joint of the chain, read and checked.
pub(super) struct ChainJoint {
    /// `None` for a fixed joint.
    pub(super) kind: Option<JointKind>,
    pub(super) origin: Transform,
    pub(super) axis: Vector3<f64>,
    pub(super) limits: JointLimits,
    pub(super) damping: f64,
    pub(super) friction: f64,
}

/// The unit `<axis>` of a moving joint (default x).
fn read_axis(ctx: &Ctx, joint: &TreeJoint, element: &str) -> Result<Vector3<f64>, UrdfError> {
    let Some(a) = child(joint.node, "axis") else {
        return Ok(Vector3::x());
    };
    let el = format!("{element} <axis>");
    match ctx.vector3(a, &el, "xyz")? {
        None => Ok(Vector3::x()),
        Some(v) if v.norm() < 1e-12 => Err(ctx.err(Some(a), el, "axis has zero length")),
        Some(v) => Ok(v / v.norm()),
    }
}

/// Reads a joint of the chain (base to tip) with every check.
pub(super) fn chain_joint(ctx: &Ctx, joint: &TreeJoint) -> Result<ChainJoint, UrdfError> {
    let element = format!("joint '{}'", joint.name);
    let node = joint.node;
    let kind = match joint.kind {
        JointType::Fixed => None,
        JointType::Revolute => Some(JointKind::Revolute),
        JointType::Continuous => Some(JointKind::Continuous),
        JointType::Prismatic => Some(JointKind::Prismatic),
        JointType::Floating | JointType::Planar => {
            return Err(ctx.err(
                Some(node),
                &element,
                format!(
                    "joint type '{}' on the chain is not supported: only revolute, continuous, \
                     prismatic and fixed joints make a serial arm (choose a base below it)",
                    joint.type_name
                ),
            ))
        }
        JointType::Unknown => return Err(unknown_type(ctx, joint)),
    };
    let origin = ctx.origin(node, &element)?;
    let axis = match kind {
        Some(_) => read_axis(ctx, joint, &element)?,
        None => Vector3::x(),
    };
    let limits = read_limits(ctx, joint, kind, &element)?;
    let (mut damping, mut friction) = (0.0, 0.0);
    if let Some(d) = child(node, "dynamics") {
        let el = format!("{element} <dynamics>");
        damping = ctx.number(d, &el, "damping")?.unwrap_or(0.0);
        friction = ctx.number(d, &el, "friction")?.unwrap_or(0.0);
        if damping < 0.0 || friction < 0.0 {
            return Err(ctx.err(Some(d), el, "damping and friction must not be negative"));
        }
    }
    Ok(ChainJoint {
        kind,
        origin,
        axis,
        limits,
        damping,
        friction,
    })
}

fn read_limits(
    ctx: &Ctx,
    joint: &TreeJoint,
    kind: Option<JointKind>,
    element: &str,
) -> Result<JointLimits, UrdfError> {
    let mut limits = JointLimits::default();
    let bounded = matches!(kind, Some(JointKind::Revolute | JointKind::Prismatic));
    let Some(l) = child(joint.node, "limit") else {
        if bounded {
            return Err(ctx.err(
                Some(joint.node),
                element,
                format!(
                    "a {} joint needs <limit lower=.. upper=.. effort=.. velocity=..>",
                    joint.type_name
                ),
            ));
        }
        return Ok(limits);
    };
    let el = format!("{element} <limit>");
    if let Some(v) = ctx.number(l, &el, "effort")? {
        limits.effort = v;
    }
    if let Some(v) = ctx.number(l, &el, "velocity")? {
        limits.velocity = v;
    }
    if bounded {
        limits.lower = ctx.number(l, &el, "lower")?.unwrap_or(0.0);
        limits.upper = ctx.number(l, &el, "upper")?.unwrap_or(0.0);
        if limits.lower > limits.upper {
            return Err(ctx.err(
                Some(l),
                el,
                format!(
                    "lower limit {} is above upper limit {}",
                    limits.lower, limits.upper
                ),
            ));
        }
    }
    if limits.effort < 0.0 || limits.velocity < 0.0 {
        return Err(ctx.err(
            Some(l),
            el,
            "effort and velocity limits must not be negative",
        ));
    }
    Ok(limits)
}

fn unknown_type(ctx: &Ctx, joint: &TreeJoint) -> UrdfError {
    ctx.err(
        Some(joint.node),
        format!("joint '{}'", joint.name),
        format!(
            "unknown joint type '{}' (expected revolute, continuous, prismatic, fixed, floating \
             or planar)",
            joint.type_name
        ),
    )
}

/// Placement of a joint off the chain in its parent link's frame: its origin, then its
/// motion at `value` (floating and planar joints are held at the identity).
pub(super) fn placement_at(
    ctx: &Ctx,
    joint: &TreeJoint,
    value: f64,
) -> Result<Transform, UrdfError> {
    let element = format!("joint '{}'", joint.name);
    let origin = ctx.origin(joint.node, &element)?;
    let motion = match joint.kind {
        JointType::Fixed | JointType::Floating | JointType::Planar => return Ok(origin),
        JointType::Unknown => return Err(unknown_type(ctx, joint)),
        JointType::Revolute | JointType::Continuous => Transform::new(
            axis_angle(&read_axis(ctx, joint, &element)?, value),
            Vector3::zeros(),
        ),
        JointType::Prismatic => Transform::new(
            nalgebra::Matrix3::identity(),
            read_axis(ctx, joint, &element)? * value,
        ),
    };
    Ok(origin.compose(&motion))
}

/// The `<limit lower upper>` of a joint off the chain, when both read cleanly (used only
/// to warn about a lock position outside them).
pub(super) fn position_range(joint: &TreeJoint) -> Option<(f64, f64)> {
    if !matches!(joint.kind, JointType::Revolute | JointType::Prismatic) {
        return None;
    }
    let l = child(joint.node, "limit")?;
    let read = |a: &str| l.attribute(a)?.trim().parse::<f64>().ok();
    Some((read("lower")?, read("upper")?))
}
