//! Step 3, chain selection: the base link, the tip link and the joints between them.
//!
//! The default tip is the arm's hand, found from the tree alone:
//!
//! 1. *End-effector joints* are set aside: a moving joint is one when it is a mimic joint,
//!    when a mimic joint follows it, or when its name contains `finger`, `gripper`, `jaw`,
//!    `thumb`, `knuckle` or `hand` (any case). Their subtrees (fingers, grippers, hands)
//!    are not part of the search. When that leaves no moving joint below the base, no
//!    joint is set aside.
//! 2. Depth counts the moving joints from the base. The *hand joint* is the moving joint
//!    of greatest depth; when several share the greatest depth (two arms, four legs) the
//!    tip is ambiguous: an error lists the candidate tips.
//! 3. The tip is the link at the end of the hand joint's body: of the links rigidly
//!    attached to the hand joint's child link (through fixed joints), the one behind the
//!    most fixed joints (a TCP frame behind a flange, say); when several tie, the hand
//!    joint's child link itself (all of them are the same body).
//!
//! On a serial chain without end-effector joints this is the single leaf, as before.

use super::tree::{list, Tree};
use super::xml::Ctx;
use super::UrdfOptions;
use crate::error::UrdfError;

/// The selected chain.
pub(super) struct Chain {
    pub(super) base: usize,
    pub(super) tip: usize,
    /// Joints from the base to the tip, in order.
    pub(super) path: Vec<usize>,
    /// Per joint of the file: whether it is on `path`.
    pub(super) on_path: Vec<bool>,
}

const END_EFFECTOR_WORDS: [&str; 6] = ["finger", "gripper", "jaw", "thumb", "knuckle", "hand"];

/// Selects base, tip and path; checks that no mimic joint is on the path.
pub(super) fn select(ctx: &Ctx, tree: &Tree, options: &UrdfOptions) -> Result<Chain, UrdfError> {
    let find = |what: &str, name: &str| {
        tree.link_index.get(name).copied().ok_or_else(|| {
            ctx.err(
                None,
                format!("{what} link '{name}'"),
                "no link of that name in the file",
            )
        })
    };
    let base = match &options.base {
        Some(name) => find("base", name)?,
        None => tree.root,
    };
    let tip = match &options.tip {
        Some(name) => find("tip", name)?,
        None => default_tip(ctx, tree, base)?,
    };
    let path = tree.path(base, tip).ok_or_else(|| {
        ctx.err(
            None,
            format!("tip link '{}'", tree.links[tip].name),
            format!("not below the base link '{}'", tree.links[base].name),
        )
    })?;
    let mut on_path = vec![false; tree.joints.len()];
    for &j in &path {
        on_path[j] = true;
        let joint = &tree.joints[j];
        if let (Some(mimic), true) = (joint.mimic, joint.moves()) {
            return Err(ctx.err(
                Some(mimic),
                format!("joint '{}' <mimic>", joint.name),
                format!(
                    "a mimic joint (it follows joint '{}') is on the chain '{}' -> '{}': it cannot \
                     be a coordinate of its own; choose a tip before it",
                    joint.mimic_target().unwrap_or("?"),
                    tree.links[base].name,
                    tree.links[tip].name
                ),
            ));
        }
    }
    Ok(Chain {
        base,
        tip,
        path,
        on_path,
    })
}

/// Step 1 of the rule: the joints set aside.
fn end_effector_joints(tree: &Tree) -> Vec<bool> {
    let mut set_aside: Vec<bool> = tree
        .joints
        .iter()
        .map(|j| {
            let name = j.name.to_ascii_lowercase();
            j.mimic.is_some() || END_EFFECTOR_WORDS.iter().any(|w| name.contains(w))
        })
        .collect();
    for j in &tree.joints {
        if let Some(&followed) = j.mimic_target().and_then(|t| tree.joint_index.get(t)) {
            set_aside[followed] = true;
        }
    }
    set_aside
}

/// Step 2: the moving joints of greatest depth below `base`, skipping `set_aside` subtrees.
fn deepest_moving_joints(tree: &Tree, base: usize, set_aside: Option<&[bool]>) -> Vec<usize> {
    let mut best = 0;
    let mut deepest = Vec::new();
    let mut stack = vec![(base, 0usize)];
    while let Some((link, depth)) = stack.pop() {
        for &j in tree.children[link].iter().rev() {
            let joint = &tree.joints[j];
            if !joint.moves() {
                stack.push((joint.child, depth));
                continue;
            }
            if set_aside.is_some_and(|s| s[j]) {
                continue;
            }
            let d = depth + 1;
            if d > best {
                best = d;
                deepest.clear();
            }
            if d == best {
                deepest.push(j);
            }
            stack.push((joint.child, d));
        }
    }
    deepest
}

/// Step 3: the end of the body that `joint` moves.
fn end_of_body(tree: &Tree, joint: usize) -> usize {
    let start = tree.joints[joint].child;
    let (mut best, mut best_depth, mut tie) = (start, 0usize, false);
    let mut stack = vec![(start, 0usize)];
    while let Some((link, depth)) = stack.pop() {
        for &j in &tree.children[link] {
            let joint = &tree.joints[j];
            if joint.moves() {
                continue;
            }
            let d = depth + 1;
            if d > best_depth {
                (best, best_depth, tie) = (joint.child, d, false);
            } else if d == best_depth {
                tie = true;
            }
            stack.push((joint.child, d));
        }
    }
    if tie {
        start
    } else {
        best
    }
}

fn default_tip(ctx: &Ctx, tree: &Tree, base: usize) -> Result<usize, UrdfError> {
    let set_aside = end_effector_joints(tree);
    let mut hands = deepest_moving_joints(tree, base, Some(&set_aside));
    if hands.is_empty() {
        hands = deepest_moving_joints(tree, base, None);
    }
    let base_name = tree.links[base].name;
    match hands.as_slice() {
        [] => Err(ctx.err(
            None,
            "tip link",
            format!("no moving joint below the base link '{base_name}': nothing to model"),
        )),
        [hand] => Ok(end_of_body(tree, *hand)),
        several => {
            let candidates: Vec<String> = several
                .iter()
                .map(|&j| {
                    format!(
                        "{} (joint {})",
                        tree.links[end_of_body(tree, j)].name,
                        tree.joints[j].name
                    )
                })
                .collect();
            let names: Vec<&str> = candidates.iter().map(String::as_str).collect();
            Err(ctx.err(
                None,
                "tip link",
                format!(
                    "ambiguous: {} branches below '{base_name}' end at the same depth: {}; \
                     name one with --tip",
                    several.len(),
                    list(&names)
                ),
            ))
        }
    }
}
