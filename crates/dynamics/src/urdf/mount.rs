//! Step 5b, the mount: how the chain's base link sits in the URDF's root link (the world),
//! through the joints above it, and so which way gravity points in the base's axes. A
//! URDF names "up" once, as the root link's z; an arm taken from a larger robot (a
//! humanoid's shoulder, a robot hung from a ceiling in a workcell's file) has a base link
//! turned against it.

use nalgebra::Vector3;

use super::chain::Chain;
use super::joint::placement_at;
use super::tree::Tree;
use super::xml::Ctx;
use super::UrdfOptions;
use crate::error::UrdfError;
use crate::spatial::Transform;

/// Standard gravity along the root link's -z (m/s^2).
const STANDARD_GRAVITY: f64 = 9.81;

/// The joints between the root link and the base link, and the gravity the base sees.
pub(super) struct Mount {
    /// Joints from the root link down to the base link.
    pub(super) above_base: Vec<usize>,
    /// Gravity in the base link's axes: the root's `(0, 0, -9.81)` turned by the joints
    /// above the base (moving ones at their lock position, 0 unless the options give one).
    pub(super) gravity: Vector3<f64>,
}

/// The base link's mount in the root link.
pub(super) fn mount(
    ctx: &Ctx,
    tree: &Tree,
    chain: &Chain,
    options: &UrdfOptions,
) -> Result<Mount, UrdfError> {
    let mut above_base = Vec::new();
    let mut link = chain.base;
    while let Some(j) = tree.parent_joint[link] {
        above_base.push(j);
        link = tree.joints[j].parent;
    }
    above_base.reverse();
    let given = |name: &str| {
        options
            .lock
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    };
    let mut pose = Transform::identity();
    for &j in &above_base {
        let joint = &tree.joints[j];
        // As a locked branch's joints are held (fold.rs): the position given, else a mimic
        // joint follows its reference's given position, else 0.
        let mut value = given(joint.name);
        if let (None, Some(mimic)) = (value, joint.mimic) {
            if let Some(reference) = joint.mimic_target().and_then(given) {
                let element = format!("joint '{}' <mimic>", joint.name);
                let multiplier = ctx.number(mimic, &element, "multiplier")?.unwrap_or(1.0);
                let offset = ctx.number(mimic, &element, "offset")?.unwrap_or(0.0);
                value = Some(multiplier * reference + offset);
            }
        }
        pose = pose.compose(&placement_at(ctx, joint, value.unwrap_or(0.0))?);
    }
    let world = Vector3::new(0.0, 0.0, -STANDARD_GRAVITY);
    // A signed zero from a turn about the vertical (sin 0 = 0 with a sign) would change no
    // value, but `+0` keeps an upright base's gravity the same bits as the root's.
    let gravity = (pose.rotation.transpose() * world).map(|g| if g == 0.0 { 0.0 } else { g });
    Ok(Mount {
        above_base,
        gravity,
    })
}
