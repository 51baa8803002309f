//! Step 6, assembly: the chain's moving joints with the fixed joints between them folded
//! into their placements, the bodies from folding, the final checks, the [`Model`].

use super::chain::Chain;
use super::fold::Folder;
use super::joint::{chain_joint, ChainJoint};
use super::mount::mount;
use super::tree::Tree;
use super::xml::Ctx;
use super::UrdfOptions;
use crate::error::UrdfError;
use crate::model::{Joint, JointKind, Model};
use crate::spatial::Transform;

/// Builds the model of `chain`.
pub(super) fn assemble(
    ctx: &Ctx,
    tree: &Tree,
    chain: &Chain,
    options: &UrdfOptions,
) -> Result<Model, UrdfError> {
    let read: Vec<ChainJoint> = chain
        .path
        .iter()
        .map(|&j| chain_joint(ctx, &tree.joints[j]))
        .collect::<Result<_, _>>()?;
    let mut joints = Vec::new();
    let mut moving_path_joints = Vec::new();
    let mut pending = Transform::identity();
    for (&j, cj) in chain.path.iter().zip(&read) {
        let Some(kind) = cj.kind else {
            pending = pending.compose(&cj.origin);
            continue;
        };
        joints.push(Joint {
            name: tree.joints[j].name.to_string(),
            kind,
            axis: cj.axis,
            placement: pending.compose(&cj.origin),
            limits: cj.limits,
            damping: cj.damping,
            friction: cj.friction,
            child_link: tree.links[tree.joints[j].child].name.to_string(),
        });
        moving_path_joints.push(j);
        pending = Transform::identity();
    }
    let (base_name, tip_name) = (tree.links[chain.base].name, tree.links[chain.tip].name);
    if joints.is_empty() {
        return Err(ctx.err(
            None,
            format!("chain '{base_name}' -> '{tip_name}'"),
            "has no moving joint",
        ));
    }

    let mut folder = Folder::new(ctx, tree, chain, options, joints.len())?;
    folder.attach(chain.base, Transform::identity(), None)?;
    let mut body: Option<usize> = None;
    let mut placement = Transform::identity();
    for (&j, cj) in chain.path.iter().zip(&read) {
        if cj.kind.is_some() {
            body = Some(body.map_or(0, |b| b + 1));
            placement = Transform::identity();
        } else {
            placement = placement.compose(&cj.origin);
        }
        folder.attach(tree.joints[j].child, placement, body)?;
    }
    let mount = mount(ctx, tree, chain, options)?;
    let folded = folder.finish(options, &mount.above_base)?;

    // The last body must resist motion about (along) its own axis, or the forward
    // dynamics are singular whatever the state.
    let last = joints.len() - 1;
    let (lj, lb) = (&joints[last], &folded.bodies[last]);
    let resisting = match lj.kind {
        JointKind::Prismatic => lb.mass,
        _ => lj.axis.dot(&(lb.rotational * lj.axis)),
    };
    // Also rejects NaN.
    if resisting.is_nan() || resisting <= 0.0 {
        return Err(ctx.err(
            Some(tree.joints[moving_path_joints[last]].node),
            format!("joint '{}'", lj.name),
            "moves no mass or inertia: the links after it need an <inertial>",
        ));
    }

    let tip_frame = folded
        .frames
        .iter()
        .position(|f| f.name == tip_name)
        .unwrap_or(folded.frames.len() - 1);
    Ok(Model {
        robot_name: ctx
            .doc
            .root_element()
            .attribute("name")
            .unwrap_or("")
            .to_string(),
        source: ctx.file.to_string(),
        base_link: base_name.to_string(),
        joints,
        bodies: folded.bodies,
        frames: folded.frames,
        tip_frame,
        gravity: mount.gravity,
        link_masses: folded.link_masses,
        excluded_links: folded.excluded_links,
        warnings: folded.warnings,
        locked_branches: folded.locked,
        dropped_branches: folded.dropped,
        lock_options: options.lock.clone(),
    })
}
